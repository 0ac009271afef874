// SPDX-License-Identifier: Apache-2.0
#include "ido/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "ido/core/error.h"

namespace ido {
namespace {

void check_quantile(double q) {
  if (!(q >= 0.0 && q <= 1.0)) throw InvalidInput("percentile: the quantile must lie in [0, 1], got " + std::to_string(q));
}

// Type-7 quantile of an already sorted, non-empty sample.
double sorted_quantile(const std::vector<double>& s, double q) {
  const double pos = q * double(s.size() - 1);
  const auto i = std::size_t(pos);
  const double f = pos - double(i);
  return i + 1 < s.size() ? s[i] + f * (s[i + 1] - s[i]) : s[i];
}

}  // namespace

double percentile(std::vector<double> values, double q) {
  check_quantile(q);
  if (values.empty()) throw InvalidInput("percentile of an empty sample");
  // Two selections instead of a sort: the order statistic at floor(rank), then the smallest
  // value above it.
  const double pos = q * double(values.size() - 1);
  const auto i = std::size_t(pos);
  const double f = pos - double(i);
  const auto it = values.begin() + std::ptrdiff_t(i);
  std::nth_element(values.begin(), it, values.end());
  const double lo = *it;
  if (f == 0.0 || i + 1 >= values.size()) return lo;
  const double hi = *std::min_element(it + 1, values.end());
  return lo + f * (hi - lo);
}

std::vector<double> percentiles(std::vector<double> values, const std::vector<double>& qs) {
  for (double q : qs) check_quantile(q);
  if (values.empty()) throw InvalidInput("percentile of an empty sample");
  std::sort(values.begin(), values.end());
  std::vector<double> out;
  out.reserve(qs.size());
  for (double q : qs) out.push_back(sorted_quantile(values, q));
  return out;
}

double median(std::vector<double> values) { return percentile(std::move(values), 0.5); }

}  // namespace ido

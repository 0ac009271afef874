// SPDX-License-Identifier: Apache-2.0
#include "ido/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "ido/core/error.h"

namespace ido {
namespace {

void check_quantile(double q) {
  if (!(q >= 0.0 && q <= 1.0)) throw InvalidInput("percentile: the quantile must lie in [0, 1], got " + std::to_string(q));
}

}  // namespace

namespace {

template <class T>
std::vector<double> select_quantiles(std::vector<T> values, const std::vector<double>& qs) {
  for (double q : qs) check_quantile(q);
  if (values.empty()) throw InvalidInput("percentile of an empty sample");
  // Ranks in increasing order; each selection works on what lies above the previous one.
  std::vector<std::size_t> order(qs.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return qs[a] < qs[b]; });
  std::vector<double> out(qs.size());
  auto from = values.begin();
  for (std::size_t o : order) {
    const double pos = qs[o] * double(values.size() - 1);
    const auto i = std::size_t(pos);
    const double f = pos - double(i);
    const auto it = values.begin() + std::ptrdiff_t(i);
    if (it >= from) std::nth_element(from, it, values.end());
    from = it;
    const double lo = double(*it);
    out[o] = (f == 0.0 || i + 1 >= values.size()) ? lo : lo + f * (double(*std::min_element(it + 1, values.end())) - lo);
  }
  return out;
}

}  // namespace

std::vector<double> percentiles(std::vector<double> values, const std::vector<double>& qs) {
  return select_quantiles(std::move(values), qs);
}

std::vector<double> percentiles(std::vector<float> values, const std::vector<double>& qs) {
  return select_quantiles(std::move(values), qs);
}

double percentile(std::vector<double> values, double q) { return select_quantiles(std::move(values), {q}).front(); }

double median(std::vector<double> values) { return percentile(std::move(values), 0.5); }

}  // namespace ido

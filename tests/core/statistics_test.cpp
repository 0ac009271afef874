// SPDX-License-Identifier: Apache-2.0
#include "ido/core/statistics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "ido/core/error.h"

namespace ido {
namespace {

TEST(Percentile, InterpolatesBetweenOrderStatisticsAsNumpyDoes) {
  // numpy.percentile([10, 40, 20, 30], [0, 25, 50, 95, 100]) = 10, 17.5, 25, 38.5, 40.
  const std::vector<double> v{10, 40, 20, 30};
  EXPECT_DOUBLE_EQ(percentile(v, 0.0), 10.0);
  EXPECT_DOUBLE_EQ(percentile(v, 0.25), 17.5);
  EXPECT_DOUBLE_EQ(percentile(v, 0.5), 25.0);
  EXPECT_DOUBLE_EQ(percentile(v, 0.95), 38.5);
  EXPECT_DOUBLE_EQ(percentile(v, 1.0), 40.0);
  EXPECT_DOUBLE_EQ(median({3, 1, 2}), 2.0);
  EXPECT_DOUBLE_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(percentile({7}, 0.99), 7.0);
}

TEST(Percentile, SelectionAndSortAgreeAndAreMonotone) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  for (std::size_t n : {2u, 3u, 10u, 101u, 1000u}) {
    std::vector<double> v(n);
    for (double& x : v) x = g(rng);
    const std::vector<double> qs{0.0, 0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99, 0.999, 1.0};
    const std::vector<double> all = percentiles(v, qs);
    for (std::size_t i = 0; i < qs.size(); ++i) {
      EXPECT_DOUBLE_EQ(all[i], percentile(v, qs[i])) << "n " << n << " q " << qs[i];
      if (i > 0) {
        EXPECT_LE(all[i - 1], all[i]);
      }
    }
    const std::vector<float> vf(v.begin(), v.end());
    const std::vector<double> vd(vf.begin(), vf.end());
    EXPECT_EQ(percentiles(vf, qs), percentiles(vd, qs)) << "n " << n;  // the float overload: the same rule
    EXPECT_DOUBLE_EQ(all.front(), *std::min_element(v.begin(), v.end()));
    EXPECT_DOUBLE_EQ(all.back(), *std::max_element(v.begin(), v.end()));
  }
}

TEST(Percentile, RefusesAnEmptySampleAndAQuantileOutsideTheUnitInterval) {
  EXPECT_THROW((void)percentile({}, 0.5), InvalidInput);
  EXPECT_THROW((void)median({}), InvalidInput);
  EXPECT_THROW((void)percentile({1, 2}, 1.5), InvalidInput);
  EXPECT_THROW((void)percentile({1, 2}, -0.1), InvalidInput);
  EXPECT_THROW((void)percentiles(std::vector<double>{1, 2}, {0.5, std::nan("")}), InvalidInput);
}

}  // namespace
}  // namespace ido

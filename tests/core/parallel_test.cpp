// SPDX-License-Identifier: Apache-2.0
// parallel_for_ranges / parallel_for: the sub-ranges cover [0, n) exactly once, in one serial
// call when not threaded or when n is within the grain.
#include "ido/core/parallel.h"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace ido {
namespace {

struct Ranges {
  std::mutex mutex;
  std::vector<std::pair<std::size_t, std::size_t>> seen;
};

// Runs parallel_for_ranges and returns the ranges it called the body with, sorted.
std::vector<std::pair<std::size_t, std::size_t>> ranges_of(std::size_t n, bool threaded, std::size_t grain) {
  Ranges r;
  parallel_for_ranges(
      n,
      [&](std::size_t b, std::size_t e) {
        const std::lock_guard lock(r.mutex);
        r.seen.emplace_back(b, e);
      },
      threaded, grain);
  std::sort(r.seen.begin(), r.seen.end());
  return r.seen;
}

TEST(ParallelFor, RangesTileZeroToNWithoutGapOrOverlap) {
  for (const std::size_t n : {std::size_t(1), std::size_t(255), std::size_t(256), std::size_t(257), std::size_t(1000),
                              std::size_t(100003)}) {
    for (const std::size_t grain : {std::size_t(1), std::size_t(16), std::size_t(256)}) {
      const auto r = ranges_of(n, true, grain);
      ASSERT_FALSE(r.empty());
      EXPECT_EQ(r.front().first, 0U) << n << " " << grain;
      EXPECT_EQ(r.back().second, n) << n << " " << grain;
      for (std::size_t i = 0; i < r.size(); ++i) {
        EXPECT_LT(r[i].first, r[i].second) << "empty range";
        if (i > 0) {
          EXPECT_EQ(r[i].first, r[i - 1].second) << "gap or overlap at " << i;
        }
      }
      // Ranges are split only while longer than the grain, in halves: none is shorter than
      // half the grain (the grain sets the granularity of the work, not a fixed chunk).
      if (n > grain) {
        for (const auto& [b, e] : r) EXPECT_GE(e - b, grain / 2) << n << " " << grain;
      }
    }
  }
}

TEST(ParallelFor, SerialWhenNotThreadedOrWithinTheGrainAndNothingForZero) {
  EXPECT_EQ(ranges_of(100000, false, 1), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 100000}}));
  EXPECT_EQ(ranges_of(256, true, 256), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 256}}));
  EXPECT_EQ(ranges_of(7, true, 8), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 7}}));
  EXPECT_TRUE(ranges_of(0, true, 1).empty());
  EXPECT_TRUE(ranges_of(0, false, 1).empty());
}

TEST(ParallelFor, EveryIndexVisitedExactlyOnce) {
  for (const bool threaded : {true, false}) {
    const std::size_t n = 50000;
    std::vector<std::atomic<int>> hits(n);
    parallel_for(
        n, [&](std::size_t i) { hits[i].fetch_add(1, std::memory_order_relaxed); }, threaded, 64);
    std::size_t wrong = 0;
    for (const auto& h : hits) wrong += h.load() != 1 ? 1U : 0U;
    EXPECT_EQ(wrong, 0U) << (threaded ? "threaded" : "serial");
  }
  // A per-index result equals the serial one (no index is computed twice or skipped).
  std::vector<double> a(12345), b(12345);
  parallel_for(a.size(), [&](std::size_t i) { a[i] = double(i) * 0.5 + 1.0; });
  parallel_for(b.size(), [&](std::size_t i) { b[i] = double(i) * 0.5 + 1.0; }, false);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
#include "ido/core/progress.h"

#include <atomic>
#include <thread>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/core/parallel.h"

namespace ido {

TEST(Progress, ReportsFractionsInOrder) {
  std::vector<double> seen;
  Progress p([&](double f, std::string_view) { seen.push_back(f); });
  for (int i = 0; i <= 4; ++i) report(&p, i / 4.0, "stage");
  ASSERT_EQ(seen.size(), 5u);
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
}

TEST(Progress, CancelFromAnotherThreadStopsWork) {
  Progress p;
  std::thread t([&] { p.cancel(); });
  t.join();
  EXPECT_THROW(p.update(0.5, "x"), Cancelled);
  EXPECT_THROW(check_cancel(&p), Cancelled);
  EXPECT_NO_THROW(check_cancel(nullptr));
}

TEST(Parallel, CoversEveryIndexExactlyOnce) {
  std::vector<std::atomic<int>> hits(100000);
  parallel_for(hits.size(), [&](std::size_t i) { hits[i].fetch_add(1); });
  for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
  std::vector<int> serial(1000, 0);
  parallel_for(serial.size(), [&](std::size_t i) { serial[i]++; }, /*threaded=*/false);
  for (int v : serial) ASSERT_EQ(v, 1);
}

}  // namespace ido

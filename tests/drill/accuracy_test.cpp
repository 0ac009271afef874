// SPDX-License-Identifier: Apache-2.0
// Removed volume against the analytic volume swept by the burr (the required accuracy figure).
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

// Removed volume against the analytic swept volume.
struct SweepResult {
  double error;
  double bound;
  double removed;
};

// budget 0: every position processed at once; otherwise the visit budget per call with the
// default backlog coalescing, and the backlog finished at the end.
SweepResult sweep(bool curved, int depth, std::size_t budget = 0) {
  TetHierarchy h(make_block({24, 24, 16}, 4.0));
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = depth, .max_node_visits = budget});
  const double r = 2.0;
  const double before = h.material_volume();
  double analytic = 0.0, area = 0.0;
  const int steps = 400;
  if (!curved) {
    const Vec3 a(6, 8, 8), b(18, 15, 9);
    for (int i = 0; i <= steps; ++i) eroder.erode(h, a + (b - a) * i / steps, r, 1.0, 0.0);
    const double len = (b - a).norm();
    analytic = kPi * r * r * len + 4.0 / 3.0 * kPi * r * r * r;
    area = 2 * kPi * r * len + 4 * kPi * r * r;
  } else {
    const double radius = 6.0, angle = 2.0;  // arc of a circle (Pappus: area × arc length)
    for (int i = 0; i <= steps; ++i) {
      const double t = angle * i / steps;
      eroder.erode(h, Vec3(12 + radius * std::cos(t), 12 + radius * std::sin(t), 8), r, 1.0, 0.0);
    }
    analytic = kPi * r * r * radius * angle + 4.0 / 3.0 * kPi * r * r * r;
    area = 2 * kPi * r * radius * angle + 4 * kPi * r * r;
  }
  (void)eroder.finish(h);
  const double removed = before - h.material_volume();
  // Leaf diameter: longest edge of a root / 2^depth.
  double diam = 0.0;
  for (std::size_t i = 0; i < h.root_count(); ++i) diam = std::max(diam, h.root_diameter(i));
  return {std::abs(removed - analytic), area * diam / std::ldexp(1.0, depth), removed};
}

TEST(Erosion, RemovedVolumeMatchesSweptVolumeAndConvergesWithDepth) {
  for (const bool curved : {false, true}) {
    std::vector<double> errors;
    for (int depth = 2; depth <= 5; ++depth) {
      const auto s = sweep(curved, depth);
      std::printf("%s depth %d error %.4f mm3 bound %.4f mm3\n", curved ? "curved" : "straight", depth, s.error, s.bound);
      EXPECT_LE(s.error, s.bound) << (curved ? "curved" : "straight") << " depth " << depth;
      errors.push_back(s.error);
    }
    // Error roughly halves per level: over three levels at least a factor 4 (ideal 8).
    EXPECT_LT(errors.back(), errors.front() / 4.0) << (curved ? "curved" : "straight");
  }
}

TEST(Erosion, VisitBudgetKeepsTheRemovedVolumeWithinTheSweptVolumeBound) {
  // A budget far below one position's work (so the backlog is coalesced): once finished,
  // the removed volume still meets the analytic bound, and differs from the unbudgeted run
  // by less than that bound.
  for (const bool curved : {false, true}) {
    for (int depth = 3; depth <= 5; ++depth) {
      const auto full = sweep(curved, depth);
      const auto budgeted = sweep(curved, depth, 500);
      std::printf("%s depth %d removed %.4f (no budget) %.4f (budget 500) mm3, bound %.4f\n", curved ? "curved" : "straight",
                  depth, full.removed, budgeted.removed, budgeted.bound);
      EXPECT_LE(budgeted.error, budgeted.bound) << (curved ? "curved" : "straight") << " depth " << depth;
      EXPECT_LE(std::abs(budgeted.removed - full.removed), full.bound) << (curved ? "curved" : "straight") << " depth " << depth;
    }
  }
}

}  // namespace
}  // namespace ido::drill

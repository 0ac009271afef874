// SPDX-License-Identifier: Apache-2.0
// geometry::Aabb, the one box type: construction from points, growth, containment, distance.
#include "ido/geometry/aabb.h"

#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace ido::geometry {
namespace {

TEST(Aabb, OfPointsIsTheSmallestBoxHoldingThem) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50, 50);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Vec3> pts(1 + trial % 9);
    for (Vec3& p : pts) p = Vec3(u(rng), u(rng), u(rng));
    const Aabb b = Aabb::of(pts);
    for (const Vec3& p : pts) EXPECT_TRUE(b.contains(p));
    // Each face touches a point: shrinking any side by a hair leaves one out.
    for (int a = 0; a < 3; ++a) {
      bool at_min = false, at_max = false;
      for (const Vec3& p : pts) at_min |= p[a] == b.min[a], at_max |= p[a] == b.max[a];
      EXPECT_TRUE(at_min && at_max) << "axis " << a;
    }
  }
  EXPECT_TRUE(Aabb::of(std::vector<Vec3>{}).empty());
  EXPECT_EQ(Aabb::of(std::vector<Vec3>{}).extent(), Vec3::Zero());
}

TEST(Aabb, ExtendOverlapContainAndDistanceAgreeWithTheirDefinitions) {
  Aabb a{Vec3(0, 0, 0), Vec3(2, 4, 6)};
  EXPECT_EQ(a.centre(), Vec3(1, 2, 3));
  EXPECT_EQ(a.longest_axis(), 2);
  EXPECT_DOUBLE_EQ(a.diagonal(), std::sqrt(4.0 + 16.0 + 36.0));
  const Aabb touching{Vec3(2, 4, 6), Vec3(3, 5, 7)}, apart{Vec3(2.001, 0, 0), Vec3(3, 1, 1)};
  EXPECT_TRUE(a.overlaps(touching));  // closed boxes: a shared corner counts
  EXPECT_FALSE(a.overlaps(apart));
  EXPECT_TRUE(a.inflated(1).contains(Aabb{Vec3(-1, -1, -1), Vec3(3, 5, 7)}));
  EXPECT_FALSE(a.contains(Aabb{Vec3(-1, 0, 0), Vec3(1, 1, 1)}));
  EXPECT_DOUBLE_EQ(a.squared_distance(Vec3(1, 2, 3)), 0.0);
  EXPECT_DOUBLE_EQ(a.squared_distance(Vec3(5, 8, 3)), 9.0 + 16.0);
  Aabb grown;
  EXPECT_TRUE(grown.empty());
  grown.extend(Vec3(1, 1, 1));
  EXPECT_FALSE(grown.empty());
  EXPECT_EQ(grown.extent(), Vec3::Zero());
  grown.extend(a);
  EXPECT_EQ(grown.min, a.min);
  EXPECT_EQ(grown.max, a.max);
  EXPECT_EQ(Aabb::of_triangle(Vec3(0, 5, 1), Vec3(3, -1, 2), Vec3(1, 2, -4)).min, Vec3(0, -1, -4));
}

}  // namespace
}  // namespace ido::geometry

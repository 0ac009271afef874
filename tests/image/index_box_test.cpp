// SPDX-License-Identifier: Apache-2.0
#include "ido/image/index_box.h"

#include <algorithm>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido::image {
using test::rotation;

using Voxel = std::tuple<std::int64_t, std::int64_t, std::int64_t>;

TEST(IndexBox, OfCentresTakesTheIntegerIndicesInsideAndClipsToTheGrid) {
  const IndexBox b = IndexBox::of_centres(Vec3(-0.5, 1.0, 2.1), Vec3(2.2, 1.0, 9.0), {5, 5, 5});
  EXPECT_EQ(b.lo, (Index3{0, 1, 3}));
  EXPECT_EQ(b.hi, (Index3{2, 1, 4}));
  EXPECT_EQ(b.extent(), (Index3{3, 1, 2}));
  // A box between two centres holds none.
  EXPECT_TRUE(IndexBox::of_centres(Vec3(0.2, 0, 0), Vec3(0.8, 1, 1), {5, 5, 5}).empty());
  EXPECT_EQ(IndexBox::of_centres(Vec3(0.2, 0, 0), Vec3(0.8, 1, 1), {5, 5, 5}).extent(), (Index3{0, 0, 0}));
}

TEST(IndexBox, NoneGrowsToTheBoundsOfTheVoxelsAdded) {
  IndexBox b = IndexBox::none();
  EXPECT_TRUE(b.empty());
  b.extend({4, -2, 7});
  EXPECT_EQ(b.extent(), (Index3{1, 1, 1}));
  b.extend({1, 3, 7});
  EXPECT_EQ(b.lo, (Index3{1, -2, 7}));
  EXPECT_EQ(b.hi, (Index3{4, 3, 7}));
  EXPECT_TRUE(b.contains(2, 0, 7));
  EXPECT_FALSE(b.contains(2, 0, 8));
}

TEST(IndexBox, GrownAddsVoxelsOnEverySideWithinTheGrid) {
  const IndexBox b{{0, 3, 5}, {2, 4, 9}};
  const IndexBox g = b.grown(2, {10, 10, 10});
  EXPECT_EQ(g.lo, (Index3{0, 1, 3}));
  EXPECT_EQ(g.hi, (Index3{4, 6, 9}));
  EXPECT_EQ(b.grown(0, {10, 10, 10}).lo, b.lo);
  EXPECT_EQ(b.grown(0, {10, 10, 10}).hi, b.hi);
}

TEST(IndexBox, ForEachVisitsEveryVoxelOnceInStorageOrder) {
  const Volume<float> v({4, 3, 5});
  const IndexBox b = IndexBox::of_grid(v.size());
  std::vector<std::size_t> seen;
  b.for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) { seen.push_back(v.linear_index(i, j, k)); });
  ASSERT_EQ(seen.size(), v.voxel_count());
  for (std::size_t l = 0; l < seen.size(); ++l) EXPECT_EQ(seen[l], l);
}

// The voxels whose centres lie in a world box, on a grid rotated against the world axes: the
// index box holds every one of them, and every voxel it holds has its centre in the box's
// index-space bounds (the corners' box), which it is exactly.
TEST(IndexBox, VoxelsInBoxHoldEveryCentreInsideTheWorldBox) {
  const Volume<float> v({20, 16, 12}, Vec3(0.7, 1.1, 2.3), Vec3(-5, 3, 40), rotation(0.4, -0.3, 0.9));
  const geometry::Aabb world{Vec3(-3, 0, 38), Vec3(6, 9, 52)};
  const IndexBox b = voxels_in_box(v, world);
  const geometry::Aabb idx = v.index_bounds(world);
  int inside = 0;
  IndexBox::of_grid(v.size()).for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) {
    const Vec3 c(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
    if (world.contains(v.index_to_world(c))) {
      ++inside;
      EXPECT_TRUE(b.contains(i, j, k)) << i << " " << j << " " << k;
    }
    EXPECT_EQ(b.contains(i, j, k), idx.contains(c)) << i << " " << j << " " << k;
  });
  EXPECT_GT(inside, 10);
}

TEST(IndexBox, IndexBoundsOfAWorldBoxHoldItsCornersIndices) {
  const Volume<float> v({8, 8, 8}, Vec3(0.5, 1.5, 3.0), Vec3(1, 2, 3), rotation(0.2, 0.7, -0.5));
  const geometry::Aabb world{Vec3(-2, -1, 0), Vec3(4, 5, 9)};
  const geometry::Aabb idx = v.index_bounds(world);
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? world.max.x() : world.min.x(), (c & 2) ? world.max.y() : world.min.y(),
                      (c & 4) ? world.max.z() : world.min.z());
    EXPECT_TRUE(idx.inflated(1e-9).contains(v.world_to_index(corner)));
  }
  // On an axis-aligned grid it is the box's own image.
  const Volume<float> a({8, 8, 8}, Vec3(0.5, 2.0, 4.0), Vec3(1, 2, 3));
  const geometry::Aabb ia = a.index_bounds(world);
  EXPECT_NEAR(ia.min.x(), (-2 - 1) / 0.5, 1e-12);
  EXPECT_NEAR(ia.max.z(), (9 - 3) / 4.0, 1e-12);
}

// The ball's voxels equal a brute-force scan of the whole grid, in the same order, on an
// anisotropic rotated grid (where a per-axis reach of radius / spacing would miss some).
TEST(IndexBox, VoxelsInABallEqualABruteForceScan) {
  const Volume<float> v({24, 20, 14}, Vec3(0.6, 1.0, 2.5), Vec3(-4, 1, 10), rotation(0.6, 0.5, -0.8));
  for (const double r : {0.0, 1.7, 4.0, 6.5}) {
    const Vec3 centre = v.index_to_world(Vec3(11.3, 9.6, 6.2));
    std::vector<Voxel> fast, brute;
    for_each_voxel_in_ball(v, centre, r, [&](std::int64_t i, std::int64_t j, std::int64_t k) { fast.emplace_back(i, j, k); });
    IndexBox::of_grid(v.size()).for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) {
      if ((v.index_to_world(Vec3(double(i), double(j), double(k))) - centre).norm() <= r) brute.emplace_back(i, j, k);
    });
    EXPECT_EQ(fast, brute) << "radius " << r;
    if (r > 4) {
      EXPECT_GT(fast.size(), 20u);
    }
  }
}

// A voxel centre exactly on the sphere counts (the norm is compared, as the seed ball does).
TEST(IndexBox, CentresOnTheSphereBelongToTheBall) {
  const Volume<float> v({9, 9, 9});
  std::vector<Voxel> got;
  for_each_voxel_in_ball(v, Vec3(4, 4, 4), 2.0, [&](std::int64_t i, std::int64_t j, std::int64_t k) { got.emplace_back(i, j, k); });
  EXPECT_EQ(got.size(), 33u);  // 1 + 6 + 12 + 8 + 6: |d|² ∈ {0, 1, 2, 3, 4}
  EXPECT_NE(std::find(got.begin(), got.end(), Voxel{6, 4, 4}), got.end());
}

}  // namespace ido::image

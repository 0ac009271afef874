// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/spatial_hash.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "ido/core/error.h"

namespace ido::geometry {
namespace {

std::vector<Aabb> random_boxes(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> at(-20.0, 20.0), size(0.05, 4.0);
  std::vector<Aabb> boxes;
  for (int i = 0; i < n; ++i) {
    const Vec3 lo(at(rng), at(rng), at(rng));
    boxes.push_back({lo, lo + Vec3(size(rng), size(rng), size(rng))});
  }
  return boxes;
}

TEST(SpatialHash, PointCandidatesHoldEveryBoxThatContainsThePoint) {
  // The hash may return false candidates but must never miss a box: checked against brute
  // force at random points, for cells smaller and larger than the boxes.
  std::mt19937 rng(3);
  const std::vector<Aabb> boxes = random_boxes(rng, 400);
  std::uniform_real_distribution<double> at(-22.0, 22.0);
  for (const double cell : {0.5, 2.0, 7.0}) {
    const SpatialHash hash(boxes, cell);
    std::size_t hits = 0, candidates = 0;
    for (int q = 0; q < 4000; ++q) {
      const Vec3 p(at(rng), at(rng), at(rng));
      const auto c = hash.candidates(p);
      const std::set<std::int32_t> got(c.begin(), c.end());
      candidates += got.size();
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (boxes[i].contains(p)) {
          ++hits;
          ASSERT_TRUE(got.count(std::int32_t(i))) << "cell " << cell << " box " << i << " missed";
        }
    }
    EXPECT_GT(hits, 100u);
    // The point of hashing: far fewer candidates than boxes.
    EXPECT_LT(double(candidates) / 4000.0, 0.25 * double(boxes.size())) << "cell " << cell;
  }
}

TEST(SpatialHash, BoxQueryVisitsEveryOverlappingBox) {
  std::mt19937 rng(11);
  const std::vector<Aabb> boxes = random_boxes(rng, 300);
  const SpatialHash hash(boxes, 1.5);
  for (const Aabb& query : random_boxes(rng, 300)) {
    std::set<std::int32_t> got;
    hash.for_each_in_box(query, [&](std::int32_t i) { got.insert(i); });
    for (std::size_t i = 0; i < boxes.size(); ++i)
      if (boxes[i].overlaps(query)) {
        ASSERT_TRUE(got.count(std::int32_t(i))) << "box " << i;
      }
  }
}

TEST(SpatialHash, RefusesABadCellOrANonFiniteBox) {
  const std::vector<Aabb> ok{{Vec3::Zero(), Vec3::Ones()}};
  EXPECT_THROW(SpatialHash(ok, 0.0), InvalidInput);
  EXPECT_THROW(SpatialHash(ok, -1.0), InvalidInput);
  const std::vector<Aabb> bad{{Vec3::Zero(), Vec3(1.0, INFINITY, 1.0)}};
  EXPECT_THROW(SpatialHash(bad, 1.0), InvalidInput);
  const SpatialHash empty;
  EXPECT_TRUE(empty.candidates(Vec3::Zero()).empty());
}

TEST(Aabb, OfPointsIsTheTightBox) {
  const std::vector<Vec3> pts{{1, -2, 3}, {-4, 5, 0.5}, {2, 2, -7}};
  const Aabb b = Aabb::of(pts);
  EXPECT_EQ(b.min, Vec3(-4, -2, -7));
  EXPECT_EQ(b.max, Vec3(2, 5, 3));
  for (const Vec3& p : pts) EXPECT_TRUE(b.contains(p));
  EXPECT_TRUE(Aabb::of(std::vector<Vec3>{}).empty());
}

}  // namespace
}  // namespace ido::geometry

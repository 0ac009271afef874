// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/bvh.h"

#include <gtest/gtest.h>

#include <random>

#include "ido/geometry/distance.h"
#include "ido/geometry/primitives.h"
#include "support/test_support.h"
#include "test_meshes.h"

namespace ido::geometry {
namespace {

TEST(Bvh, ClosestPointAgreesWithBruteForce) {
  const TriangleMesh m = test::merged(test::jittered(icosphere(Vec3::Zero(), 2.0, 3), 0.05, 2),
                                      torus_surface(Vec3(3, 0, 0), 2, 0.5, 24, 12));
  const TriangleBvh bvh(m);
  EXPECT_EQ(bvh.size(), m.triangles.size());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5, 7);
  for (int q = 0; q < 300; ++q) {
    const Vec3 p(u(rng), u(rng) * 0.7, u(rng) * 0.5);
    double best = 1e300;
    for (const Tri& t : m.triangles) {
      best = std::min(best, point_triangle_distance(p, m.vertices[static_cast<std::size_t>(t[0])],
                                                    m.vertices[static_cast<std::size_t>(t[1])],
                                                    m.vertices[static_cast<std::size_t>(t[2])]));
    }
    const ClosestPoint c = bvh.closest_point(p);
    ASSERT_GE(c.triangle, 0);
    EXPECT_TRUE(test::near(c.distance_mm, best, 1e-12));
    EXPECT_TRUE(test::near((c.point - p).norm(), c.distance_mm, 1e-12));
    const Tri& t = m.triangles[static_cast<std::size_t>(c.triangle)];
    EXPECT_TRUE(test::near(point_triangle_distance(p, m.vertices[static_cast<std::size_t>(t[0])],
                                                   m.vertices[static_cast<std::size_t>(t[1])],
                                                   m.vertices[static_cast<std::size_t>(t[2])]),
                           best, 1e-12));
    // A radius below the distance finds nothing.
    EXPECT_EQ(bvh.closest_point(p, 0.5 * best).triangle, -1);
  }
}

TEST(Bvh, OverlapQueryAgreesWithBruteForce) {
  const TriangleMesh m = icosphere(Vec3::Zero(), 3.0, 3);
  const TriangleBvh bvh(m);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-4, 4);
  for (int q = 0; q < 100; ++q) {
    Aabb box = Aabb::of_point(Vec3(u(rng), u(rng), u(rng)));
    box.extend(Vec3(u(rng), u(rng), u(rng)) * 0.3);
    std::vector<std::int32_t> ref;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const Tri& tri = m.triangles[t];
      if (Aabb::of_triangle(m.vertices[static_cast<std::size_t>(tri[0])], m.vertices[static_cast<std::size_t>(tri[1])],
                            m.vertices[static_cast<std::size_t>(tri[2])])
              .overlaps(box)) {
        ref.push_back(static_cast<std::int32_t>(t));
      }
    }
    EXPECT_EQ(bvh.overlapping(box), ref);
  }
}

TEST(Bvh, SelfPairsAreAllOverlappingBoxPairs) {
  const TriangleMesh m = test::jittered(icosphere(Vec3::Zero(), 1.0, 2), 0.02, 5);
  const TriangleBvh bvh(m);
  std::vector<std::pair<std::int32_t, std::int32_t>> ref;
  const auto n = static_cast<std::int32_t>(m.triangles.size());
  for (std::int32_t i = 0; i < n; ++i) {
    for (std::int32_t j = i + 1; j < n; ++j) {
      const auto& a = bvh.corners(i);
      const auto& b = bvh.corners(j);
      if (Aabb::of_triangle(a[0], a[1], a[2]).overlaps(Aabb::of_triangle(b[0], b[1], b[2]))) ref.emplace_back(i, j);
    }
  }
  auto all = [](std::int32_t, std::int32_t) { return true; };
  EXPECT_EQ(bvh.self_pairs(all, false), ref);
  EXPECT_EQ(bvh.self_pairs(all, true), ref);
}

TEST(Bvh, EmptyMesh) {
  const TriangleBvh bvh(TriangleMesh{});
  EXPECT_EQ(bvh.closest_point(Vec3::Zero()).triangle, -1);
  EXPECT_TRUE(bvh.overlapping(Aabb::of_point(Vec3::Zero())).empty());
  EXPECT_TRUE(bvh.bounds().empty());
}

}  // namespace
}  // namespace ido::geometry

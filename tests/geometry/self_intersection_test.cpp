// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/self_intersection.h"

#include <gtest/gtest.h>

#include <random>

#include "ido/geometry/primitives.h"
#include "test_meshes.h"

namespace ido::geometry {
namespace {

using Pairs = std::vector<std::pair<std::int32_t, std::int32_t>>;

Pairs brute_force(const TriangleMesh& m) {
  Pairs out;
  const auto n = static_cast<std::int32_t>(m.triangles.size());
  for (std::int32_t i = 0; i < n; ++i) {
    for (std::int32_t j = i + 1; j < n; ++j) {
      if (mesh_triangles_intersect(m, i, j)) out.emplace_back(i, j);
    }
  }
  return out;
}

void expect_matches_brute_force(const TriangleMesh& m, bool expect_some) {
  const Pairs ref = brute_force(m);
  EXPECT_EQ(self_intersections(m, {.threaded = false}), ref);
  EXPECT_EQ(self_intersections(m, {.threaded = true}), ref);
  EXPECT_EQ(has_self_intersections(m), !ref.empty());
  EXPECT_EQ(!ref.empty(), expect_some);
}

TEST(SelfIntersection, CleanSurfacesHaveNone) {
  expect_matches_brute_force(icosphere(Vec3(1, 2, 3), 2.0, 3), false);
  expect_matches_brute_force(torus_surface(Vec3::Zero(), 3, 1, 32, 16), false);
  expect_matches_brute_force(box_surface(Vec3(0, 0, 0), Vec3(1, 1, 1)), false);  // coplanar neighbours
  expect_matches_brute_force(uv_cylinder(Vec3(0, 0, 0), Vec3(0, 0, 3), 1, 24, 4), false);
}

TEST(SelfIntersection, OverlappingSpheresIntersectAlongACurve) {
  const TriangleMesh m = test::merged(icosphere(Vec3(0, 0, 0), 1.0, 2), icosphere(Vec3(1, 0.1, 0), 1.0, 2));
  const Pairs ref = brute_force(m);
  EXPECT_EQ(self_intersections(m), ref);
  const auto half = static_cast<std::int32_t>(m.triangles.size() / 2);
  ASSERT_GT(ref.size(), 10u);
  for (const auto& [i, j] : ref) {  // every pair has one triangle from each sphere
    EXPECT_LT(i, half);
    EXPECT_GE(j, half);
  }
}

TEST(SelfIntersection, NoisySphereMatchesBruteForce) {
  // Strong jitter folds the surface: many intersecting pairs, many of them adjacent.
  for (unsigned seed = 1; seed <= 2; ++seed) {
    const TriangleMesh m = test::jittered(icosphere(Vec3::Zero(), 1.0, 3), 0.12, seed);
    expect_matches_brute_force(m, true);
  }
}

TEST(SelfIntersection, AdversarialGridMeshMatchesBruteForce) {
  // A triangulated grid whose vertices are snapped to a coarse integer lattice in z: many
  // exactly coplanar neighbours, folds, vertices touching faces, zero-area triangles.
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> h(-1, 1);
  const int n = 14;
  TriangleMesh m;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i, j, h(rng));
  }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  // Pull some vertices sideways onto lattice points of neighbours to create folds.
  std::uniform_int_distribution<int> pick(0, static_cast<int>(m.vertices.size()) - 1);
  for (int k = 0; k < 25; ++k) {
    Vec3& v = m.vertices[static_cast<std::size_t>(pick(rng))];
    v.x() += h(rng) * 1.5;
    v.y() += h(rng) * 1.5;
  }
  expect_matches_brute_force(m, true);
}

TEST(SelfIntersection, FoldedCoplanarNeighboursAndDuplicates) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.3, 0}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}};  // consistent orientation, but folded onto each other
  EXPECT_EQ(self_intersections(m), (Pairs{{0, 1}}));
  m.vertices[3] = {0.5, -0.3, 0};  // unfolded: flat neighbours
  EXPECT_TRUE(self_intersections(m).empty());
  m.triangles.push_back({2, 1, 0});  // the same face again, reversed
  EXPECT_EQ(self_intersections(m), (Pairs{{0, 2}}));
  // Touching at a vertex that is not shared by index: counts.
  TriangleMesh t;
  t.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {-1, 0, 0}, {0, -1, 1}};
  t.triangles = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(self_intersections(t), (Pairs{{0, 1}}));
  t.triangles[1] = {0, 4, 5};  // now shared by index: legitimate
  EXPECT_TRUE(self_intersections(t).empty());
}

TEST(SelfIntersection, EmptyAndSingle) {
  EXPECT_TRUE(self_intersections(TriangleMesh{}).empty());
  TriangleMesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {{0, 1, 2}};
  EXPECT_FALSE(has_self_intersections(one));
}

}  // namespace
}  // namespace ido::geometry

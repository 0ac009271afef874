// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/self_intersection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "ido/core/error.h"
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

/// Both searches and both early-exit queries, one and several threads, against the exact
/// brute force; returns the reference pairs.
Pairs expect_agrees_with_brute_force(const TriangleMesh& m) {
  const Pairs ref = brute_force(m);
  EXPECT_EQ(self_intersections(m, {.threaded = false}), ref);
  EXPECT_EQ(self_intersections(m, {.threaded = true}), ref);
  EXPECT_EQ(has_self_intersections(m, {.threaded = false}), !ref.empty());
  EXPECT_EQ(has_self_intersections(m, {.threaded = true}), !ref.empty());
  return ref;
}

void expect_matches_brute_force(const TriangleMesh& m, bool expect_some) {
  EXPECT_EQ(!expect_agrees_with_brute_force(m).empty(), expect_some);
}

/// @p m with its vertices and triangles in random order (same surface, no index locality).
TriangleMesh shuffled(const TriangleMesh& m, unsigned seed) { return test::shuffled(m, std::mt19937(seed)); }

/// A (n + 1)² lattice grid in the plane z = 0 triangulated into 2n² triangles, with every
/// vertex's z set by @p height(i, j).
template <class Height>
TriangleMesh lattice_grid(int n, const Height& height) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i, j, height(i, j));
  }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
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

TEST(SelfIntersection, ShuffledIndicesMatchBruteForce) {
  // No index locality: the search sorts a copy spatially (and the early-exit query probes a
  // prefix in input order first); pairs must come back in the caller's triangle ids.
  for (unsigned seed = 1; seed <= 2; ++seed) {
    const TriangleMesh folded = shuffled(test::jittered(icosphere(Vec3::Zero(), 1.0, 3), 0.12, seed), seed);
    expect_matches_brute_force(folded, true);
  }
  expect_matches_brute_force(shuffled(torus_surface(Vec3::Zero(), 3, 1, 48, 24), 5), false);
  // One fold in a large clean mesh: the input-order probe misses it, the sorted pass finds it.
  TriangleMesh one_fold = torus_surface(Vec3::Zero(), 3, 1, 48, 24);
  Vec3& dragged = one_fold.vertices[1000];
  // Pushed through the tube and out of its opposite wall: a spike through the far side.
  const Vec3 centre_line = 3.0 * Vec3(dragged.x(), dragged.y(), 0.0).normalized();
  dragged -= 2.3 * (dragged - centre_line).normalized();
  const TriangleMesh one_fold_shuffled = shuffled(one_fold, 9);
  EXPECT_FALSE(expect_agrees_with_brute_force(one_fold_shuffled).empty());
}

TEST(SelfIntersection, UnevenTriangleSizesMatchBruteForce) {
  // Large triangles across the whole box of a finely meshed sphere (from near one corner to
  // near the opposite one, through the sphere): registering them in every cell of a grid
  // sized to the small triangles exceeds the grid's budget, and the BVH takes over.
  TriangleMesh m = icosphere(Vec3::Zero(), 1.0, 3);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-6.0, 6.0);
  std::uniform_real_distribution<double> jitter(-0.5, 0.5);
  for (int k = 0; k < 12; ++k) {
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.emplace_back(-6.0 + jitter(rng), -6.0 + jitter(rng), -6.0 + jitter(rng));
    m.vertices.emplace_back(6.0 + jitter(rng), 6.0 + jitter(rng), 6.0 + jitter(rng));
    m.vertices.emplace_back(u(rng), u(rng), u(rng));
    m.triangles.push_back({base, base + 1, base + 2});
  }
  expect_matches_brute_force(m, true);
  expect_matches_brute_force(shuffled(m, 4), true);
}

TEST(SelfIntersection, NearCoplanarNeighboursAtRoundoffLevel) {
  // Heights a few units in the last place of coordinates near 1000 mm: neighbours are
  // coplanar or off each other's planes by one rounding step, where the floating-point plane
  // filter cannot decide and the exact predicates must; folds and vertices pulled onto
  // neighbours' edges add touching and overlapping coplanar pairs.
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> ulps(-2, 2);
  const double ulp = std::nextafter(1000.0, 2000.0) - 1000.0;
  for (int variant = 0; variant < 3; ++variant) {
    TriangleMesh m = lattice_grid(12, [&](int, int) { return ulps(rng) * ulp; });
    for (Vec3& v : m.vertices) v = Vec3(1000.0, 1000.0, 1000.0) + (variant == 2 ? 1e-9 : 1.0) * v;
    std::uniform_int_distribution<int> pick(0, static_cast<int>(m.vertices.size()) - 1);
    std::uniform_int_distribution<int> step(-1, 1);
    for (int k = 0; k < 6 * variant; ++k) {
      Vec3& v = m.vertices[static_cast<std::size_t>(pick(rng))];
      const double scale = variant == 2 ? 1e-9 : 1.0;
      v.x() += step(rng) * 1.5 * scale;
      v.y() += step(rng) * 0.5 * scale;
    }
    const Pairs ref = expect_agrees_with_brute_force(m);
    EXPECT_EQ(ref.empty(), variant == 0);  // the unfolded grid is a height field
    EXPECT_EQ(expect_agrees_with_brute_force(shuffled(m, 3 + static_cast<unsigned>(variant))).size(), ref.size());
  }
  // Exactly flat: no intersection however the plane signs round.
  expect_matches_brute_force(lattice_grid(12, [](int, int) { return 1000.0; }), false);
}

TEST(SelfIntersection, VertexNeighboursCrossingOrTangent) {
  // Two triangles sharing vertex 0 whose opposite edges cross each other's planes: the
  // filter decides the crossing from certified signs, or hands over near the boundary
  // (the edge passing through the other triangle's edge or corner).
  // They meet beyond the shared vertex iff |y| <= 1/2 (the second triangle's cut through
  // the first's plane is the segment from the origin to (1, y, 0)).
  for (double y : {0.75, 0.5 + 0x1p-40, 0.5, 0.5 - 0x1p-40, 0.25, 1e-17, 0.0, -0.5, -0.5 - 0x1p-40}) {
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {2, -1, 0}, {2, 1, 0}, {1, y, -1}, {1, y, 1}};
    m.triangles = {{0, 1, 2}, {0, 3, 4}};
    const Pairs ref = brute_force(m);
    EXPECT_EQ(!ref.empty(), std::abs(y) <= 0.5) << "y = " << y;
    EXPECT_EQ(self_intersections(m, {.threaded = false}), ref) << "y = " << y;
    EXPECT_EQ(has_self_intersections(m, {.threaded = false}), !ref.empty()) << "y = " << y;
  }
  // The second triangle's opposite edge passes exactly through the first's corner (2, 1, 0).
  TriangleMesh corner;
  corner.vertices = {{0, 0, 0}, {2, -1, 0}, {2, 1, 0}, {2, 1, -1}, {2, 1, 1}};
  corner.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(self_intersections(corner), (Pairs{{0, 1}}));
  // Crossing beyond the first triangle: they meet only at the shared vertex.
  corner.vertices[3] = {3, 2, -1};
  corner.vertices[4] = {3, 2, 1};
  EXPECT_TRUE(self_intersections(corner).empty());
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

// From 16 384 triangles on the threaded search cuts the triangles into index blocks (one per
// worker) with a cross pass between them: the pairs must be those of the one-block serial pass
// (checked against the brute force above), also where many pairs straddle the blocks (the
// folded 20k sphere; the two 5k spheres stay below the threshold, one block either way).
TEST(SelfIntersection, ThreadedBlocksFindTheSerialPairs) {
  const TriangleMesh folded = test::jittered(icosphere(Vec3::Zero(), 1.0, 5), 0.02, 3);  // 20 480 triangles
  const TriangleMesh two = test::merged(icosphere(Vec3(0, 0, 0), 1.0, 4), icosphere(Vec3(1, 0.1, 0), 1.0, 4));
  for (const TriangleMesh* m : {&folded, &two}) {
    const Pairs serial = self_intersections(*m, {.threaded = false});
    EXPECT_FALSE(serial.empty());
    EXPECT_EQ(self_intersections(*m, {.threaded = true}), serial);
    EXPECT_TRUE(has_self_intersections(*m, {.threaded = true}));
  }
}

/// The pairs of @p all with at least one triangle flagged in @p changed.
Pairs touching(const Pairs& all, const std::vector<std::uint8_t>& changed) {
  Pairs out;
  for (const auto& p : all)
    if (changed[static_cast<std::size_t>(p.first)] || changed[static_cast<std::size_t>(p.second)]) out.push_back(p);
  return out;
}

// The incremental search returns exactly the brute force's pairs that have a flagged triangle,
// on folded, adversarial (coplanar, touching, shared edges) and shuffled meshes, with few, half
// or all triangles flagged, on one and several threads; a pair of two flagged triangles once.
TEST(SelfIntersection, TouchingSearchEqualsTheFlaggedPairsOfTheBruteForce) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> h(-1, 1);
  TriangleMesh adversarial = lattice_grid(12, [&](int, int) { return double(h(rng)); });
  std::uniform_int_distribution<int> pick(0, static_cast<int>(adversarial.vertices.size()) - 1);
  for (int k = 0; k < 20; ++k) {
    Vec3& v = adversarial.vertices[static_cast<std::size_t>(pick(rng))];
    v.x() += h(rng) * 1.5;
    v.y() += h(rng) * 1.5;
  }
  const std::vector<TriangleMesh> meshes = {
      test::jittered(icosphere(Vec3::Zero(), 1.0, 3), 0.12, 1), adversarial,
      shuffled(test::jittered(icosphere(Vec3::Zero(), 1.0, 3), 0.08, 2), 4),
      test::merged(icosphere(Vec3(0, 0, 0), 1.0, 2), icosphere(Vec3(1, 0.1, 0), 1.0, 2))};
  for (const TriangleMesh& m : meshes) {
    const Pairs all = brute_force(m);
    ASSERT_FALSE(all.empty());
    for (const double share : {0.02, 0.5, 1.0}) {
      std::bernoulli_distribution flag(share);
      std::vector<std::uint8_t> changed(m.triangles.size());
      for (auto& c : changed) c = flag(rng) ? 1 : 0;
      const Pairs want = touching(all, changed);
      EXPECT_EQ(self_intersections_touching(m, changed, {.threaded = false}), want) << share;
      EXPECT_EQ(self_intersections_touching(m, changed, {.threaded = true}), want) << share;
    }
    EXPECT_TRUE(self_intersections_touching(m, std::vector<std::uint8_t>(m.triangles.size(), 0)).empty());
  }
  EXPECT_THROW((void)self_intersections_touching(meshes[0], {1, 0}), InvalidInput);
}

// A clean surface that then moves in one place: flagging the triangles of the moved vertices
// finds every pair the whole search finds.
TEST(SelfIntersection, TouchingSearchAfterALocalMoveEqualsTheWholeSearch) {
  TriangleMesh m = torus_surface(Vec3::Zero(), 3, 1, 48, 24);
  ASSERT_TRUE(self_intersections(m).empty());
  Vec3& dragged = m.vertices[1000];
  const Vec3 centre_line = 3.0 * Vec3(dragged.x(), dragged.y(), 0.0).normalized();
  dragged -= 2.3 * (dragged - centre_line).normalized();  // a spike through the tube's far wall
  std::vector<std::uint8_t> changed(m.triangles.size(), 0);
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (std::int32_t v : m.triangles[t]) changed[t] |= v == 1000 ? 1 : 0;
  const Pairs whole = self_intersections(m);
  ASSERT_FALSE(whole.empty());
  EXPECT_EQ(self_intersections_touching(m, changed), whole);
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

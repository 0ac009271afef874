// SPDX-License-Identifier: Apache-2.0
// Topology repair: overlapping surfaces rebuilt with the topology of what they enclose, the
// components kept by volume and seeds, and folds opened in place.
#include "ido/segment/topology_repair.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/self_intersection.h"
#include "ido/geometry/winding_number.h"
#include "ido/meshing/remesh.h"
#include "ido/meshing/signed_distance.h"
#include "ido/segment/balloon.h"
#include "support/test_support.h"

namespace ido::segment {
namespace {

// Overlapping closed spheres (a self-intersecting surface) → one closed, exact-checked
// surface of the union; a ring of overlapping spheres → a torus (Euler 0).
geometry::TriangleMesh union_of_spheres(const std::vector<Vec3>& centres, double r) {
  geometry::TriangleMesh m;
  for (const Vec3& c : centres) {
    const auto s = balloon_icosphere(c, r, 3);
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), s.vertices.begin(), s.vertices.end());
    for (const Tri& t : s.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return m;
}

// The repair's signed distance evaluates the winding number only within about a grid spacing
// of the surface (and near uncounted triangles) and takes every other sign from a neighbour
// or a connected component. The full path — the winding number at every grid point, the
// distance to the nearest counted triangle by brute force — must give the same field. Both
// sign methods: the crossing parity these closed meshes take by default, and the winding
// number with its safe-step components.
void expect_field_equals_full_evaluation(const geometry::TriangleMesh& m, const image::Volume<float>& grid,
                                         meshing::SignedDistanceOptions o) {
  for (const auto method : {meshing::SignMethod::automatic, meshing::SignMethod::winding_number}) {
    o.sign = method;
    const image::Volume<float> f = meshing::signed_distance(m, grid, o);
    const geometry::WindingNumber winding(m, {.beta = o.winding_beta});
    std::int64_t wrong_sign = 0, wrong_distance = 0, inside = 0;
    for (std::int64_t k = 0; k < grid.size(2); ++k)
      for (std::int64_t j = 0; j < grid.size(1); ++j)
        for (std::int64_t i = 0; i < grid.size(0); ++i) {
          const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
          const bool in = winding.at(p) > 0.5;
          inside += in ? 1 : 0;
          if ((f(i, j, k) < 0.0f) != in) ++wrong_sign;
          double d = o.band_mm;
          for (std::size_t t = 0; t < m.triangles.size(); ++t) {
            if (!o.distance_triangles.empty() && !o.distance_triangles[t]) continue;
            const Tri& tr = m.triangles[t];
            const Vec3 c = meshing::closest_point_on_triangle_mm(p, m.vertices[tr[0]], m.vertices[tr[1]], m.vertices[tr[2]]);
            d = std::min(d, (c - p).norm());
          }
          if (std::abs(std::abs(double(f(i, j, k))) - d) > 1e-5) ++wrong_distance;
        }
    EXPECT_GT(inside, 0);
    EXPECT_EQ(wrong_sign, 0) << int(method);
    EXPECT_EQ(wrong_distance, 0) << int(method);
  }
}

TEST(TopologyRepair, SignedDistanceFastSignEqualsWindingNumberEverywhere) {
  // Two overlapping spheres: the intersecting triangles are left out of the distance, as the
  // repair does, so grid points near them must still read the winding number directly.
  const auto two = union_of_spheres({Vec3(0, 0, 0), Vec3(3.0, 0, 0)}, 2.5);
  const auto pairs = geometry::self_intersections(two);
  ASSERT_FALSE(pairs.empty());
  meshing::SignedDistanceOptions o;
  o.band_mm = 1.0;
  o.distance_triangles.assign(two.triangles.size(), 1);
  for (const auto& [a, b] : pairs) o.distance_triangles[std::size_t(a)] = o.distance_triangles[std::size_t(b)] = 0;
  expect_field_equals_full_evaluation(two, image::Volume<float>({24, 16, 16}, Vec3::Constant(0.5), Vec3(-3.1, -3.9, -4.05)), o);
  // Uncounted triangles far from the counted ones: a second sphere left out of the distance
  // entirely still bounds an inside, which only the direct evaluations near it can see.
  const auto apart = union_of_spheres({Vec3(0, 0, 0), Vec3(6.0, 0, 0)}, 2.0);
  meshing::SignedDistanceOptions half;
  half.band_mm = 1.0;
  half.distance_triangles.assign(apart.triangles.size(), 1);
  std::fill(half.distance_triangles.begin() + std::ptrdiff_t(apart.triangles.size() / 2), half.distance_triangles.end(), 0);
  expect_field_equals_full_evaluation(apart, image::Volume<float>({26, 12, 12}, Vec3::Constant(0.5), Vec3(-3.1, -2.9, -2.95)), half);
  // Every triangle counted, an anisotropic rotated grid and a band of three spacings.
  meshing::SignedDistanceOptions all;
  all.band_mm = 3 * 0.7;
  image::Volume<float> rotated({20, 18, 14}, Vec3(0.45, 0.5, 0.7), Vec3(-4.2, -4.3, -4.4));
  rotated.set_direction(test::rotation(0.3, -0.2, 0.5));
  expect_field_equals_full_evaluation(two, rotated, all);
  // A ring of spheres (genus one once repaired): an inner far region the surface encloses.
  std::vector<Vec3> ring;
  for (int i = 0; i < 8; ++i) ring.emplace_back(6 * std::cos(2 * kPi * i / 8), 6 * std::sin(2 * kPi * i / 8), 0);
  const auto torus = union_of_spheres(ring, 2.6);
  expect_field_equals_full_evaluation(torus, image::Volume<float>({36, 36, 14}, Vec3::Constant(0.5), Vec3(-9.1, -8.9, -3.3)), all);
}

// The remesher's check of its input (each edge runs once each way) still rejects an open
// mesh and a mesh with one triangle turned over, and accepts the closed ones it remeshes.
TEST(TopologyRepair, RemesherInputCheckRejectsOpenAndMisorientedMeshes) {
  const auto s = balloon_icosphere(Vec3::Zero(), 2.0, 1);
  EXPECT_NO_THROW(meshing::SurfaceRemesher{s});
  auto open = s;
  open.triangles.pop_back();
  EXPECT_THROW(meshing::SurfaceRemesher{open}, InvalidInput);
  auto flipped = s;
  std::swap(flipped.triangles[3][0], flipped.triangles[3][1]);
  EXPECT_THROW(meshing::SurfaceRemesher{flipped}, InvalidInput);
  auto doubled = s;
  doubled.triangles.push_back(s.triangles[0]);
  EXPECT_THROW(meshing::SurfaceRemesher{doubled}, InvalidInput);
}

TEST(TopologyRepair, MergesOverlapsIntoAValidSurfaceOfTheRightTopology) {
  TopologyRepairOptions ro;
  ro.grid_spacing_mm = 0.5;
  ro.target_edge_mm = 0.75;
  {
    const double r = 4.0, d = 4.0;  // two spheres, centres 4 mm apart
    const auto m = union_of_spheres({Vec3(0, 0, 0), Vec3(d, 0, 0)}, r);
    const auto pairs = geometry::self_intersections(m);
    ASSERT_FALSE(pairs.empty());
    const auto out = repair_topology(m, pairs, ro);
    const auto c = geometry::check_mesh(out);
    EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
    EXPECT_EQ(c.euler_characteristic, 2);
    EXPECT_FALSE(geometry::has_self_intersections(out));
    // Union of two balls: 2 · (4/3 π r³) − lens volume π (4r + d)(2r − d)² / 12.
    const double exact = 2 * 4.0 / 3.0 * kPi * r * r * r - kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
    EXPECT_TRUE(test::rel_near(c.signed_volume_mm3, exact, 0.05));
  }
  {
    std::vector<Vec3> ring;
    for (int i = 0; i < 10; ++i) ring.emplace_back(10 * std::cos(2 * kPi * i / 10), 10 * std::sin(2 * kPi * i / 10), 0);
    const auto m = union_of_spheres(ring, 3.5);  // neighbours 6.18 mm apart overlap by 0.8 mm
    const auto out = repair_topology(m, geometry::self_intersections(m), ro);
    const auto c = geometry::check_mesh(out);
    EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
    EXPECT_EQ(c.euler_characteristic, 0);
    EXPECT_EQ(c.components, 1);
    EXPECT_FALSE(geometry::has_self_intersections(out));
  }
  EXPECT_THROW((void)repair_topology(geometry::TriangleMesh{}, {}, ro), InvalidInput);
}

// A repair keeps what holds the seeds: of three disjoint spheres (one holding a seed, one
// holding none, one too small) only the seeded one stays; with no seed inside any, every
// sphere above the volume floor stays; an inward-facing sphere (a cavity) has negative
// volume and goes with the floor. Kept vertices are renumbered in order of first use.
TEST(TopologyRepair, KeepsTheComponentsHoldingASeed) {
  const auto three = union_of_spheres({Vec3(0, 0, 0), Vec3(20, 0, 0)}, 4.0);
  geometry::TriangleMesh m = three;
  {
    const auto small = balloon_icosphere(Vec3(-20, 0, 0), 0.5, 2);
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), small.vertices.begin(), small.vertices.end());
    for (const Tri& t : small.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  const double floor = 1.0;  // mm³: the r 0.5 sphere encloses ≈ 0.5
  const auto seeded = keep_components(m, floor, {Vec3(20.5, 0.3, -0.2)});
  auto c = geometry::check_mesh(seeded);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.euler_characteristic, 2);
  for (const Vec3& v : seeded.vertices) EXPECT_NEAR((v - Vec3(20, 0, 0)).norm(), 4.0, 1e-9);  // the sphere at x = 20
  EXPECT_EQ(seeded.triangles.size(), three.triangles.size() / 2);
  EXPECT_EQ(seeded.vertices.size(), three.vertices.size() / 2);
  // No component holds the point: the floor alone decides.
  const auto unseeded = keep_components(m, floor, {Vec3(10, 0, 0)});
  c = geometry::check_mesh(unseeded);
  EXPECT_EQ(c.components, 2);
  EXPECT_EQ(unseeded.triangles.size(), three.triangles.size());
  EXPECT_EQ(unseeded.vertices.size(), three.vertices.size());
  // A cavity: the inner sphere turned inward, inside the seeded sphere.
  geometry::TriangleMesh hollow = union_of_spheres({Vec3(0, 0, 0)}, 6.0);
  {
    const auto inner = balloon_icosphere(Vec3(0, 0, 0), 2.0, 2);
    const auto base = static_cast<std::int32_t>(hollow.vertices.size());
    hollow.vertices.insert(hollow.vertices.end(), inner.vertices.begin(), inner.vertices.end());
    for (const Tri& t : inner.triangles) hollow.triangles.push_back({t[0] + base, t[2] + base, t[1] + base});
  }
  const auto filled = keep_components(hollow, floor, {Vec3(4, 0, 0)});
  EXPECT_EQ(geometry::check_mesh(filled).components, 1);
  EXPECT_GT(geometry::check_mesh(filled).signed_volume_mm3, 4.0 / 3.0 * kPi * 5.9 * 5.9 * 5.9);
}

// A vertex dragged past its neighbour folds its fan over the surface (pairs one ring apart):
// untangle_folds opens it in place, leaving every vertex outside its region bit for bit and
// the connectivity as it was; the surface is then closed, manifold and free of intersections.
// A spike pushed through the far side of the sphere meets triangles many rings away: not a fold,
// so nothing is touched and the caller must rebuild.
TEST(TopologyRepair, UntanglesAFoldInPlaceAndLeavesContactsToTheRebuild) {
  const geometry::TriangleMesh sphere = balloon_icosphere(Vec3::Zero(), 10.0, 3);
  // Vertex 0 and its first neighbour.
  std::int32_t w = -1;
  for (const Tri& t : sphere.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] == 0) w = t[(k + 1) % 3];
  ASSERT_GE(w, 0);
  geometry::TriangleMesh folded = sphere;
  folded.vertices[0] += 1.8 * (sphere.vertices[std::size_t(w)] - sphere.vertices[0]);
  const auto pairs = geometry::self_intersections(folded);
  ASSERT_FALSE(pairs.empty());
  geometry::TriangleMesh fixed_up = folded;
  const auto region = untangle_folds(fixed_up, pairs, {});
  ASSERT_TRUE(region.has_value());
  EXPECT_TRUE(geometry::self_intersections(fixed_up).empty());
  const auto c = geometry::check_mesh(fixed_up);
  EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
  EXPECT_EQ(c.euler_characteristic, 2);
  EXPECT_EQ(fixed_up.triangles, folded.triangles);
  std::vector<std::uint8_t> in_region(folded.vertices.size(), 0);
  for (std::int32_t v : *region) in_region[std::size_t(v)] = 1;
  EXPECT_LT(region->size(), folded.vertices.size() / 10);
  for (std::size_t v = 0; v < folded.vertices.size(); ++v)
    if (!in_region[v]) {
      EXPECT_EQ(fixed_up.vertices[v], folded.vertices[v]) << v;
    }
  // With the dragged vertex's whole neighbourhood fixed, the fold cannot open.
  std::vector<std::uint8_t> fixed(folded.vertices.size(), 1);
  geometry::TriangleMesh stuck = folded;
  EXPECT_FALSE(untangle_folds(stuck, pairs, fixed).has_value());
  EXPECT_EQ(stuck.vertices, folded.vertices);
  // A contact: vertex 0 pushed through the sphere and out of its far side.
  geometry::TriangleMesh spiked = sphere;
  spiked.vertices[0] *= -1.3;
  const auto contact = geometry::self_intersections(spiked);
  ASSERT_FALSE(contact.empty());
  geometry::TriangleMesh untouched = spiked;
  EXPECT_FALSE(untangle_folds(untouched, contact, {}).has_value());
  EXPECT_EQ(untouched.vertices, spiked.vertices);
}


TEST(TopologyRepair, SeedsAndVolumeFloorSelectTheRebuiltComponents) {
  // Two disjoint spheres, no intersection: the rebuild keeps both, closed and genus 0, each
  // with about its ball's volume; a seed inside one keeps only that one.
  const double r = 3.0;
  const auto two = union_of_spheres({Vec3(0, 0, 0), Vec3(10, 0, 0)}, r);
  TopologyRepairOptions o;
  o.grid_spacing_mm = 0.5;
  o.remesh = false;
  const auto both = repair_topology(two, {}, o);
  auto c = geometry::check_mesh(both);
  EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
  EXPECT_EQ(c.components, 2);
  EXPECT_EQ(c.genus, 0);
  EXPECT_TRUE(test::rel_near(c.signed_volume_mm3, 2 * 4.0 / 3.0 * kPi * r * r * r, 0.05));
  o.keep_points_mm = {Vec3(10.5, 0.2, -0.3)};
  const auto one = repair_topology(two, {}, o);
  c = geometry::check_mesh(one);
  EXPECT_EQ(c.components, 1);
  EXPECT_GT(c.bounds_min.x(), 5.0) << "the kept sphere is the one at x = 10";
  // A floor above both volumes drops everything.
  o.keep_points_mm.clear();
  o.min_component_volume_mm3 = 1000.0;
  EXPECT_TRUE(repair_topology(two, {}, o).triangles.empty());
}

TEST(TopologyRepair, BadArgumentsAreRefused) {
  const auto s = union_of_spheres({Vec3::Zero()}, 2.0);
  TopologyRepairOptions o;
  for (const double bad : {0.0, -1.0, double(NAN)}) {
    o = {};
    o.grid_spacing_mm = bad;
    EXPECT_THROW((void)repair_topology(s, {}, o), InvalidInput) << bad;
    o = {};
    o.target_edge_mm = bad;
    EXPECT_THROW((void)repair_topology(s, {}, o), InvalidInput) << bad;
  }
  // Fixed flags must be empty or one per vertex.
  geometry::TriangleMesh m = s;
  EXPECT_THROW((void)untangle_folds(m, {{0, 1}}, std::vector<std::uint8_t>(3, 0)), InvalidInput);
  // No pairs: nothing to untangle, the mesh untouched.
  EXPECT_FALSE(untangle_folds(m, {}, {}).has_value());
  EXPECT_EQ(m.vertices, s.vertices);
}

TEST(KeepComponents, RenumbersVerticesInOrderOfFirstUseAndDropsUnusedOnes) {
  auto m = union_of_spheres({Vec3(0, 0, 0), Vec3(10, 0, 0)}, 2.0);
  // An unused vertex at the front, and the triangles of the second sphere first.
  m.vertices.insert(m.vertices.begin(), Vec3(100, 100, 100));
  for (Tri& t : m.triangles)
    for (auto& v : t) ++v;
  std::rotate(m.triangles.begin(), m.triangles.begin() + std::ptrdiff_t(m.triangles.size() / 2), m.triangles.end());
  const auto out = keep_components(m, 0.0);
  EXPECT_EQ(out.vertices.size(), m.vertices.size() - 1);
  ASSERT_EQ(out.triangles.size(), m.triangles.size());
  std::int32_t next = 0;
  for (std::size_t t = 0; t < out.triangles.size(); ++t)
    for (std::int32_t v : out.triangles[t]) {
      ASSERT_LE(v, next) << "vertex " << v << " used before " << next;
      if (v == next) ++next;
    }
  // The same triangles in the same order, on the same positions.
  for (std::size_t t = 0; t < out.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(out.vertices[std::size_t(out.triangles[t][k])], m.vertices[std::size_t(m.triangles[t][k])]);
  EXPECT_GT(out.vertices[0].x(), 5.0) << "the first kept triangle is the second sphere's";
}

}  // namespace
}  // namespace ido::segment

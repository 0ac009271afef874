// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/mesh_checks.h"

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/primitives.h"
#include "test_meshes.h"
#include "support/test_support.h"

namespace ido::geometry {
namespace {

TEST(MeshChecks, SphereIsClosedGenusZero) {
  for (int s = 0; s <= 3; ++s) {
    const TriangleMesh m = icosphere(Vec3(1, 2, 3), 5.0, s);
    const MeshCheckReport r = check_mesh(m);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.edge_manifold);
    EXPECT_TRUE(r.vertex_manifold);
    EXPECT_TRUE(r.oriented);
    EXPECT_EQ(r.euler_characteristic, 2);
    ASSERT_TRUE(r.genus.has_value());
    EXPECT_EQ(*r.genus, 0);
    EXPECT_EQ(r.components, 1);
    EXPECT_EQ(r.boundary_edges, 0u);
    EXPECT_EQ(r.degenerate_triangles, 0u);
    EXPECT_EQ(r.vertices, 10u * (1u << (2 * s)) + 2u);
    EXPECT_EQ(r.edges, 3 * r.triangles / 2);
    EXPECT_GT(r.signed_volume_mm3, 0.0);
    EXPECT_LE(r.bounds_max.x(), 6.0 + 1e-12);
    EXPECT_GE(r.bounds_min.x(), -4.0 - 1e-12);
  }
}

TEST(MeshChecks, TorusHasGenusOne) {
  const MeshCheckReport r = check_mesh(torus_surface(Vec3::Zero(), 10.0, 3.0, 24, 12));
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(r.euler_characteristic, 0);
  ASSERT_TRUE(r.genus.has_value());
  EXPECT_EQ(*r.genus, 1);
  EXPECT_GT(r.signed_volume_mm3, 0.0);
}

TEST(MeshChecks, TwoDisjointSpheresAndSphereWithTorus) {
  const TriangleMesh a = icosphere(Vec3::Zero(), 1.0, 2);
  const TriangleMesh b = icosphere(Vec3(5, 0, 0), 1.0, 1);
  MeshCheckReport r = check_mesh(test::merged(a, b));
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.euler_characteristic, 4);
  ASSERT_TRUE(r.genus.has_value());
  EXPECT_EQ(*r.genus, 0);
  r = check_mesh(test::merged(a, torus_surface(Vec3(20, 0, 0), 5.0, 1.0, 16, 8)));
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.euler_characteristic, 2);
  ASSERT_TRUE(r.genus.has_value());
  EXPECT_EQ(*r.genus, 1);
}

TEST(MeshChecks, OpenMeshCountsBoundaryEdges) {
  TriangleMesh m = icosphere(Vec3::Zero(), 1.0, 1);
  m.triangles.pop_back();  // one hole: 3 boundary edges
  MeshCheckReport r = check_mesh(m);
  EXPECT_FALSE(r.closed);
  EXPECT_FALSE(is_closed(m));
  EXPECT_EQ(r.boundary_edges, 3u);
  EXPECT_TRUE(r.edge_manifold);
  EXPECT_TRUE(r.vertex_manifold);
  EXPECT_FALSE(r.genus.has_value());
  EXPECT_EQ(r.euler_characteristic, 1);  // a disc
  // A single triangle: 3 boundary edges, χ = 1.
  TriangleMesh tri;
  tri.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.triangles = {{0, 1, 2}};
  r = check_mesh(tri);
  EXPECT_EQ(r.boundary_edges, 3u);
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_TRUE(test::near(r.area_mm2, 0.5, 1e-15));
}

TEST(MeshChecks, NonManifoldEdgeDetected) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshCheckReport r = check_mesh(m);
  EXPECT_FALSE(r.edge_manifold);
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_FALSE(r.oriented);
  EXPECT_FALSE(r.genus.has_value());
}

TEST(MeshChecks, BowTieVertexDetected) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  const MeshCheckReport r = check_mesh(m);
  EXPECT_TRUE(r.edge_manifold);
  EXPECT_FALSE(r.vertex_manifold);
  EXPECT_EQ(r.non_manifold_vertices, 1u);
  EXPECT_EQ(r.components, 1);
  // Two spheres glued at one vertex: closed, edge-manifold, but not vertex-manifold.
  TriangleMesh a = icosphere(Vec3::Zero(), 1.0, 1);
  TriangleMesh b = icosphere(Vec3(2, 0, 0), 1.0, 1);
  TriangleMesh ab = test::merged(a, b);
  // Vertex of b at (1,0,0) is the one with minimum x; replace it with a's vertex at max x.
  std::int32_t amax = 0;
  std::int32_t bmin = 0;
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(a.vertices.size()); ++i) {
    if (a.vertices[static_cast<std::size_t>(i)].x() > a.vertices[static_cast<std::size_t>(amax)].x()) amax = i;
    if (b.vertices[static_cast<std::size_t>(i)].x() < b.vertices[static_cast<std::size_t>(bmin)].x()) bmin = i;
  }
  const auto shift = static_cast<std::int32_t>(a.vertices.size());
  for (std::size_t t = a.triangles.size(); t < ab.triangles.size(); ++t) {
    for (auto& v : ab.triangles[t]) {
      if (v == bmin + shift) v = amax;
    }
  }
  const MeshCheckReport r2 = check_mesh(ab);
  EXPECT_TRUE(r2.closed);
  EXPECT_TRUE(r2.edge_manifold);
  EXPECT_EQ(r2.non_manifold_vertices, 1u);
  EXPECT_EQ(r2.components, 1);
  EXPECT_FALSE(r2.genus.has_value());
}

TEST(MeshChecks, FlippedTriangleBreaksOrientation) {
  TriangleMesh m = icosphere(Vec3::Zero(), 1.0, 2);
  std::swap(m.triangles[7][1], m.triangles[7][2]);
  const MeshCheckReport r = check_mesh(m);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.edge_manifold);
  EXPECT_FALSE(r.oriented);
  EXPECT_FALSE(r.genus.has_value());
  // Flipping every triangle keeps it oriented but negates the volume.
  TriangleMesh all = icosphere(Vec3::Zero(), 1.0, 2);
  const double v = signed_volume(all);
  for (Tri& t : all.triangles) std::swap(t[1], t[2]);
  EXPECT_TRUE(check_mesh(all).oriented);
  EXPECT_TRUE(test::rel_near(signed_volume(all), -v, 1e-14));
}

TEST(MeshChecks, IcosphereVolumeConvergesToBall) {
  const double r = 7.5;
  const double exact = 4.0 / 3.0 * kPi * r * r * r;
  double previous_error = 1e300;
  for (int s = 1; s <= 5; ++s) {
    const TriangleMesh m = icosphere(Vec3(-3, 4, 100), r, s);
    const double err = std::abs(signed_volume(m) - exact);
    EXPECT_LT(signed_volume(m), exact);  // inscribed polyhedron
    EXPECT_LT(err, previous_error / 3.5);  // O(h²): error falls about 4× per subdivision
    previous_error = err;
    const double area_err = std::abs(surface_area(m) - 4 * kPi * r * r);
    EXPECT_LT(area_err / (4 * kPi * r * r), 2.0 / (1 << (2 * s)));
  }
  EXPECT_LT(previous_error / exact, 1e-3);
}

TEST(MeshChecks, BoxVolumeAndAreaExact) {
  const TriangleMesh m = box_surface(Vec3(-1, 2, 3), Vec3(2, 4, 7.5));
  const MeshCheckReport r = check_mesh(m);
  EXPECT_TRUE(test::near(r.signed_volume_mm3, 3.0 * 2.0 * 4.5, 1e-12));
  EXPECT_TRUE(test::near(r.area_mm2, 2 * (3.0 * 2.0 + 3.0 * 4.5 + 2.0 * 4.5), 1e-12));
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(*r.genus, 0);
  EXPECT_EQ(r.bounds_min, Vec3(-1, 2, 3));
  EXPECT_EQ(r.bounds_max, Vec3(2, 4, 7.5));
}

TEST(MeshChecks, CylinderIsClosedWithRightVolume) {
  const TriangleMesh m = uv_cylinder(Vec3(1, 1, 1), Vec3(1, 5, 4), 2.0, 64, 3);
  const MeshCheckReport r = check_mesh(m);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(*r.genus, 0);
  // Inscribed 64-gon prism: area of the polygon × height.
  const double polygon = 0.5 * 64 * 4.0 * std::sin(2 * kPi / 64);
  EXPECT_TRUE(test::rel_near(r.signed_volume_mm3, polygon * 5.0, 1e-12));
}

TEST(MeshChecks, DegenerateTriangleCountedExactly) {
  TriangleMesh m;
  // Collinear corners with non-representable step: 0.1, 0.2, 0.3 are not exactly collinear
  // in binary, (0,0,0), (1,1,1), (3,3,3) are.
  m.vertices = {{0, 0, 0}, {1, 1, 1}, {3, 3, 3}, {0.1, 0.1, 0}, {0.2, 0.2, 0}, {0.3, 0.3, 0}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {0, 0, 1}};
  const MeshCheckReport r = check_mesh(m);
  // 0.1+0.2 ≠ 0.3 in binary, but the three points (0.1,0.1), (0.2,0.2), (0.3,0.3) are still
  // exactly on the line y = x: so all three triangles are degenerate.
  EXPECT_EQ(r.degenerate_triangles, 3u);
  m.vertices[5] = {0.3, 0.30000000000000004, 0};
  EXPECT_EQ(check_mesh(m).degenerate_triangles, 2u);
}

TEST(MeshChecks, BadIndexThrows) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 3}};
  EXPECT_THROW((void)check_mesh(m), InvalidInput);
  m.triangles = {{0, 1, 2}};
  m.vertices[1].x() = std::nan("");
  EXPECT_THROW((void)check_mesh(m), InvalidInput);
}

TEST(MeshChecks, EmptyMesh) {
  const MeshCheckReport r = check_mesh(TriangleMesh{});
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.components, 0);
  EXPECT_EQ(r.euler_characteristic, 0);
}

}  // namespace
}  // namespace ido::geometry

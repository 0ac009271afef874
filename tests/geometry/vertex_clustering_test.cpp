// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/vertex_clustering.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/primitives.h"

namespace ido::geometry {
namespace {

/// Occupied cubes of edge @p cell_mm from the bounding-box minimum (the documented grid).
std::size_t occupied_cells(const TriangleMesh& m, double cell_mm) {
  Vec3 lo = m.vertices[0];
  for (const Vec3& v : m.vertices) lo = lo.cwiseMin(v);
  std::set<std::array<long long, 3>> cells;
  for (const Vec3& v : m.vertices) {
    const Vec3 c = ((v - lo) / cell_mm).array().floor();
    cells.insert({static_cast<long long>(c.x()), static_cast<long long>(c.y()), static_cast<long long>(c.z())});
  }
  return cells.size();
}

/// Every triangle names three different vertices and has an area above 10⁻⁹ · cell², and no
/// triangle is repeated.
void expect_no_degenerate(const TriangleMesh& m, double cell_mm) {
  std::set<std::array<std::int32_t, 3>> seen;
  for (const Tri& t : m.triangles) {
    EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    const Vec3& a = m.vertices[std::size_t(t[0])];
    const double area = 0.5 * (m.vertices[std::size_t(t[1])] - a).cross(m.vertices[std::size_t(t[2])] - a).norm();
    EXPECT_GT(area, 1e-9 * cell_mm * cell_mm);
    std::array<std::int32_t, 3> key = t;
    std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
    EXPECT_TRUE(seen.insert(key).second) << "a repeated triangle";
  }
}

TEST(VertexClustering, SphereStaysWithinOneCellAndKeepsItsVolume) {
  const Vec3 c(3, -2, 7);
  const double r = 10.0, cell = 1.5;
  const TriangleMesh in = icosphere(c, r, 5);  // 10 242 vertices, 20 480 triangles
  const TriangleMesh out = cluster_vertices(in, cell);
  EXPECT_LE(out.vertex_count(), occupied_cells(in, cell));
  EXPECT_LT(out.triangle_count(), in.triangle_count() / 4);
  EXPECT_GT(out.triangle_count(), 500u);
  expect_no_degenerate(out, cell);
  // Each vertex is the mean of input vertices in one cube: within a cube's diagonal of them,
  // so of the sphere (the input's vertices lie on it, its triangles within 0.01 mm of it).
  for (const Vec3& v : out.vertices) EXPECT_LE(std::abs((v - c).norm() - r), std::sqrt(3.0) * cell);
  // Closed in, about the same solid out, still facing outward.
  const MeshCheckReport before = check_mesh(in), after = check_mesh(out);
  EXPECT_NEAR(after.signed_volume_mm3 / before.signed_volume_mm3, 1.0, 0.05);
}

TEST(VertexClustering, TorusKeepsItsShapeAndOrientation) {
  const double major = 40.0, minor = 15.0, cell = 2.0;
  const TriangleMesh in = torus_surface(Vec3::Zero(), major, minor, 500, 200);  // 200 000 triangles
  const TriangleMesh out = cluster_vertices(in, cell);
  EXPECT_LE(out.vertex_count(), occupied_cells(in, cell));
  expect_no_degenerate(out, cell);
  for (const Vec3& v : out.vertices) {
    const double rho = std::hypot(v.x(), v.y());
    EXPECT_LE(std::abs(std::hypot(rho - major, v.z()) - minor), std::sqrt(3.0) * cell);
  }
  const MeshCheckReport before = check_mesh(in), after = check_mesh(out);
  EXPECT_NEAR(after.signed_volume_mm3 / before.signed_volume_mm3, 1.0, 0.05);  // positive: outward
  // Every edge still has triangles on both sides (no hole opened); the topology is not kept
  // (clustering makes non-manifold vertices where a cube straddles the surface twice).
  EXPECT_TRUE(after.closed);
}

TEST(VertexClustering, BudgetIsMetAndSmallMeshesAreKept) {
  const TriangleMesh in = torus_surface(Vec3::Zero(), 40.0, 15.0, 500, 200);
  for (const std::size_t budget : {30000u, 5000u, 100u}) {
    const TriangleMesh out = cluster_vertices_to(in, budget);
    EXPECT_LE(out.triangle_count(), budget);
    EXPECT_GT(out.triangle_count(), budget / 4) << "the first tries should come close to the budget";
  }
  const TriangleMesh box = box_surface(Vec3::Zero(), Vec3::Ones());
  const TriangleMesh kept = cluster_vertices_to(box, 12);
  EXPECT_EQ(kept.triangles, box.triangles);
  EXPECT_EQ(kept.vertices, box.vertices);
}

TEST(VertexClustering, CoarseCellsCollapseEverythingAndBadCellsAreRefused) {
  const TriangleMesh in = icosphere(Vec3::Zero(), 1.0, 2);
  EXPECT_EQ(cluster_vertices(in, 100.0).triangle_count(), 0u);  // one cube: no triangle has 3 cubes
  EXPECT_EQ(cluster_vertices(TriangleMesh{}, 1.0).vertex_count(), 0u);
  EXPECT_THROW((void)cluster_vertices(in, 0.0), InvalidInput);
  EXPECT_THROW((void)cluster_vertices(in, std::nan("")), InvalidInput);
  EXPECT_THROW((void)cluster_vertices(in, 1e-30), InvalidInput);  // too many cells
  EXPECT_THROW((void)cluster_vertices_to(in, 0), InvalidInput);
}

}  // namespace
}  // namespace ido::geometry

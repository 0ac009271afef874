// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/mesh_topology.h"

#include <gtest/gtest.h>

#include <set>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/primitives.h"
#include "test_meshes.h"
#include "support/test_support.h"

namespace ido::geometry {
namespace {

TEST(MeshTopology, EdgesOfClosedSurface) {
  const TriangleMesh m = icosphere(Vec3::Zero(), 1.0, 2);
  const EdgeMap map = build_edge_map(m);
  EXPECT_EQ(map.edges.size(), m.triangles.size() * 3 / 2);
  std::set<Edge> seen;
  for (const EdgeInfo& e : map.edges) {
    EXPECT_LT(e.vertices[0], e.vertices[1]);
    EXPECT_EQ(e.triangle_count, 2);
    EXPECT_EQ(e.forward, 1);
    EXPECT_EQ(e.backward, 1);
    seen.insert(e.vertices);
  }
  EXPECT_EQ(seen.size(), map.edges.size());
  // triangle_edges points at the edge with the triangle's corners.
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const EdgeInfo& e = map.edges[static_cast<std::size_t>(map.triangle_edges[t][static_cast<std::size_t>(k)])];
      const std::int32_t a = m.triangles[t][static_cast<std::size_t>(k)];
      const std::int32_t b = m.triangles[t][static_cast<std::size_t>((k + 1) % 3)];
      EXPECT_EQ(e.vertices, (Edge{std::min(a, b), std::max(a, b)}));
      EXPECT_TRUE(e.triangles[0] == static_cast<std::int32_t>(t) || e.triangles[1] == static_cast<std::int32_t>(t));
    }
  }
  EXPECT_EQ(unique_edges(m).size(), map.edges.size());
}

TEST(MeshTopology, VertexTrianglesInvertsTriangles) {
  const TriangleMesh m = torus_surface(Vec3::Zero(), 4, 1, 8, 6);
  const auto vt = vertex_triangles(m);
  std::size_t total = 0;
  for (std::size_t v = 0; v < vt.size(); ++v) {
    EXPECT_EQ(vt[v].size(), 6u);  // regular torus grid: valence 6
    for (const std::int32_t t : vt[v]) {
      const Tri& tri = m.triangles[static_cast<std::size_t>(t)];
      EXPECT_TRUE(tri[0] == static_cast<std::int32_t>(v) || tri[1] == static_cast<std::int32_t>(v) ||
                  tri[2] == static_cast<std::int32_t>(v));
    }
    total += vt[v].size();
  }
  EXPECT_EQ(total, 3 * m.triangles.size());
}

TEST(MeshTopology, ComponentsCounted) {
  TriangleMesh m = test::merged(icosphere(Vec3::Zero(), 1, 1), box_surface(Vec3(3, 3, 3), Vec3(4, 4, 4)));
  m = test::merged(m, torus_surface(Vec3(10, 0, 0), 3, 1, 6, 5));
  EXPECT_EQ(connected_components(m), 3);
  const auto labels = triangle_components(m);
  EXPECT_EQ(labels.front(), 0);
  EXPECT_EQ(labels.back(), 2);
  EXPECT_EQ(connected_components(TriangleMesh{}), 0);
}

TEST(MeshTopology, WeldRestoresSoupToClosedSurface) {
  // Triangle soup: every triangle with its own three vertices, slightly jittered.
  const TriangleMesh sphere = icosphere(Vec3(1, 1, 1), 3.0, 2);
  TriangleMesh soup;
  for (const Tri& t : sphere.triangles) {
    const auto base = static_cast<std::int32_t>(soup.vertices.size());
    for (const std::int32_t v : t) soup.vertices.push_back(sphere.vertices[static_cast<std::size_t>(v)]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  soup = test::jittered(soup, 1e-7, 3);
  EXPECT_FALSE(is_closed(soup));
  const TriangleMesh welded = weld_vertices(soup, 1e-5);
  EXPECT_EQ(welded.vertices.size(), sphere.vertices.size());
  EXPECT_EQ(welded.triangles.size(), sphere.triangles.size());
  const MeshCheckReport r = check_mesh(welded);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(*r.genus, 0);
  // Exact weld of the un-jittered soup also works; too small a tolerance leaves it open.
  EXPECT_FALSE(is_closed(weld_vertices(soup, 1e-12)));
}

TEST(MeshTopology, WeldDropsCollapsedTrianglesAndTheirCellData) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1e-9, 0, 0}, {5, 5, 5}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}};
  m.cell_fields["id"] = Field{1, {10.0, 20.0}};
  m.point_fields["p"] = Field{1, {0, 1, 2, 3, 4}};
  const TriangleMesh w = weld_vertices(m, 1e-6);
  ASSERT_EQ(w.triangles.size(), 1u);
  EXPECT_EQ(w.vertices.size(), 3u);
  EXPECT_EQ(w.cell_fields.at("id").values, std::vector<double>{10.0});
  EXPECT_EQ(w.point_fields.at("p").values, (std::vector<double>{0, 1, 2}));
  EXPECT_THROW((void)weld_vertices(m, -1.0), InvalidInput);
}

TEST(MeshTopology, RemoveUnusedVerticesKeepsGeometry) {
  TriangleMesh m;
  m.vertices = {{9, 9, 9}, {0, 0, 0}, {8, 8, 8}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{1, 3, 4}};
  m.point_fields["w"] = Field{2, {0, 0, 1, 1, 2, 2, 3, 3, 4, 4}};
  const TriangleMesh c = without_unused_vertices(m);
  ASSERT_EQ(c.vertices.size(), 3u);
  EXPECT_EQ(c.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(c.vertices[1], Vec3(1, 0, 0));
  EXPECT_EQ(c.point_fields.at("w").values, (std::vector<double>{1, 1, 3, 3, 4, 4}));
  m.triangles.push_back({0, 1, 7});
  EXPECT_THROW(remove_unused_vertices(m), InvalidInput);
}

}  // namespace
}  // namespace ido::geometry

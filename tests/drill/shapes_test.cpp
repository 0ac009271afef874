// SPDX-License-Identifier: Apache-2.0
// The drill's test shapes: cubes and blocks that fill their box with positively oriented,
// conforming tetrahedra, the cell count the size asks for, and the spec parser's errors.
#include "ido/drill/shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/tet_quality.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

TEST(Shapes, BlocksAreConformingAndFillTheirBox) {
  for (const auto& m : {make_block({1, 1, 1}, 1.0), make_cube12(1.0), make_shape("block:3,2,1,0.5")}) {
    TetHierarchy h(m);
    const double want = m.vertices.back().prod() > 0 ? 0.0 : 0.0;
    (void)want;
    std::size_t boundary = 0;
    for (std::size_t r = 0; r < h.root_count(); ++r)
      for (int f = 0; f < 4; ++f) boundary += h.root_neighbor(r, f).root < 0 ? 1 : 0;
    // Boundary faces tile the box's surface: their total area equals the box's.
    double area = 0.0;
    for (std::size_t r = 0; r < h.root_count(); ++r)
      for (int f = 0; f < 4; ++f) {
        if (h.root_neighbor(r, f).root >= 0) continue;
        std::array<Vec3, 3> p;
        int n = 0;
        for (int k = 0; k < 4; ++k)
          if (k != f) p[static_cast<std::size_t>(n++)] = h.vertices()[static_cast<std::size_t>(h.root_tet(r)[static_cast<std::size_t>(k)])];
        area += 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
      }
    Vec3 lo = m.vertices[0], hi = m.vertices[0];
    for (const auto& v : m.vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    const Vec3 d = hi - lo;
    EXPECT_TRUE(test::rel_near(area, 2 * (d.x() * d.y() + d.y() * d.z() + d.x() * d.z()), 1e-12));
    EXPECT_TRUE(test::rel_near(h.total_volume(), d.prod(), 1e-12));
    EXPECT_GT(boundary, 0U);
  }
}

TEST(Shapes, CountsOrientationAndConformity) {
  struct Case {
    geometry::TetMesh mesh;
    std::size_t vertices, tets;
    Vec3 size;
  };
  const Case cases[] = {
      {make_block({2, 2, 2}, 2.0), 8, 6, Vec3(2, 2, 2)},  // one cell: the 6-tetrahedron cube
      {make_cube12(3.0), 9, 12, Vec3(3, 3, 3)},
      {make_block({4, 3, 2}, 1.0), 5 * 4 * 3, 6 * 24, Vec3(4, 3, 2)},
      // Cells of about the size asked: 10 / 3 → 3 cells, 1 / 3 → 1 cell (at least one).
      {make_block({10, 1, 5}, 3.0), 4 * 2 * 3, 6 * 3 * 1 * 2, Vec3(10, 1, 5)},
      {make_shape("block:3,2,1"), 13 * 9 * 5, 6 * 12 * 8 * 4, Vec3(3, 2, 1)},  // CELL = 1 / 4
  };
  for (const Case& c : cases) {
    EXPECT_EQ(c.mesh.vertices.size(), c.vertices);
    EXPECT_EQ(c.mesh.tets.size(), c.tets);
    double volume = 0.0;
    for (const Tet& t : c.mesh.tets) {
      const double v = signed_volume(c.mesh.vertices[std::size_t(t[0])], c.mesh.vertices[std::size_t(t[1])],
                                     c.mesh.vertices[std::size_t(t[2])], c.mesh.vertices[std::size_t(t[3])]);
      EXPECT_GT(v, 0.0);
      volume += v;
    }
    EXPECT_TRUE(test::rel_near(volume, c.size.prod(), 1e-12));
    // Conforming: every face is shared by two tetrahedra or lies on the box's surface.
    const geometry::TetMeshReport report = geometry::check_tet_mesh(c.mesh);
    EXPECT_TRUE(report.boundary_closed && report.boundary_manifold);
    const geometry::TriangleMesh boundary = geometry::tet_boundary(c.mesh);
    EXPECT_EQ(boundary.triangles.size(), report.boundary_faces);
    for (const Tri& face : boundary.triangles) {
      bool on_box = false;
      for (int a = 0; a < 3; ++a)
        for (const double side : {0.0, c.size[a]}) {
          bool all = true;
          for (std::int32_t v : face) all = all && c.mesh.vertices[std::size_t(v)][a] == side;
          on_box = on_box || all;
        }
      EXPECT_TRUE(on_box);
    }
    for (const Vec3& v : c.mesh.vertices) {
      EXPECT_TRUE((v.array() >= 0.0).all() && (v.array() <= c.size.array()).all());
    }
  }
}

TEST(Shapes, BadSizesAndSpecsAreRefusedNamingTheText) {
  auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const InvalidInput& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(message([] { (void)make_block({1, 0, 1}, 0.5); }).find("block"), std::string::npos);
  EXPECT_NE(message([] { (void)make_block({1, 1, 1}, -0.5); }).find("block"), std::string::npos);
  EXPECT_NE(message([] { (void)make_block({1, 1, std::nan("")}, 0.5); }).find("block"), std::string::npos);
  EXPECT_NE(message([] { (void)make_block({1000, 1000, 1000}, 1.0); }).find("10^7"), std::string::npos);
  EXPECT_NE(message([] { (void)make_cube12(0.0); }).find("cube12"), std::string::npos);
  EXPECT_NE(message([] { (void)make_shape("block:1,2"); }).find("'block:1,2'"), std::string::npos);
  EXPECT_NE(message([] { (void)make_shape("block:1,2,3,4,5"); }).find("'block:1,2,3,4,5'"), std::string::npos);
  const std::string bad_number = message([] { (void)make_shape("block:1,x,3"); });
  EXPECT_NE(bad_number.find("'block:1,x,3'"), std::string::npos) << bad_number;
  EXPECT_NE(bad_number.find("'x'"), std::string::npos) << bad_number;
  EXPECT_NE(message([] { (void)make_shape("sphere"); }).find("'sphere'"), std::string::npos);
  EXPECT_NE(message([] { (void)make_shape("block:1,2,-3"); }), "accepted");
  EXPECT_EQ(make_shape("cube").tets.size(), 6U);
  EXPECT_EQ(make_shape("cube12").tets.size(), 12U);
}

}  // namespace
}  // namespace ido::drill

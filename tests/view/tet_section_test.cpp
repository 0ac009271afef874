// SPDX-License-Identifier: Apache-2.0
// The Mesh workspace's section of a tetrahedral mesh by a plane (its area is the cross
// section's, its faces face along the normal, corners on the plane counted once) and its
// dihedral-angle histogram.
#include "ido/view/tet_section.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/shapes.h"
#include "support/test_support.h"

namespace ido {
namespace {

/// The unit cube in 5 positively oriented tetrahedra (four corners and a regular one inside).
geometry::TetMesh unit_cube() {
  geometry::TetMesh m;
  for (int c = 0; c < 8; ++c) m.vertices.push_back(Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1));
  m.tets = {{0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}, {1, 2, 4, 7}};
  for (Tet& t : m.tets) {
    const auto& v = m.vertices;
    const Vec3 a = v[std::size_t(t[0])];
    if ((v[std::size_t(t[1])] - a).cross(v[std::size_t(t[2])] - a).dot(v[std::size_t(t[3])] - a) < 0) std::swap(t[2], t[3]);
  }
  return m;
}

double area(const geometry::TriangleMesh& m, const Vec3& n, bool* facing) {
  double total = 0;
  *facing = true;
  for (const Tri& t : m.triangles) {
    const Vec3 c = (m.vertices[std::size_t(t[1])] - m.vertices[std::size_t(t[0])])
                       .cross(m.vertices[std::size_t(t[2])] - m.vertices[std::size_t(t[0])]);
    total += 0.5 * c.norm();
    if (c.dot(n) <= 0) *facing = false;
  }
  return total;
}

TEST(TetSection, CutsThroughTetrahedraWithTheCrossSectionsArea) {
  const geometry::TetMesh cube = unit_cube();
  // Parallel to a face: every tetrahedron is cut and the section is the unit square.
  viz::ClipPlane plane{Vec3(0.3, 0.6, 0.37), Vec3(0, 0, 2)};
  view::TetSection s = view::tet_section(cube, plane);
  EXPECT_EQ(s.cut_tets, 5u);
  bool facing = false;
  EXPECT_TRUE(test::near(area(s.faces, Vec3::UnitZ(), &facing), 1.0, 1e-12));
  EXPECT_TRUE(facing) << "section faces face along the normal";
  for (const Vec3& p : s.faces.vertices) EXPECT_TRUE(test::near(p.z(), 0.37, 1e-12));
  EXPECT_GE(s.edges.size(), 15u);  // 4 triangles and a quadrilateral: 3·4 + 4 edges
  // Oblique: x + y + z = 1.5 cuts the cube in a regular hexagon of side √2/2, area 3√3/4.
  plane = {Vec3(0.5, 0.5, 0.5), Vec3(1, 1, 1)};
  s = view::tet_section(cube, plane);
  EXPECT_TRUE(test::near(area(s.faces, Vec3(1, 1, 1), &facing), 3.0 * std::sqrt(3.0) / 4.0, 1e-12));
  EXPECT_TRUE(facing);
  // Beside the mesh: nothing.
  plane = {Vec3(0, 0, 2), Vec3(0, 0, 1)};
  EXPECT_EQ(view::tet_section(cube, plane).cut_tets, 0u);
  EXPECT_THROW((void)view::tet_section(cube, {Vec3::Zero(), Vec3::Zero()}), InvalidInput);
}

TEST(TetSection, DihedralHistogramCountsEveryAngle) {
  const auto h = view::dihedral_histogram(unit_cube(), 36);
  ASSERT_EQ(h.size(), 36u);
  std::size_t total = 0;
  for (std::size_t c : h) total += c;
  EXPECT_EQ(total, 30u);
  EXPECT_EQ(h[14], 6u);   // the regular tetrahedron inside: acos(1/3) = 70.53° (bin 70-75°)
  EXPECT_EQ(h[10], 12u);  // the corner tetrahedra's atan(√2) = 54.74° angles (three each): bin 50-55°
  EXPECT_EQ(h[18], 12u);  // and their 90° angles in bin 90-95°
  EXPECT_THROW((void)view::dihedral_histogram(unit_cube(), 0), InvalidInput);
}

TEST(TetSection, PlanesThroughVerticesCoverTheSectionOnce) {
  // A 2 mm cube of 48 Kuhn tetrahedra (0.5 mm cells): lattice planes pass through vertices,
  // edges and whole faces. Corners on the plane count as kept, so each piece of the section is
  // given by exactly one tetrahedron: the area is the cross section's, without overlaps.
  const geometry::TetMesh block = drill::make_shape("block:2,2,2,0.5");
  ASSERT_EQ(block.tets.size(), 6U * 64U);
  struct Case {
    viz::ClipPlane plane;
    double area;
  };
  const Case cases[] = {
      {{Vec3(0, 0, 1.0), Vec3(0, 0, 1)}, 4.0},                             // a lattice plane
      {{Vec3(0, 0, 1.0), Vec3(0, 0, -3)}, 4.0},                            // the same, facing down
      {{Vec3(1.5, 0, 0), Vec3(1, 0, 0)}, 4.0},
      {{Vec3(1, 1, 1), Vec3(1, 1, 1)}, 3.0 * std::sqrt(3.0)},              // regular hexagon of side √2
      {{Vec3(1, 1, 0), Vec3(1, -1, 0)}, 2.0 * 2.0 * std::sqrt(2.0)},       // the diagonal rectangle
      {{Vec3(1.3, 0.7, 0.9), Vec3(0.2, -0.5, 1)}, -1.0},                   // oblique: area by formula below
  };
  for (const Case& c : cases) {
    const view::TetSection s = view::tet_section(block, c.plane);
    const Vec3 n = c.plane.normal.normalized();
    double area = 0.0;
    std::size_t facing_wrong = 0;
    for (const Tri& t : s.faces.triangles) {
      const Vec3 a = s.faces.vertices[std::size_t(t[0])], b = s.faces.vertices[std::size_t(t[1])],
                 d = s.faces.vertices[std::size_t(t[2])];
      const Vec3 cr = (b - a).cross(d - a);
      area += 0.5 * cr.norm();
      if (cr.norm() > 1e-12 && cr.dot(n) <= 0) ++facing_wrong;
    }
    for (const Vec3& p : s.faces.vertices) ASSERT_TRUE(test::near((p - c.plane.point).dot(n), 0.0, 1e-12));
    for (const auto& e : s.edges) {
      ASSERT_TRUE(test::near((e[0] - c.plane.point).dot(n), 0.0, 1e-12));
      ASSERT_TRUE(test::near((e[1] - c.plane.point).dot(n), 0.0, 1e-12));
    }
    EXPECT_EQ(facing_wrong, 0U);
    EXPECT_GT(s.cut_tets, 0U);
    // Every cut tetrahedron has its 3- or 4-sided polygon: 3 or 4 edges each.
    EXPECT_GE(s.edges.size(), 3 * s.cut_tets);
    EXPECT_LE(s.edges.size(), 4 * s.cut_tets);
    // An oblique plane through the cube's centre, normal n with |n_z| largest: the section is
    // the unit square's image, area 4 · |n| / |n_z| when it stays inside the side faces.
    const double want = c.area > 0 ? c.area : 4.0 / std::abs(n.z());
    EXPECT_TRUE(test::near(area, want, 1e-9)) << c.plane.normal.transpose();
  }
}

TEST(TetSection, BadMeshesAndBinCountsAreRefused) {
  geometry::TetMesh bad = unit_cube();
  bad.tets.push_back({0, 1, 2, 8});
  EXPECT_THROW((void)view::tet_section(bad, {Vec3::Zero(), Vec3(0, 0, 1)}), InvalidInput);
  EXPECT_THROW((void)view::dihedral_histogram(bad, 36), InvalidInput);
  bad.tets.back() = {0, 1, -1, 3};
  EXPECT_THROW((void)view::tet_section(bad, {Vec3::Zero(), Vec3(0, 0, 1)}), InvalidInput);
  EXPECT_THROW((void)view::dihedral_histogram(unit_cube(), 3601), InvalidInput);
  EXPECT_THROW((void)view::dihedral_histogram(unit_cube(), -3), InvalidInput);
  // One bin holds all 30 angles; 3600 bins hold them too, each where its angle is.
  EXPECT_EQ(view::dihedral_histogram(unit_cube(), 1), std::vector<std::size_t>{30});
  const auto fine = view::dihedral_histogram(unit_cube(), 3600);
  std::size_t total = 0;
  for (std::size_t c : fine) total += c;
  EXPECT_EQ(total, 30U);
  EXPECT_EQ(fine[1799] + fine[1800], 12U);  // the corner tetrahedra's 90° angles, 0.05° bins
  EXPECT_EQ(fine[std::size_t(std::acos(1.0 / 3.0) * 180.0 / kPi * 20.0)], 6U);
  // An empty mesh has an empty histogram.
  const auto none = view::dihedral_histogram(geometry::TetMesh{}, 18);
  EXPECT_EQ(none, std::vector<std::size_t>(18, 0));
}

}  // namespace
}  // namespace ido

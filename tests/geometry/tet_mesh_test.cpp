// SPDX-License-Identifier: Apache-2.0
// TetMesh: counts, and the orientation convention (b − a) · ((c − a) × (d − a)) > 0 that the
// rest of the library (volumes, checks, boundary extraction) reads the same way.
#include "ido/geometry/tet_mesh.h"

#include <utility>

#include <gtest/gtest.h>

#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "support/test_support.h"

namespace ido::geometry {
namespace {

// Two tetrahedra sharing the face (1, 2, 3), both positively oriented by the header's rule.
TetMesh two_tets() {
  TetMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1)};
  m.tets = {{0, 1, 2, 3}, {4, 2, 1, 3}};
  return m;
}

double rule(const TetMesh& m, const Tet& t) {
  const Vec3& a = m.vertices[std::size_t(t[0])];
  return (m.vertices[std::size_t(t[1])] - a).dot((m.vertices[std::size_t(t[2])] - a).cross(m.vertices[std::size_t(t[3])] - a));
}

TEST(TetMesh, CountsFollowTheArrays) {
  TetMesh m;
  EXPECT_EQ(m.vertex_count(), 0U);
  EXPECT_EQ(m.tet_count(), 0U);
  m = two_tets();
  EXPECT_EQ(m.vertex_count(), 5U);
  EXPECT_EQ(m.tet_count(), 2U);
  // Fields hold one entry per vertex or per tetrahedron.
  m.point_fields["displacement_mm"] = Field{3, std::vector<double>(3 * m.vertex_count(), 0.0)};
  m.cell_fields["von_mises_pa"] = Field{1, {1.0, 2.0}};
  EXPECT_EQ(m.point_fields.at("displacement_mm").count(), m.vertex_count());
  EXPECT_EQ(m.cell_fields.at("von_mises_pa").count(), m.tet_count());
}

TEST(TetMesh, PositiveOrientationIsPositiveVolumeAndOutwardBoundary) {
  TetMesh m = two_tets();
  for (const Tet& t : m.tets) {
    ASSERT_GT(rule(m, t), 0.0);
    const double v = tet_signed_volume(m.vertices[std::size_t(t[0])], m.vertices[std::size_t(t[1])],
                                       m.vertices[std::size_t(t[2])], m.vertices[std::size_t(t[3])]);
    EXPECT_TRUE(test::near(v, rule(m, t) / 6.0, 1e-15));
  }
  TetMeshReport r = check_tet_mesh(m);
  EXPECT_EQ(r.inverted, 0U);
  EXPECT_TRUE(test::near(r.volume_mm3, 1.0 / 6.0 + 1.0 / 3.0, 1e-15));  // corner tet + (1,1,1) tet
  // The boundary of positively oriented tetrahedra faces outward: positive enclosed volume.
  const TriangleMesh boundary = tet_boundary(m);
  EXPECT_EQ(boundary.triangle_count(), 6U);  // 8 faces, the shared one dropped twice
  EXPECT_TRUE(test::near(signed_volume(boundary), r.volume_mm3, 1e-12));

  // Swapping two corners inverts a tetrahedron: negative by the rule, counted inverted.
  std::swap(m.tets[1][2], m.tets[1][3]);
  EXPECT_LT(rule(m, m.tets[1]), 0.0);
  r = check_tet_mesh(m);
  EXPECT_EQ(r.inverted, 1U);
  EXPECT_TRUE(test::near(r.volume_mm3, 1.0 / 6.0 - 1.0 / 3.0, 1e-15));
}

}  // namespace
}  // namespace ido::geometry

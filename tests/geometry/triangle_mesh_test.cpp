// SPDX-License-Identifier: Apache-2.0
// TriangleMesh: counts, and the orientation convention (counter-clockwise seen from outside
// for a closed outward surface) as the volume and check functions read it.
#include "ido/geometry/triangle_mesh.h"

#include <utility>

#include <gtest/gtest.h>

#include "ido/geometry/mesh_checks.h"
#include "support/test_support.h"

namespace ido::geometry {
namespace {

// The box [0, 2] × [0, 3] × [0, 4] (mm), 12 triangles counter-clockwise seen from outside.
TriangleMesh box() {
  TriangleMesh m;
  for (int c = 0; c < 8; ++c) m.vertices.emplace_back(2.0 * (c & 1), 3.0 * ((c >> 1) & 1), 4.0 * ((c >> 2) & 1));
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

TEST(TriangleMesh, CountsFollowTheArrays) {
  TriangleMesh m;
  EXPECT_EQ(m.vertex_count(), 0U);
  EXPECT_EQ(m.triangle_count(), 0U);
  m = box();
  EXPECT_EQ(m.vertex_count(), 8U);
  EXPECT_EQ(m.triangle_count(), 12U);
  m.cell_fields["label"] = Field{1, std::vector<double>(m.triangle_count(), 1.0)};
  EXPECT_EQ(m.cell_fields.at("label").count(), m.triangle_count());
  // A copy is independent (value semantics: no shared storage).
  TriangleMesh copy = m;
  copy.vertices[0] = Vec3(-1, -1, -1);
  copy.cell_fields["label"].values[0] = 5.0;
  EXPECT_EQ(m.vertices[0], Vec3::Zero());
  EXPECT_EQ(m.cell_fields.at("label").values[0], 1.0);
}

TEST(TriangleMesh, CounterClockwiseFromOutsideEnclosesPositiveVolume) {
  TriangleMesh m = box();
  // Every normal (by the right-hand rule) points away from the box centre.
  const Vec3 centre(1.0, 1.5, 2.0);
  for (const Tri& t : m.triangles) {
    const Vec3 a = m.vertices[std::size_t(t[0])], b = m.vertices[std::size_t(t[1])], c = m.vertices[std::size_t(t[2])];
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - centre), 0.0);
  }
  EXPECT_TRUE(test::near(signed_volume(m), 24.0, 1e-12));
  EXPECT_TRUE(test::near(surface_area(m), 2 * (6.0 + 12.0 + 8.0), 1e-12));
  MeshCheckReport r = check_mesh(m);
  EXPECT_TRUE(r.closed && r.oriented);
  EXPECT_EQ(r.euler_characteristic, 2);
  // Reversed triangles describe the same surface facing inward: the volume changes sign.
  for (Tri& t : m.triangles) std::swap(t[1], t[2]);
  EXPECT_TRUE(test::near(signed_volume(m), -24.0, 1e-12));
  // One triangle turned over breaks the orientation.
  m = box();
  std::swap(m.triangles[3][1], m.triangles[3][2]);
  r = check_mesh(m);
  EXPECT_TRUE(r.closed);
  EXPECT_FALSE(r.oriented);
}

}  // namespace
}  // namespace ido::geometry

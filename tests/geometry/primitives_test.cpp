// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/primitives.h"

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "support/test_support.h"

namespace ido::geometry {
namespace {

TEST(Primitives, IcosphereVerticesOnSphereAndOutward) {
  const Vec3 c(2, -1, 0.5);
  const TriangleMesh m = icosphere(c, 4.0, 3);
  EXPECT_EQ(m.triangles.size(), 20u * 64u);
  for (const Vec3& v : m.vertices) EXPECT_TRUE(test::near((v - c).norm(), 4.0, 1e-12));
  for (const Tri& t : m.triangles) {
    const Vec3& a = m.vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = m.vertices[static_cast<std::size_t>(t[1])];
    const Vec3& d = m.vertices[static_cast<std::size_t>(t[2])];
    const Vec3 n = (b - a).cross(d - a);
    EXPECT_GT(n.dot((a + b + d) / 3.0 - c), 0.0);  // every face normal points away from c
  }
  EXPECT_THROW((void)icosphere(c, -1.0, 2), InvalidInput);
  EXPECT_THROW((void)icosphere(c, 1.0, 11), InvalidInput);
}

TEST(Primitives, TorusVolumeConverges) {
  const double R = 10, r = 2;
  const double exact = 2 * kPi * kPi * R * r * r;
  const TriangleMesh m = torus_surface(Vec3(1, 2, 3), R, r, 128, 64);
  const MeshCheckReport rep = check_mesh(m);
  EXPECT_EQ(*rep.genus, 1);
  EXPECT_TRUE(test::rel_near(rep.signed_volume_mm3, exact, 3e-3));
  EXPECT_LT(rep.signed_volume_mm3, exact);
  EXPECT_THROW((void)torus_surface(Vec3::Zero(), 1, 2, 8, 8), InvalidInput);
}

TEST(Primitives, BoxTetsAllPositive) {
  const TetMesh m = box_tets(Vec3(0, 0, 0), Vec3(1, 2, 3), 4);
  EXPECT_EQ(m.vertices.size(), 125u);
  for (const Tet& t : m.tets) {
    EXPECT_GT(tet_signed_volume(m.vertices[static_cast<std::size_t>(t[0])], m.vertices[static_cast<std::size_t>(t[1])],
                                m.vertices[static_cast<std::size_t>(t[2])], m.vertices[static_cast<std::size_t>(t[3])]),
              0.0);
  }
  EXPECT_THROW((void)box_tets(Vec3(0, 0, 0), Vec3(1, 0, 1), 2), InvalidInput);
}

}  // namespace
}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/tet_quality.h"

#include <gtest/gtest.h>

#include <random>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/predicates.h"
#include "ido/geometry/primitives.h"
#include "support/test_support.h"

namespace ido::geometry {
namespace {

const Vec3 kA(1, 1, 1), kB(1, -1, -1), kC(-1, 1, -1), kD(-1, -1, 1);  // regular, edge 2√2

TEST(TetQuality, RegularTetrahedron) {
  const double vol = tet_signed_volume(kA, kB, kC, kD);
  const double edge = 2.0 * std::sqrt(2.0);
  EXPECT_TRUE(test::near(std::abs(vol), edge * edge * edge / (6.0 * std::sqrt(2.0)), 1e-12));
  for (const double a : dihedral_angles_deg(kA, kB, kC, kD)) {
    EXPECT_TRUE(test::near(a, 70.52877936550931, 1e-10));
  }
  EXPECT_TRUE(test::near(std::abs(mean_ratio(kA, kB, kC, kD)), 1.0, 1e-12));
  // Scale and translation invariance.
  const Vec3 t(5, -2, 9);
  EXPECT_TRUE(test::near(mean_ratio(3 * kA + t, 3 * kB + t, 3 * kC + t, 3 * kD + t),
                         mean_ratio(kA, kB, kC, kD), 1e-12));
}

TEST(TetQuality, OrientationSignsAgree) {
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  EXPECT_TRUE(test::near(tet_signed_volume(o, x, y, z), 1.0 / 6.0, 1e-15));
  EXPECT_GT(orient3d(o, x, y, z), 0.0);
  EXPECT_GT(mean_ratio(o, x, y, z), 0.0);
  EXPECT_LT(tet_signed_volume(o, y, x, z), 0.0);
  EXPECT_LT(orient3d(o, y, x, z), 0.0);
  EXPECT_LT(mean_ratio(o, y, x, z), 0.0);
  // Right-corner tet: three right angles at the edges through o, and acos(1/√3) at the others.
  const auto ang = dihedral_angles_deg(o, x, y, z);
  EXPECT_TRUE(test::near(ang[0], 90.0, 1e-12));
  EXPECT_TRUE(test::near(ang[1], 90.0, 1e-12));
  EXPECT_TRUE(test::near(ang[2], 90.0, 1e-12));
  for (int i = 3; i < 6; ++i) {
    EXPECT_TRUE(test::near(ang[static_cast<std::size_t>(i)], std::acos(1.0 / std::sqrt(3.0)) * 180 / kPi, 1e-12));
  }
}

TEST(TetQuality, RandomTetsSatisfyInvariants) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)),
        d(u(rng), u(rng), u(rng));
    const double q = mean_ratio(a, b, c, d);
    EXPECT_LE(std::abs(q), 1.0 + 1e-12);
    EXPECT_EQ(sign_of(q), sign_of(tet_signed_volume(a, b, c, d)));
    // Swapping two vertices negates volume and mean ratio, keeps dihedral angles as a set.
    EXPECT_TRUE(test::near(mean_ratio(b, a, c, d), -q, 1e-12));
    auto s1 = dihedral_angles_deg(a, b, c, d);
    auto s2 = dihedral_angles_deg(b, a, c, d);
    std::sort(s1.begin(), s1.end());
    std::sort(s2.begin(), s2.end());
    for (int k = 0; k < 6; ++k) EXPECT_TRUE(test::near(s1[static_cast<std::size_t>(k)], s2[static_cast<std::size_t>(k)], 1e-9));
    // Dihedral angles of a tetrahedron sum to between 2π and 3π.
    double sum = 0;
    for (const double x : s1) sum += x;
    EXPECT_GT(sum, 360.0 - 1e-9);
    EXPECT_LT(sum, 540.0 + 1e-9);
  }
}

TEST(TetQuality, DegenerateTetHasZeroQuality) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0.3, 0.3, 0);
  EXPECT_EQ(mean_ratio(a, b, c, d), 0.0);
  EXPECT_EQ(orient3d(a, b, c, d), 0.0);
  EXPECT_EQ(mean_ratio(a, a, a, a), 0.0);
}

TEST(TetQuality, CubeOfTetsHasClosedBoundaryWithCubeVolume) {
  const Vec3 lo(-1, 0, 2), hi(2, 1.5, 4);
  const TetMesh m = box_tets(lo, hi, 3);
  const TetMeshReport r = check_tet_mesh(m);
  EXPECT_EQ(r.tets, 6u * 27u);
  EXPECT_EQ(r.inverted, 0u);
  EXPECT_EQ(r.degenerate, 0u);
  const double vol = 3.0 * 1.5 * 2.0;
  EXPECT_TRUE(test::near(r.volume_mm3, vol, 1e-12));
  EXPECT_TRUE(r.boundary_closed);
  EXPECT_TRUE(r.boundary_manifold);
  EXPECT_EQ(r.boundary_faces, 6u * 9u * 2u);
  EXPECT_GT(r.min_dihedral_deg, 0.0);
  EXPECT_LT(r.max_dihedral_deg, 180.0);
  const TriangleMesh boundary = tet_boundary(m);
  EXPECT_EQ(boundary.vertices.size(), m.vertices.size());  // indices kept
  const MeshCheckReport s = check_mesh(boundary);
  EXPECT_TRUE(s.closed);
  EXPECT_TRUE(s.oriented);
  EXPECT_EQ(*s.genus, 0);
  EXPECT_EQ(s.vertices, 4u * 4u * 4u - 2u * 2u * 2u);  // the surface vertices only
  EXPECT_TRUE(test::near(s.signed_volume_mm3, vol, 1e-12));  // outward
  EXPECT_TRUE(test::near(s.area_mm2, 2 * (3 * 1.5 + 3 * 2 + 1.5 * 2), 1e-12));
}

TEST(TetQuality, InvertedTetCountedAndOpenBoundaryReported) {
  TetMesh m = box_tets(Vec3::Zero(), Vec3::Ones(), 2);
  std::swap(m.tets[5][0], m.tets[5][1]);
  m.tets.pop_back();
  const TetMeshReport r = check_tet_mesh(m);
  EXPECT_EQ(r.inverted, 1u);
  EXPECT_LT(r.min_mean_ratio, 0.0);
  // Removing a tet exposes its inner faces, so the boundary stays closed; the flipped tet
  // contributes inward faces, so the boundary is no longer consistently oriented.
  const MeshCheckReport s = check_mesh(tet_boundary(m));
  EXPECT_TRUE(s.closed);
  EXPECT_FALSE(s.oriented);
}

TEST(TetQuality, FaceSharedByThreeTetsIsNonManifold) {
  TetMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}, {0.2, 0.2, 1}};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}};
  const TetMeshReport r = check_tet_mesh(m);
  EXPECT_FALSE(r.boundary_manifold);
}

TEST(TetQuality, BadInputThrows) {
  TetMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.tets = {{0, 1, 2, 4}};
  EXPECT_THROW((void)check_tet_mesh(m), InvalidInput);
  EXPECT_THROW((void)tet_boundary(m), InvalidInput);
  EXPECT_EQ(check_tet_mesh(TetMesh{}).tets, 0u);
}

}  // namespace
}  // namespace ido::geometry

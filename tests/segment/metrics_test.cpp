// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/metrics.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ido/geometry/mesh_checks.h"
#include "ido/meshing/marching_cubes.h"
#include "support/random_mask.h"
#include "support/test_support.h"

namespace ido::segment {
using image::Volume;
using test::near;
using test::random_mask;
using test::rel_near;
using test::rotation;

namespace {

/// Voxels whose centre is inside the ball (world mm).
Volume<std::uint8_t> ball(const Index3& n, const Vec3& spacing, const Vec3& centre, double r,
                          const Vec3& origin = Vec3::Zero(), const Mat3& dir = Mat3::Identity()) {
  Volume<std::uint8_t> m(n, spacing, origin, dir, 0);
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i)
        m(i, j, k) = (m.index_to_world(Vec3(double(i), double(j), double(k))) - centre).norm() < r;
  return m;
}

}  // namespace

TEST(CompareMasks, IdenticalMasksScorePerfectly) {
  const auto m = ball({30, 30, 30}, Vec3(0.7, 0.8, 1.0), Vec3(10, 12, 15), 8.0);
  const auto s = compare_masks(m, m);
  EXPECT_DOUBLE_EQ(s.dice, 1.0);
  EXPECT_DOUBLE_EQ(s.hd95_mm, 0.0);
  EXPECT_DOUBLE_EQ(s.assd_mm, 0.0);
  EXPECT_DOUBLE_EQ(s.volume_ratio, 1.0);
  EXPECT_EQ(s.components_mask, 1);
  EXPECT_EQ(s.voxels_mask, s.voxels_truth);
  EXPECT_FALSE(s.resampled);
}

TEST(CompareMasks, OffsetSpheresMatchAnalyticDice) {
  // Two balls of radius R whose centres are d apart overlap in a lens of volume
  // π (4R + d)(2R − d)² / 12, so Dice = lens / ((4/3) π R³).
  const double r = 10.0, d = 6.0;
  const Vec3 sp(0.4, 0.4, 0.4);
  const Vec3 c(16.1, 16.2, 16.3);
  const auto a = ball({80, 80, 80}, sp, c, r);
  const auto b = ball({80, 80, 80}, sp, c + Vec3(d, 0, 0) , r);
  const double lens = kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
  const double dice = lens / (4.0 / 3.0 * kPi * r * r * r);
  const auto s = compare_masks(a, b);
  // Voxelisation changes each volume by O(surface · spacing² / R) ≈ 0.2 %.
  EXPECT_TRUE(near(s.dice, dice, 0.005));
  const auto t = compare_masks(b, a);
  EXPECT_DOUBLE_EQ(s.dice, t.dice);
  EXPECT_DOUBLE_EQ(s.hd95_mm, t.hd95_mm);
  EXPECT_TRUE(near(s.assd_mm, t.assd_mm, 1e-12));  // same sum, other order
  // The farthest surface points are d apart (along the offset).
  EXPECT_TRUE(near(s.hd_mm, d, 2 * sp.x()));
}

TEST(CompareMasks, ConcentricSpheresDistancesEqualRadiusDifference) {
  const Vec3 sp(0.5, 0.6, 0.4);
  const Vec3 c(15.2, 15.1, 15.3);
  const auto inner = ball({64, 54, 80}, sp, c, 9.0);
  const auto outer = ball({64, 54, 80}, sp, c, 12.0);
  const auto s = compare_masks(inner, outer);
  // Surface voxels lie within one voxel inside each true sphere, so every surface distance
  // is 3 mm ± the largest spacing (0.6 mm); the mean error largely cancels.
  EXPECT_TRUE(near(s.assd_mm, 3.0, 0.3));
  EXPECT_TRUE(near(s.hd95_mm, 3.0, 0.6));
  EXPECT_TRUE(near(s.volume_ratio, 729.0 / 1728.0, 0.01));
}

TEST(CompareMasks, ResamplingAcrossGridsGivesTheSameDice) {
  const Vec3 sp(0.9, 1.0, 1.2);
  const auto truth = ball({30, 30, 30}, sp, Vec3(13, 14, 15), 9.0);
  const auto mask = ball({30, 30, 30}, sp, Vec3(14, 14, 16), 8.5);
  const auto same = compare_masks(mask, truth);
  // The mask on a grid three times finer whose middle sub-voxels are centred on the coarse
  // centres: nearest-neighbour resampling recovers the coarse mask exactly.
  Volume<std::uint8_t> fine({90, 90, 90}, sp / 3.0, -sp / 3.0, Mat3::Identity(), 0);
  for (std::int64_t k = 0; k < 90; ++k)
    for (std::int64_t j = 0; j < 90; ++j)
      for (std::int64_t i = 0; i < 90; ++i) fine(i, j, k) = mask(i / 3, j / 3, k / 3);
  const auto across = compare_masks(fine, truth);
  EXPECT_TRUE(across.resampled);
  EXPECT_DOUBLE_EQ(across.dice, same.dice);
  EXPECT_DOUBLE_EQ(across.hd95_mm, same.hd95_mm);
  EXPECT_DOUBLE_EQ(across.assd_mm, same.assd_mm);
  // A rotated, shifted fine grid holding the same ball: Dice close to the one-grid value.
  const Mat3 rot = rotation(0.3, 0.2, -0.4);
  const auto rotated = ball({70, 70, 70}, Vec3(0.4, 0.4, 0.4), Vec3(14, 14, 16), 8.5, Vec3(14, 14, 16) - rot * Vec3(14, 14, 14), rot);
  EXPECT_TRUE(near(compare_masks(rotated, truth).dice, same.dice, 0.02));
}

TEST(CompareMasks, EmptyMasksAndBadInput) {
  const auto truth = ball({10, 10, 10}, Vec3::Ones(), Vec3(5, 5, 5), 3.0);
  const auto empty = truth.like<std::uint8_t>(0);
  const auto s = compare_masks(empty, truth);
  EXPECT_DOUBLE_EQ(s.dice, 0.0);
  EXPECT_TRUE(std::isinf(s.hd95_mm));
  EXPECT_DOUBLE_EQ(s.volume_ratio, 0.0);
  EXPECT_DOUBLE_EQ(compare_masks(empty, empty).dice, 1.0);
  EXPECT_THROW((void)compare_masks(Volume<std::uint8_t>(), truth), InvalidInput);
}

TEST(CountComponents, SixVersusTwentySixConnectivity) {
  Volume<std::uint8_t> m({5, 5, 5});
  m(0, 0, 0) = 1;
  m(1, 1, 0) = 1;  // edge neighbour of the first
  m(2, 2, 1) = 1;  // corner neighbour of the second
  m(4, 4, 4) = 1;
  m(4, 4, 3) = 1;  // face neighbour
  EXPECT_EQ(count_components(m, Connectivity::Six), 4);
  EXPECT_EQ(count_components(m, Connectivity::TwentySix), 2);
}

TEST(MaskEuler, KnownShapes) {
  Volume<std::uint8_t> m({7, 7, 7});
  m(3, 3, 3) = 1;
  EXPECT_EQ(mask_euler_characteristic(m), 2);
  // A hollow cube: two surfaces (outer sphere and inner sphere), χ = 4.
  for (std::int64_t k = 1; k < 6; ++k)
    for (std::int64_t j = 1; j < 6; ++j)
      for (std::int64_t i = 1; i < 6; ++i) m(i, j, k) = !(i == 3 && j == 3 && k == 3);
  EXPECT_EQ(mask_euler_characteristic(m), 4);
  // A square ring of voxels: a solid torus, χ = 0.
  Volume<std::uint8_t> ring({5, 5, 1});
  for (std::int64_t j = 0; j < 5; ++j)
    for (std::int64_t i = 0; i < 5; ++i) ring(i, j, 0) = i == 0 || j == 0 || i == 4 || j == 4;
  EXPECT_EQ(mask_euler_characteristic(ring), 0);
}

TEST(MaskEuler, AgreesWithMarchingCubesOnRandomMasks) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 3000; ++trial) {
    const auto m = random_mask(rng, 5, trial % 2 ? 0.5 : 0.75);
    const auto mesh = meshing::marching_cubes_mask(m, false);
    const std::int64_t chi = mesh.triangles.empty() ? 0 : geometry::euler_characteristic(mesh);
    ASSERT_EQ(mask_euler_characteristic(m), chi) << "trial " << trial;
  }
}

TEST(CompareMeshToMask, SphereSurfaceAgainstAnalyticMask) {
  const Vec3 sp(0.8, 0.7, 0.9);
  const Vec3 c(12.3, 11.8, 12.9);
  Volume<float> f({32, 35, 30}, sp);
  for (std::int64_t k = 0; k < 30; ++k)
    for (std::int64_t j = 0; j < 35; ++j)
      for (std::int64_t i = 0; i < 32; ++i)
        f(i, j, k) = float((f.index_to_world(Vec3(double(i), double(j), double(k))) - c).norm() - 9.0);
  const auto mesh = meshing::marching_cubes(f);
  const auto truth = ball({32, 35, 30}, sp, c, 9.0);
  const auto s = compare_mesh_to_mask(mesh, truth);
  EXPECT_GT(s.dice, 0.99);
  EXPECT_LE(s.hd95_mm, sp.maxCoeff());
  geometry::TriangleMesh bad = mesh;
  bad.triangles[0][1] = 1 << 30;
  EXPECT_THROW((void)compare_mesh_to_mask(bad, truth), InvalidInput);
}

}  // namespace ido::segment

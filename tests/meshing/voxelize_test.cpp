// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/voxelize.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/meshing/marching_cubes.h"
#include "ido/meshing/signed_distance.h"
#include "support/random_mask.h"
#include "support/test_support.h"

namespace ido::meshing {
using image::Volume;
using test::random_mask;
using test::rel_near;
using test::rotation;

TEST(Voxelize, MaskSurfaceRasterisesBackToTheMask) {
  // The marching-cubes surface of a mask separates every inside voxel centre from every
  // outside one, so rasterising it onto the same grid must give the mask back exactly,
  // whatever the grid's orientation (mirrored ones included).
  std::mt19937 rng(8);
  for (int trial = 0; trial < 300; ++trial) {
    auto m = random_mask(rng, 7, 0.5);
    Mat3 d = rotation(0.1 * trial, 0.2, -0.05 * trial);
    if (trial % 2) d.col(1) *= -1.0;
    m.set_direction(d);
    m.set_origin(Vec3(trial * 0.1, -3.0, 2.0));
    const auto mesh = marching_cubes_mask(m, false);
    ASSERT_EQ(voxelize(mesh, m).data(), m.data()) << "trial " << trial;
  }
}

TEST(Voxelize, SphereHasItsVolumeAndAgreesWithTheSignedDistance) {
  const Vec3 sp(0.8, 0.7, 0.9);
  const Vec3 c(12.3, 11.8, 12.9);
  Volume<float> f({32, 35, 30}, sp);
  for (std::int64_t k = 0; k < 30; ++k)
    for (std::int64_t j = 0; j < 35; ++j)
      for (std::int64_t i = 0; i < 32; ++i)
        f(i, j, k) = float((f.index_to_world(Vec3(double(i), double(j), double(k))) - c).norm() - 9.0);
  const auto mesh = marching_cubes(f);
  // On a finer grid the voxel count is the sphere's volume.
  const auto fine = voxelize(mesh, image::GridGeometry{{80, 80, 80}, Vec3(0.3, 0.3, 0.3), Vec3::Zero(), Mat3::Identity()});
  const double vol = double(std::count(fine.data().begin(), fine.data().end(), 1)) * 0.027;
  EXPECT_TRUE(rel_near(vol, 4.0 / 3.0 * kPi * 729.0, 0.01));
  // Wherever the signed distance is clearly away from the surface, both inside rules agree;
  // single-threaded and threaded rows give the same mask.
  const auto field = signed_distance(mesh, fine.like<float>(0.0f));
  std::int64_t compared = 0;
  for (std::size_t l = 0; l < fine.data().size(); ++l) {
    if (std::abs(field.data()[l]) < 1e-3f) continue;
    ++compared;
    ASSERT_EQ(fine.data()[l], field.data()[l] < 0.0f ? 1 : 0) << "voxel " << l;
  }
  EXPECT_GT(compared, 500000);
  EXPECT_EQ(voxelize(mesh, fine, {.threaded = false}).data(), fine.data());
  geometry::TriangleMesh bad = mesh;
  bad.triangles[0][1] = 1 << 30;
  EXPECT_THROW((void)voxelize(bad, fine), InvalidInput);
  bad = mesh;
  bad.vertices[3].x() = std::nan("");
  EXPECT_THROW((void)voxelize(bad, fine), InvalidInput);
}

}  // namespace ido::meshing

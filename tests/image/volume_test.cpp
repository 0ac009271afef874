// SPDX-License-Identifier: Apache-2.0
#include "ido/image/volume.h"

#include <bit>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido::image {
using test::near;
using test::rotation;


TEST(Volume, IndexToWorldFollowsItkFormula) {
  const Mat3 d = rotation(0.3, -0.2, 1.1);
  Volume<float> v({10, 20, 30}, Vec3(0.5, 0.8, 2.0), Vec3(-10, 5, 100), d);
  const Vec3 idx(3, 7, 11);
  const Vec3 expected = Vec3(-10, 5, 100) + d * Vec3(3 * 0.5, 7 * 0.8, 11 * 2.0);
  EXPECT_LT((v.index_to_world(idx) - expected).norm(), 1e-12);
}

TEST(Volume, WorldToIndexInvertsIndexToWorld) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-50, 50);
  Volume<float> v({8, 8, 8}, Vec3(0.7, 1.3, 2.5), Vec3(1, 2, 3), rotation(0.5, 0.1, -0.4));
  for (int t = 0; t < 100; ++t) {
    const Vec3 w(u(rng), u(rng), u(rng));
    EXPECT_LT((v.index_to_world(v.world_to_index(w)) - w).norm(), 1e-10);
  }
}

TEST(Volume, TrilinearReproducesLinearFunctionsExactly) {
  // A linear function of the index is reproduced exactly by trilinear interpolation.
  Volume<double> v({6, 7, 8}, Vec3(1.0, 0.5, 2.0), Vec3(3, -1, 0));
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 7; ++j)
      for (int i = 0; i < 6; ++i) v(i, j, k) = 2.0 * i - 3.0 * j + 0.5 * k + 1.0;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ui(0, 5), uj(0, 6), uk(0, 7);
  for (int t = 0; t < 200; ++t) {
    const Vec3 idx(ui(rng), uj(rng), uk(rng));
    EXPECT_TRUE(near(v.sample_index(idx), 2.0 * idx.x() - 3.0 * idx.y() + 0.5 * idx.z() + 1.0, 1e-12));
    EXPECT_TRUE(near(v.sample(v.index_to_world(idx)), v.sample_index(idx), 1e-9));
  }
}

TEST(Volume, BoundaryModes) {
  Volume<float> v({4, 4, 4}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), 5.0f);
  EXPECT_DOUBLE_EQ(v.sample(Vec3(-10, 1, 1), Boundary::Clamp), 5.0);
  EXPECT_DOUBLE_EQ(v.sample(Vec3(-10, 1, 1), Boundary::Constant, -1000.0), -1000.0);
  EXPECT_DOUBLE_EQ(v.sample(Vec3(-0.4, 1, 1), Boundary::Constant, -1000.0), 5.0);
  EXPECT_DOUBLE_EQ(v.sample(Vec3(3.0, 3.0, 3.0), Boundary::Constant, -1000.0), 5.0);
}

TEST(Volume, SingleVoxelThickAxisSamples) {
  Volume<float> v({4, 4, 1}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), 2.0f);
  EXPECT_DOUBLE_EQ(v.sample(Vec3(1.5, 1.5, 0.0)), 2.0);
}

// Trilinear interpolation written out with floor(), as sample_index did before it truncated
// instead (the clamped index is never negative, where the two agree).
namespace {
double reference_sample(const image::Volume<float>& v, const Vec3& world, image::Boundary boundary) {
  if (v.data().empty()) return 0.0;
  const Vec3 index = v.world_to_index(world);
  double f[3];
  std::int64_t i0[3], i1[3];
  for (int a = 0; a < 3; ++a) {
    const double hi = double(v.size(a) - 1);
    double x = index[a];
    if (!(x >= 0.0 && x <= hi)) {
      if (boundary == image::Boundary::Constant && !(x >= -0.5 && x <= hi + 0.5)) return 0.0;
      x = std::clamp(std::isnan(x) ? 0.0 : x, 0.0, hi);
    }
    i0[a] = std::min<std::int64_t>(static_cast<std::int64_t>(std::floor(x)), std::max<std::int64_t>(v.size(a) - 2, 0));
    f[a] = x - double(i0[a]);
    i1[a] = std::min(i0[a] + 1, v.size(a) - 1);
  }
  auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return static_cast<double>(v(i, j, k)); };
  const double c00 = at(i0[0], i0[1], i0[2]) * (1 - f[0]) + at(i1[0], i0[1], i0[2]) * f[0];
  const double c10 = at(i0[0], i1[1], i0[2]) * (1 - f[0]) + at(i1[0], i1[1], i0[2]) * f[0];
  const double c01 = at(i0[0], i0[1], i1[2]) * (1 - f[0]) + at(i1[0], i0[1], i1[2]) * f[0];
  const double c11 = at(i0[0], i1[1], i1[2]) * (1 - f[0]) + at(i1[0], i1[1], i1[2]) * f[0];
  const double c0 = c00 * (1 - f[1]) + c10 * f[1];
  const double c1 = c01 * (1 - f[1]) + c11 * f[1];
  return c0 * (1 - f[2]) + c1 * f[2];
}
}  // namespace

// Same bits as the floor() formulation — inside, on and beyond the border, both boundary
// modes, on a rotated anisotropic grid and on a grid one voxel thick — so results computed
// before the change (e.g. segmentations) are reproduced exactly.
TEST(Volume, SampleMatchesTheFloorFormulationBitForBit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 12.0);
  std::normal_distribution<float> value(100.0f, 40.0f);
  for (const Index3& size : {Index3{9, 7, 5}, Index3{6, 1, 4}}) {
    image::Volume<float> v(size, Vec3(0.8, 0.9, 1.4), Vec3(-2.0, 1.0, 0.5));
    v.set_direction(test::rotation(0.2, 0.4, -0.3));
    for (float& x : v.data()) x = value(rng);
    for (const auto boundary : {image::Boundary::Clamp, image::Boundary::Constant}) {
      std::int64_t differ = 0;
      for (int q = 0; q < 20000; ++q) {
        const Vec3 p(u(rng), u(rng), u(rng));
        differ += std::bit_cast<std::uint64_t>(reference_sample(v, p, boundary)) !=
                  std::bit_cast<std::uint64_t>(v.sample(p, boundary));
      }
      for (std::int64_t k = 0; k < size[2]; ++k)
        for (std::int64_t i = 0; i < size[0]; ++i) {
          const Vec3 p = v.index_to_world(Vec3(double(i), double(size[1] - 1), double(k)));
          differ += std::bit_cast<std::uint64_t>(reference_sample(v, p, boundary)) !=
                    std::bit_cast<std::uint64_t>(v.sample(p, boundary));
        }
      EXPECT_EQ(differ, 0);
    }
  }
}

TEST(Volume, RejectsBadGeometry) {
  EXPECT_THROW(Volume<float>({2, 2, 2}, Vec3(1, 0, 1)), InvalidInput);
  EXPECT_THROW(Volume<float>({2, 2, 2}, Vec3(1, 1, 1), Vec3::Zero(), Mat3::Zero()), InvalidInput);
  EXPECT_THROW(Volume<float>({-1, 2, 2}), InvalidInput);
  Volume<float> v({2, 2, 2});
  EXPECT_THROW((void)v.at(2, 0, 0), InvalidInput);
}

TEST(Volume, LikeKeepsGrid) {
  Volume<std::int16_t> ct({5, 6, 7}, Vec3(0.9, 0.9, 2), Vec3(1, 2, 3), rotation(0, 0, 0.5));
  const auto mask = ct.like<std::uint8_t>(1);
  EXPECT_TRUE(ct.same_grid(mask));
  EXPECT_EQ(mask.voxel_count(), 5u * 6u * 7u);
}

}  // namespace ido::image

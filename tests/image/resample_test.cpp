// SPDX-License-Identifier: Apache-2.0
#include "ido/image/resample.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido::image {
using test::near;
using test::rotation;

namespace {
double linear(const Vec3& w) { return 5.0 + 1.5 * w.x() - 0.5 * w.y() + 0.25 * w.z(); }
}  // namespace

TEST(Resample, IdentityGridIsExact) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1000, 1000);
  Volume<float> v({13, 9, 7}, Vec3(0.7, 1.1, 2.3), Vec3(4, 5, -6), rotation(0.1, 0.2, 0.3));
  for (float& x : v.data()) x = u(rng);
  const auto r = resample_linear(v, v);
  EXPECT_TRUE(r.same_grid(v));
  EXPECT_EQ(r.data(), v.data());
  Volume<std::uint8_t> m = v.like<std::uint8_t>();
  for (std::size_t n = 0; n < m.data().size(); ++n) m.data()[n] = std::uint8_t(n % 7);
  EXPECT_EQ(resample_nearest(m, m).data(), m.data());
}

TEST(Resample, ShiftedRotatedGridOfLinearFieldIsExact) {
  Volume<float> src({30, 30, 30}, Vec3(1.0, 0.8, 1.2), Vec3(-10, -8, -12), rotation(0.2, -0.1, 0.4));
  for (std::int64_t k = 0; k < 30; ++k)
    for (std::int64_t j = 0; j < 30; ++j)
      for (std::int64_t i = 0; i < 30; ++i)
        src(i, j, k) = float(linear(src.index_to_world(Vec3(double(i), double(j), double(k)))));
  // A smaller, shifted and differently rotated grid whose centres all lie inside src.
  const Vec3 centre = src.index_to_world(Vec3(14.5, 14.5, 14.5));
  const Mat3 d = rotation(-0.3, 0.25, 0.1);
  const Vec3 sp(0.55, 0.9, 0.7);
  const GridGeometry g{{16, 12, 14}, sp, centre - d * (sp.cwiseProduct(Vec3(7.5, 5.5, 6.5))), d};
  const auto r = resample_linear(src, g);
  for (std::int64_t k = 0; k < 14; ++k)
    for (std::int64_t j = 0; j < 12; ++j)
      for (std::int64_t i = 0; i < 16; ++i)
        ASSERT_TRUE(near(r(i, j, k), linear(r.index_to_world(Vec3(double(i), double(j), double(k)))), 1e-3));
}

TEST(Resample, NearestPicksContainingVoxelAndOutsideValue) {
  Volume<std::uint8_t> m({4, 4, 4}, Vec3(2, 2, 2));
  m(1, 2, 3) = 7;
  // A 1 mm grid over the 2 mm one: many target centres fall exactly on voxel borders.
  const GridGeometry fine{{10, 10, 10}, Vec3(1, 1, 1), Vec3(-1, -1, -1), Mat3::Identity()};
  const auto r = resample_nearest(m, fine, {.outside_value = 9});
  for (std::int64_t k = 0; k < 10; ++k)
    for (std::int64_t j = 0; j < 10; ++j)
      for (std::int64_t i = 0; i < 10; ++i) {
        const Vec3 w = r.index_to_world(Vec3(double(i), double(j), double(k)));
        const Vec3 idx = w / 2.0;
        const bool outside = (idx.array() < -0.5).any() || (idx.array() >= 3.5).any();
        // Voxel n owns indices in [n − ½, n + ½) (ties round half up).
        const bool in_voxel = std::floor(idx.x() + 0.5) == 1 && std::floor(idx.y() + 0.5) == 2 &&
                              std::floor(idx.z() + 0.5) == 3;
        const int expected = outside ? 9 : (in_voxel ? 7 : 0);
        ASSERT_EQ(int(r(i, j, k)), expected) << i << " " << j << " " << k;
      }
  EXPECT_THROW((void)resample_nearest(Volume<std::uint8_t>(), fine), InvalidInput);
}

}  // namespace ido::image

// SPDX-License-Identifier: Apache-2.0
#include "ido/image/filters.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido::image {
using test::near;
using test::rotation;
using test::rel_near;


TEST(GaussianSmooth, ConstantStaysConstant) {
  Volume<float> v({17, 12, 9}, Vec3(0.7, 1.3, 2.1), Vec3::Zero(), Mat3::Identity(), 42.5f);
  const auto s = gaussian_smooth(v, 2.5);
  for (float x : s.data()) ASSERT_TRUE(near(x, 42.5, 1e-4));
}

TEST(GaussianSmooth, DeltaIntegratesToOneWithPerAxisVarianceInMillimetres) {
  const Vec3 spacing(0.5, 1.0, 2.0);
  const double sigma_mm = 3.0;
  Volume<float> v({61, 41, 31}, spacing, Vec3(5, -2, 7), rotation(0.2, 0.5, -0.3), 0.f);
  const std::int64_t ci = 30, cj = 20, ck = 15;
  v(ci, cj, ck) = 1.f;
  const auto s = gaussian_smooth(v, sigma_mm, {.threaded = true});
  double mass = 0;
  Vec3 mean = Vec3::Zero(), var = Vec3::Zero();
  for (std::int64_t k = 0; k < 31; ++k)
    for (std::int64_t j = 0; j < 41; ++j)
      for (std::int64_t i = 0; i < 61; ++i) {
        const double w = s(i, j, k);
        const Vec3 d((i - ci) * spacing[0], (j - cj) * spacing[1], (k - ck) * spacing[2]);
        mass += w;
        mean += w * d;
        var += w * d.cwiseProduct(d);
      }
  EXPECT_TRUE(near(mass, 1.0, 1e-5));
  EXPECT_LT(mean.norm(), 1e-5);
  // Sampled Gaussians with σ ≥ 1.5 voxels have variance σ² to better than 0.1 %.
  for (int a = 0; a < 3; ++a) EXPECT_TRUE(rel_near(var[a], sigma_mm * sigma_mm, 2e-3)) << a;
}

// The textbook form, one voxel at a time: along each axis in turn (i, j, k; an axis of one
// voxel or a negligible σ skipped), the clamped neighbours weighted from the kernel's first
// tap to its last. gaussian_smooth vectorises and reuses buffers, but must give these floats.
Volume<float> smooth_voxel_by_voxel(const Volume<float>& v, const Vec3& sigma_mm) {
  Volume<float> cur = v;
  for (int a = 0; a < 3; ++a) {
    const double sigma_vox = sigma_mm[a] / v.spacing()[a];
    if (v.size(a) < 2 || sigma_vox < 1e-3) continue;
    const std::vector<float> kernel = gaussian_kernel(sigma_vox, 4.0);
    const auto half = static_cast<std::int64_t>(kernel.size() / 2);
    Volume<float> next = cur.like<float>();
    for (std::int64_t k = 0; k < v.size(2); ++k)
      for (std::int64_t j = 0; j < v.size(1); ++j)
        for (std::int64_t i = 0; i < v.size(0); ++i) {
          float acc = 0.f;
          for (std::int64_t m = 0; m < std::int64_t(kernel.size()); ++m) {
            std::int64_t idx[3] = {i, j, k};
            idx[a] = std::clamp<std::int64_t>(idx[a] + m - half, 0, v.size(a) - 1);
            acc += kernel[std::size_t(m)] * cur(idx[0], idx[1], idx[2]);
          }
          next(i, j, k) = acc;
        }
    cur = std::move(next);
  }
  return cur;
}

TEST(GaussianSmooth, EqualsTheVoxelByVoxelConvolutionBitForBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1000, 3000);
  // Three passes, two (σ negligible along k), one (only i has more than one voxel), rows of
  // lengths that do not fill a vector register.
  const struct {
    Index3 size;
    Vec3 spacing, sigma;
  } cases[] = {{{37, 21, 13}, Vec3(0.98, 0.98, 2.0), Vec3::Constant(0.69)},
               {{19, 17, 9}, Vec3(0.8, 1.1, 1.4), Vec3(0.9, 1.6, 0.0)},
               {{45, 1, 1}, Vec3(1, 1, 1), Vec3::Constant(1.3)},
               {{3, 5, 30}, Vec3(1.5, 0.5, 0.7), Vec3::Constant(2.2)}};
  for (const auto& c : cases) {
    Volume<float> v(c.size, c.spacing, Vec3(1, 2, 3), rotation(0.1, -0.4, 0.3));
    for (float& x : v.data()) x = u(rng);
    const auto want = smooth_voxel_by_voxel(v, c.sigma);
    for (bool threaded : {false, true}) {
      const auto got = gaussian_smooth(v, c.sigma, {.threaded = threaded});
      ASSERT_TRUE(got.same_grid(v));
      ASSERT_EQ(got.data(), want.data()) << c.size[0] << "x" << c.size[1] << "x" << c.size[2];
    }
  }
}

// The textbook gradient, one voxel at a time: central differences inside, one-sided on the
// border, none along an axis of one voxel; mapped to world axes by J^{-T}.
Volume<float> gradient_magnitude_voxel_by_voxel(const Volume<float>& v) {
  Volume<float> out = v.like<float>();
  const Mat3 jit = v.world_to_index_matrix().transpose();
  for (std::int64_t k = 0; k < v.size(2); ++k)
    for (std::int64_t j = 0; j < v.size(1); ++j)
      for (std::int64_t i = 0; i < v.size(0); ++i) {
        Vec3 g;
        for (int a = 0; a < 3; ++a) {
          const std::int64_t n = v.size(a);
          std::int64_t lo[3] = {i, j, k}, hi[3] = {i, j, k};
          lo[a] = std::max<std::int64_t>(lo[a] - 1, 0);
          hi[a] = std::min<std::int64_t>(hi[a] + 1, n - 1);
          g[a] = n < 2 ? 0.0
                       : (double(v(hi[0], hi[1], hi[2])) - double(v(lo[0], lo[1], lo[2]))) / double(hi[a] - lo[a]);
        }
        out(i, j, k) = static_cast<float>(Vec3(jit * g).norm());
      }
  return out;
}

TEST(GradientMagnitude, EqualsTheVoxelByVoxelDifferencesBitForBit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1000, 3000);
  for (const Index3 size : {Index3{17, 9, 6}, Index3{2, 5, 4}, Index3{7, 1, 5}, Index3{6, 4, 1}, Index3{3, 3, 3}}) {
    Volume<float> v(size, Vec3(0.8, 1.1, 2.0), Vec3(1, 2, 3), rotation(0.3, -0.2, 0.5));
    for (float& x : v.data()) x = u(rng);
    const auto want = gradient_magnitude_voxel_by_voxel(v);
    for (bool threaded : {false, true})
      ASSERT_EQ(gradient_magnitude(v, threaded).data(), want.data()) << size[0] << "x" << size[1] << "x" << size[2];
  }
}

TEST(Volume, TakesOverDecodedVoxelsAndChecksTheirCount) {
  std::vector<float> voxels(4 * 3 * 2);
  for (std::size_t n = 0; n < voxels.size(); ++n) voxels[n] = float(n);
  const float* where = voxels.data();
  const Volume<float> v({4, 3, 2}, std::move(voxels), Vec3(0.5, 1, 2), Vec3(1, 2, 3), rotation(0.3, 0.1, -0.2));
  EXPECT_EQ(v.data().data(), where);  // no copy
  EXPECT_EQ(v(3, 2, 1), 23.f);
  EXPECT_EQ(v(1, 2, 0), 9.f);
  EXPECT_TRUE(v.same_grid(Volume<float>({4, 3, 2}, Vec3(0.5, 1, 2), Vec3(1, 2, 3), rotation(0.3, 0.1, -0.2))));
  EXPECT_THROW(Volume<float>({4, 3, 2}, std::vector<float>(23), Vec3::Ones(), Vec3::Zero(), Mat3::Identity()),
               InvalidInput);
  EXPECT_THROW(Volume<float>({4, 3, 2}, std::vector<float>(24), Vec3(1, 0, 1), Vec3::Zero(), Mat3::Identity()),
               InvalidInput);
}

TEST(GaussianSmooth, ThreadedEqualsSerialAndRejectsBadSigma) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-100, 100);
  Volume<float> v({23, 19, 11}, Vec3(1, 1.5, 0.8));
  for (float& x : v.data()) x = u(rng);
  const auto a = gaussian_smooth(v, 1.7, {.threaded = false});
  const auto b = gaussian_smooth(v, 1.7, {.threaded = true});
  EXPECT_EQ(a.data(), b.data());
  EXPECT_TRUE(a.same_grid(v));
  EXPECT_EQ(gaussian_smooth(v, 0.0).data(), v.data());
  EXPECT_THROW((void)gaussian_smooth(v, -1.0), InvalidInput);
  EXPECT_THROW((void)gaussian_smooth(v, NAN), InvalidInput);
}

TEST(Gradient, LinearFieldIsExactInWorldFrame) {
  const Mat3 d = rotation(0.3, -0.7, 1.2);
  Volume<float> v({9, 8, 7}, Vec3(0.6, 1.1, 1.9), Vec3(3, -4, 5), d);
  const Vec3 g(2.0, -1.5, 0.75);  // intensity per mm
  for (std::int64_t k = 0; k < 7; ++k)
    for (std::int64_t j = 0; j < 8; ++j)
      for (std::int64_t i = 0; i < 9; ++i)
        v(i, j, k) = float(10.0 + g.dot(v.index_to_world(Vec3(double(i), double(j), double(k)))));
  const auto grad = gradient(v);
  const auto mag = gradient_magnitude(v);
  for (std::int64_t k = 0; k < 7; ++k)
    for (std::int64_t j = 0; j < 8; ++j)
      for (std::int64_t i = 0; i < 9; ++i) {  // borders included (one-sided differences)
        ASSERT_LT((grad(i, j, k).cast<double>() - g).norm(), 2e-4);
        ASSERT_TRUE(near(mag(i, j, k), g.norm(), 2e-4));
      }
}

TEST(RobustStats, MedianAndMad) {
  EXPECT_THROW((void)robust_stats({}), InvalidInput);
  const auto s = robust_stats({1, 2, 3, 4, 100});
  EXPECT_DOUBLE_EQ(s.median, 3.0);
  EXPECT_DOUBLE_EQ(s.mad, 1.0);  // |dev| = 2 1 0 1 97
}

TEST(RobustStats, BallIgnoresOutliersAndUsesWorldRadius) {
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(350.0, 20.0);
  Volume<float> v({40, 40, 20}, Vec3(0.5, 0.5, 1.0), Vec3(-10, -10, 0));
  for (float& x : v.data()) x = float(noise(rng));
  // Outliers in 5 % of the voxels must not move the median much.
  for (std::size_t n = 0; n < v.data().size(); n += 20) v.data()[n] = 3000.f;
  const Vec3 c = v.index_to_world(Vec3(20, 20, 10));
  const auto s = robust_stats_in_ball(v, c, 4.0);
  // Ball volume 268 mm³ / 0.25 mm³ per voxel ≈ 1072 voxels.
  EXPECT_NEAR(double(s.count), 4.0 / 3.0 * kPi * 64 / 0.25, 40.0);
  EXPECT_TRUE(near(s.median, 350.0, 5.0));
  EXPECT_TRUE(rel_near(s.sigma(), 20.0 * 1.05, 0.12));  // 5 % outliers inflate MAD slightly
  EXPECT_THROW((void)robust_stats_in_ball(v, Vec3(1000, 0, 0), 2.0), InvalidInput);
  EXPECT_EQ(robust_stats_in_ball(v, c, 0.0).count, 1u);
}

}  // namespace ido::image

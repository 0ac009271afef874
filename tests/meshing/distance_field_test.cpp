// SPDX-License-Identifier: Apache-2.0
// The exact Euclidean distance transform (Felzenszwalb & Huttenlocher) against brute force
// on random anisotropic masks, and the signed field's documented values.
#include "ido/meshing/distance_field.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/random_mask.h"
#include "support/test_support.h"

namespace ido::meshing {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Distance (mm) from voxel (i, j, k) to the nearest voxel centre where @p pick holds, by
// trying every voxel.
template <class Pick>
double brute_distance(const image::Volume<std::uint8_t>& m, std::int64_t i, std::int64_t j, std::int64_t k, Pick pick) {
  double best = std::numeric_limits<double>::infinity();
  const Vec3& s = m.spacing();
  for (std::int64_t c = 0; c < m.size(2); ++c)
    for (std::int64_t b = 0; b < m.size(1); ++b)
      for (std::int64_t a = 0; a < m.size(0); ++a)
        if (pick(m(a, b, c))) best = std::min(best, Vec3(double(a - i) * s.x(), double(b - j) * s.y(), double(c - k) * s.z()).norm());
  return best;
}

TEST(DistanceField, DistanceToMaskEqualsBruteForceOnRandomMasks) {
  std::mt19937 rng(17);
  int masks_with_voxels = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const auto mask = test::random_mask(rng, 9, trial % 4 == 0 ? 0.02 : 0.15);
    const auto d = distance_to_mask(mask, {.threaded = trial % 2 == 0});
    ASSERT_EQ(d.size(0), mask.size(0));
    ASSERT_EQ(d.size(1), mask.size(1));
    ASSERT_EQ(d.size(2), mask.size(2));
    EXPECT_EQ(d.spacing(), mask.spacing());
    bool any = false;
    for (std::int64_t k = 0; k < mask.size(2); ++k)
      for (std::int64_t j = 0; j < mask.size(1); ++j)
        for (std::int64_t i = 0; i < mask.size(0); ++i) {
          const double want = brute_distance(mask, i, j, k, [](std::uint8_t x) { return x != 0; });
          any = any || mask(i, j, k) != 0;
          if (std::isinf(want)) {
            ASSERT_EQ(d(i, j, k), kInf) << "trial " << trial;
          } else {
            ASSERT_TRUE(test::near(d(i, j, k), want, 1e-5 * (1.0 + want))) << "trial " << trial << " at " << i << "," << j << "," << k;
          }
          if (mask(i, j, k) != 0) {
            ASSERT_EQ(d(i, j, k), 0.0f);
          }
        }
    masks_with_voxels += any ? 1 : 0;
  }
  EXPECT_GT(masks_with_voxels, 30);
}

TEST(DistanceField, ThreadedAndSerialAreBitForBitEqual) {
  std::mt19937 rng(3);
  image::Volume<std::uint8_t> mask({40, 33, 21}, Vec3(0.7, 1.1, 2.5));
  std::bernoulli_distribution b(0.01);
  for (auto& x : mask.data()) x = b(rng);
  EXPECT_EQ(distance_to_mask(mask, {.threaded = true}).data(), distance_to_mask(mask, {.threaded = false}).data());
  EXPECT_EQ(signed_distance_from_mask(mask, {.threaded = true}).data(),
            signed_distance_from_mask(mask, {.threaded = false}).data());
}

TEST(DistanceField, SignedDistanceIsNegativeInsideAndHalfWayAcrossTheBoundary) {
  // A box of voxels [3, 8] × [2, 6] × [1, 4] in a 12 × 10 × 7 grid, spacing (0.5, 1, 2) mm.
  const Vec3 sp(0.5, 1.0, 2.0);
  image::Volume<std::uint8_t> mask({12, 10, 7}, sp);
  auto in_box = [](std::int64_t i, std::int64_t j, std::int64_t k) { return i >= 3 && i <= 8 && j >= 2 && j <= 6 && k >= 1 && k <= 4; };
  for (std::int64_t k = 0; k < 7; ++k)
    for (std::int64_t j = 0; j < 10; ++j)
      for (std::int64_t i = 0; i < 12; ++i) mask(i, j, k) = in_box(i, j, k) ? 1 : 0;
  const auto f = signed_distance_from_mask(mask);
  for (std::int64_t k = 0; k < 7; ++k)
    for (std::int64_t j = 0; j < 10; ++j)
      for (std::int64_t i = 0; i < 12; ++i) {
        const bool in = in_box(i, j, k);
        const double want = in ? -brute_distance(mask, i, j, k, [](std::uint8_t x) { return x == 0; })
                               : brute_distance(mask, i, j, k, [](std::uint8_t x) { return x != 0; });
        ASSERT_TRUE(test::near(f(i, j, k), want, 1e-5)) << i << "," << j << "," << k;
        ASSERT_EQ(f(i, j, k) < 0.0f, in);
      }
  // Face neighbours of opposite label: opposite signs, magnitude the spacing along their axis.
  EXPECT_EQ(f(3, 4, 2), -0.5f);
  EXPECT_EQ(f(2, 4, 2), 0.5f);
  EXPECT_EQ(f(5, 2, 2), -1.0f);
  EXPECT_EQ(f(5, 1, 2), 1.0f);
  EXPECT_EQ(f(5, 4, 0), 2.0f);
  EXPECT_EQ(f(5, 4, 1), -1.5f);  // inside, the nearest outside voxel is 3 voxels away along i
  // The unsigned distance agrees outside and is 0 inside.
  const auto d = distance_to_mask(mask);
  EXPECT_EQ(d(0, 0, 0), f(0, 0, 0));
  EXPECT_EQ(d(5, 4, 2), 0.0f);
  // Diagonal: from voxel (0, 0, 0) to the corner (3, 2, 1).
  EXPECT_TRUE(test::near(d(0, 0, 0), Vec3(3 * 0.5, 2 * 1.0, 1 * 2.0).norm(), 1e-6));
}

TEST(DistanceField, EmptyFullAndVoxellessMasks) {
  image::Volume<std::uint8_t> none({5, 4, 3}, Vec3(1, 2, 3));
  const auto none_d = distance_to_mask(none), none_s = signed_distance_from_mask(none);
  for (float v : none_d.data()) EXPECT_EQ(v, kInf);
  for (float v : none_s.data()) EXPECT_EQ(v, kInf);
  image::Volume<std::uint8_t> all({5, 4, 3}, Vec3(1, 2, 3), Vec3::Zero(), Mat3::Identity(), 1);
  const auto all_d = distance_to_mask(all), all_s = signed_distance_from_mask(all);
  for (float v : all_d.data()) EXPECT_EQ(v, 0.0f);
  for (float v : all_s.data()) EXPECT_EQ(v, -kInf);
  // A single voxel: the distance to it grows with the spacing along each axis.
  image::Volume<std::uint8_t> one({1, 1, 1}, Vec3(1, 1, 1), Vec3::Zero(), Mat3::Identity(), 1);
  EXPECT_EQ(distance_to_mask(one).data()[0], 0.0f);
  for (auto fn : {&distance_to_mask, &signed_distance_from_mask}) {
    try {
      (void)fn(image::Volume<std::uint8_t>{}, {});
      FAIL() << "empty mask accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace ido::meshing

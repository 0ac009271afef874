// SPDX-License-Identifier: Apache-2.0
// The balloon's intensity model: the band, the inflation speed, and the estimate at the seeds.
#include "ido/segment/intensity_model.h"

#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"

namespace ido::segment {
namespace {

TEST(IntensityModel, DepartureAndSpeedFollowTheBand) {
  const IntensityModel sym{.reference = 100, .tolerance = 20, .accept_brighter = false};
  EXPECT_EQ(intensity_departure(130, sym), 30.0);
  EXPECT_EQ(intensity_departure(70, sym), 30.0);
  EXPECT_DOUBLE_EQ(inflation_speed(100, sym), 1.0);   // at the reference: full inflation
  EXPECT_DOUBLE_EQ(inflation_speed(110, sym), 0.5);   // half-way to the band's edge
  EXPECT_DOUBLE_EQ(inflation_speed(120, sym), 0.0);   // at the edge: stops
  EXPECT_LT(inflation_speed(150, sym), 0.0);          // beyond: deflates
  EXPECT_GE(inflation_speed(1e6, sym), -1.0);         // clamped
  const IntensityModel bone{.reference = 100, .tolerance = 20, .accept_brighter = true};
  EXPECT_EQ(intensity_departure(1000, bone), 0.0);  // brighter also belongs
  EXPECT_DOUBLE_EQ(inflation_speed(1000, bone), 1.0);
  EXPECT_EQ(intensity_departure(70, bone), 30.0);
}

TEST(IntensityModel, EstimateRecoversAUniformRegionsLevelAndNoise) {
  // 40^3 voxels of 200 + N(0, 10): the median is the level and 2.5 × 1.4826 × MAD ≈ 2.5 σ.
  image::Volume<float> ct({40, 40, 40}, Vec3(1, 1, 1));
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 10.0f);
  for (float& v : ct.data()) v = 200.0f + noise(rng);
  const IntensityModel m = estimate_intensity_model(ct, {Vec3(20, 20, 20)}, {.radius_mm = 8.0});
  EXPECT_NEAR(m.reference, 200.0, 1.5);
  EXPECT_NEAR(m.tolerance, 25.0, 4.0);
  EXPECT_FALSE(m.accept_brighter);
  // A flat region still gets a usable band: min_tolerance_fraction of the level.
  image::Volume<float> flat({10, 10, 10}, Vec3(1, 1, 1), Vec3::Zero(), Mat3::Identity(), 300.0f);
  EXPECT_DOUBLE_EQ(estimate_intensity_model(flat, {Vec3(5, 5, 5)}).tolerance, 0.05 * 300.0);
  EXPECT_THROW((void)estimate_intensity_model(flat, {}), InvalidInput);
  EXPECT_THROW((void)estimate_intensity_model(flat, {Vec3(50, 5, 5)}), InvalidInput);
}

}  // namespace
}  // namespace ido::segment

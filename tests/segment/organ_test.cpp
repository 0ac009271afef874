// SPDX-License-Identifier: Apache-2.0
// Organ choices and the one place a user's choices become BalloonOptions.
#include "ido/segment/organ.h"

#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"

namespace ido::segment {
namespace {

TEST(Organ, NamesRoundTripAndUnknownNamesListTheChoices) {
  for (Organ o : {Organ::Generic, Organ::Artery, Organ::Vein, Organ::Vertebra}) EXPECT_EQ(parse_organ(organ_name(o)), o);
  try {
    (void)parse_organ("liver");
    FAIL() << "liver was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("generic, artery, vein or vertebra"), std::string::npos) << e.what();
  }
}

TEST(BalloonChoices, DefaultsAreTheOrgansOptions) {
  for (Organ o : {Organ::Generic, Organ::Artery, Organ::Vein, Organ::Vertebra}) {
    BalloonChoices c;
    c.organ = o;
    const BalloonOptions got = balloon_options(c), want = organ_options(o);
    EXPECT_EQ(got.accept_brighter, want.accept_brighter);
    EXPECT_EQ(got.edge_reach_voxels, want.edge_reach_voxels);
    EXPECT_EQ(got.outside_level, want.outside_level);
    EXPECT_EQ(got.leak.separate_neighbours, want.leak.separate_neighbours);
    EXPECT_EQ(got.leak.chamber_factor, want.leak.chamber_factor);
    EXPECT_EQ(got.max_iterations, want.max_iterations);
    EXPECT_EQ(got.estimate.residual_ball_factor, want.estimate.residual_ball_factor);
    EXPECT_FALSE(got.roi_mm.has_value());
  }
}

TEST(BalloonChoices, EachChoiceReachesItsOption) {
  BalloonChoices c;
  c.organ = Organ::Artery;
  c.reference = 300;
  c.tolerance = 40;
  c.bone = true;
  c.white_noise = true;
  c.edge_reach_voxels = 3;
  c.outside_level = 10;
  c.max_iterations = 77;
  c.roi_mm = geometry::Aabb{Vec3(0, 0, 0), Vec3(1, 2, 3)};
  c.leak_control = false;
  c.stop_points_mm = {Vec3(1, 1, 1)};
  c.max_radius_mm = 12;
  const BalloonOptions o = balloon_options(c);
  EXPECT_EQ(o.reference, 300.0);
  EXPECT_EQ(o.tolerance, 40.0);
  EXPECT_TRUE(o.accept_brighter);
  EXPECT_EQ(o.estimate.residual_ball_factor, 5.0);
  EXPECT_EQ(o.edge_reach_voxels, 3.0);
  EXPECT_EQ(o.outside_level, 10.0);
  EXPECT_EQ(o.max_iterations, 77);
  ASSERT_TRUE(o.roi_mm.has_value());
  EXPECT_EQ(o.roi_mm->max, Vec3(1, 2, 3));
  EXPECT_FALSE(o.leak.enabled);
  ASSERT_EQ(o.leak.stop_points_mm.size(), 1u);
  EXPECT_EQ(o.leak.max_radius_mm, 12.0);
  // An edge reach of 0 keeps the organ's own (the artery's 2 voxels).
  c.edge_reach_voxels = 0;
  EXPECT_EQ(balloon_options(c).edge_reach_voxels, organ_options(Organ::Artery).edge_reach_voxels);
}

TEST(BalloonChoices, ErrorsNameTheOptionAsTheCallerSpellsIt) {
  const auto message = [](const BalloonChoices& c, bool cli) {
    try {
      (void)balloon_options(c, cli ? std::function<std::string(std::string_view)>(
                                         [](std::string_view f) { return "--x-" + std::string(f); })
                                   : nullptr);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  BalloonChoices bad_tolerance;
  bad_tolerance.tolerance = -1;
  EXPECT_EQ(message(bad_tolerance, false).rfind("tolerance", 0), 0u) << message(bad_tolerance, false);
  EXPECT_EQ(message(bad_tolerance, true).rfind("--x-tolerance", 0), 0u) << message(bad_tolerance, true);
  BalloonChoices bad_iterations;
  bad_iterations.max_iterations = 0;
  EXPECT_EQ(message(bad_iterations, false).rfind("max_iterations", 0), 0u);
  BalloonChoices bad_reach;
  bad_reach.edge_reach_voxels = -1;
  EXPECT_EQ(message(bad_reach, false).rfind("edge_reach_voxels", 0), 0u);
  BalloonChoices bad_roi;
  bad_roi.roi_mm = geometry::Aabb{Vec3(0, 0, 0), Vec3(0, 1, 1)};  // empty along x
  EXPECT_EQ(message(bad_roi, false).rfind("roi", 0), 0u);
  BalloonChoices bad_radius;
  bad_radius.max_radius_mm = 0;
  EXPECT_EQ(message(bad_radius, false).rfind("max_radius_mm", 0), 0u);
  BalloonChoices bad_level;
  bad_level.outside_level = INFINITY;
  EXPECT_EQ(message(bad_level, false).rfind("outside_level", 0), 0u);
}

}  // namespace
}  // namespace ido::segment

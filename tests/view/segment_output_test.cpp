// SPDX-License-Identifier: Apache-2.0
// What the Segment workspace saves: the report's seeds, organ, surface figures and leak
// controls, and the checks of the output names.
#include "ido/view/segment_output.h"

#include <memory>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "ido/geometry/aabb.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"
#include "support/ball_ct.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(SegmentOutput, ReportRecordsSeedsOrganAndSurfaceFigures) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  const std::vector<Vec3> seeds = {ct->index_to_world(Vec3(16, 15, 14))};
  view::SegmentRequest request{"ct.nii.gz", seeds, segment::Organ::Artery, segment::organ_options(segment::Organ::Artery)};
  const segment::BalloonResult r = segment::segment_balloon(*ct, seeds, request.options);
  const nlohmann::json j = view::segment_report_json(request, r, {"s.stl", "", "r.json"});
  EXPECT_EQ(j["seeds_mm"][0][0].get<double>(), seeds[0].x());
  EXPECT_EQ(j["seeds_mm"][0][2].get<double>(), seeds[0].z());
  EXPECT_EQ(j["organ"], "artery");
  EXPECT_EQ(j["triangles"].get<std::int64_t>(), std::int64_t(r.surface.triangle_count()));
  EXPECT_EQ(j["surface"], "s.stl");
  EXPECT_TRUE(j["mask"].is_null());
  EXPECT_TRUE(j["leak_control"]["stop_points_mm"].empty());
  EXPECT_TRUE(j["leak_control"]["max_radius_mm"].is_null());
  EXPECT_TRUE(j["roi_mm"].is_null());
  // The stop points and radius bound the balloon ran with are listed with the leak control's
  // figures (from its report); the region of interest from the request.
  segment::BalloonResult with_controls = r;
  with_controls.report.stop_points_mm = {Vec3(1.5, -2.25, 40.125)};
  with_controls.report.max_radius_mm = 7.5;
  request.options.roi_mm = geometry::Aabb{Vec3(-1, -2, -3), Vec3(4, 5, 6)};
  const nlohmann::json with_stop = view::segment_report_json(request, with_controls, {});
  EXPECT_EQ(with_stop["leak_control"]["stop_points_mm"], nlohmann::json::parse("[[1.5, -2.25, 40.125]]"));
  EXPECT_EQ(with_stop["leak_control"]["max_radius_mm"].get<double>(), 7.5);
  EXPECT_EQ(with_stop["roi_mm"], nlohmann::json::parse("[[-1, -2, -3], [4, 5, 6]]"));
  EXPECT_THROW(view::check_segment_outputs({"s.txt", "", ""}), InvalidInput);
  EXPECT_THROW(view::check_segment_outputs({"", "m.stl", ""}), InvalidInput);
  EXPECT_NO_THROW(view::check_segment_outputs({"s.ply", "m.nii.gz", "r.json"}));
}

}  // namespace
}  // namespace ido

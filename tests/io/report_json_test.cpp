// SPDX-License-Identifier: Apache-2.0
// The one JSON form of each report (io::to_json): every key documented in docs/reports.md,
// non-finite figures as null, and the CLI's, the pipeline's and Python's forms all built by it.
#include "ido/io/report_json.h"

#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/io/mesh_io.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"
#include "ido/segment/phantom.h"
#include "ido/sim/generators.h"
#include "support/ball_ct.h"
#include "support/test_support.h"

namespace ido {
namespace {

std::string reports_doc() {
  std::ifstream in(test::source_dir() / "docs" / "reports.md");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every key of @p j (and of its nested objects, and of objects inside its arrays) appears in
// the reports page as `key`.
void expect_documented(const io::Json& j, const std::string& doc, const std::string& where) {
  if (j.is_array()) {
    for (const auto& e : j) expect_documented(e, doc, where);
    return;
  }
  if (!j.is_object()) return;
  for (const auto& [k, v] : j.items()) {
    EXPECT_NE(doc.find("`" + k + "`"), std::string::npos) << where << ": key '" << k << "' is not in docs/reports.md";
    expect_documented(v, doc, where + "." + k);
  }
}

TEST(ReportJson, EveryKeyOfEveryReportIsDocumented) {
  const std::string doc = reports_doc();
  ASSERT_FALSE(doc.empty());
  // A real balloon run, so the leak-control block has events and markers to describe.
  const auto ph = segment::make_phantom(segment::PhantomKind::Sphere);
  const auto run = segment::segment_balloon(ph.ct_hu, {ph.seeds_mm.front()});
  segment::BalloonReport rep = run.report;
  rep.leaks.push_back({segment::LeakCause::Chamber, Vec3(1, 2, 3), 7, 12.0, 1.95});
  rep.neighbour_markers_mm.push_back(Vec3(4, 5, 6));
  expect_documented(io::to_json(rep), doc, "balloon");
  expect_documented(io::to_json(geometry::check_mesh(run.surface)), doc, "mesh checks");
  expect_documented(io::to_json(geometry::TetMeshReport{}), doc, "tet checks");
  expect_documented(io::to_json(segment::SegmentationScores{}), doc, "scores");
  sim::EnergyReport e;
  e.kinetic_mj = 1;
  e.elastic_mj = {2, 3};
  e.model_kinds = {"mass_spring", "linear_fem"};
  expect_documented(io::to_json(e), doc, "energy");
}

TEST(ReportJson, FiguresKeepTheirValuesAndNonFiniteOnesAreNull) {
  segment::SegmentationScores s;
  s.dice = 0.5;
  s.hd95_mm = 2.0;
  s.hd_mm = INFINITY;
  s.volume_ratio = NAN;
  s.resampled = true;
  const io::Json j = io::to_json(s);
  EXPECT_EQ(j["dice"].get<double>(), 0.5);
  EXPECT_EQ(j["hd95_mm"].get<double>(), 2.0);
  EXPECT_TRUE(j["hausdorff_mm"].is_null());
  EXPECT_TRUE(j["volume_ratio"].is_null());
  EXPECT_TRUE(j["resampled_to_truth_grid"].get<bool>());

  sim::EnergyReport e;
  e.kinetic_mj = 1.5;
  e.gravitational_mj = -0.25;
  e.elastic_mj = {2.0, 3.0};
  e.model_kinds = {"mass_spring", "linear_fem"};
  const io::Json k = io::to_json(e);
  EXPECT_EQ(k["elastic_mj"].get<double>(), 5.0);
  EXPECT_EQ(k["total_mj"].get<double>(), 6.25);
  ASSERT_EQ(k["per_model"].size(), 2u);
  EXPECT_EQ(k["per_model"][1]["model"], "linear_fem");
  EXPECT_EQ(k["per_model"][1]["elastic_mj"].get<double>(), 3.0);

  segment::BalloonReport b;
  b.chamber_radius_mm = INFINITY;
  b.leaks.push_back({segment::LeakCause::StopPoint, Vec3(1, 2, 3), 9, 4.0, 1.1});
  const io::Json r = io::to_json(b);
  EXPECT_TRUE(r["leak_control"]["chamber_radius_mm"].is_null());
  EXPECT_EQ(r["leak_control"]["events"][0]["cause"], "stop_point");
  EXPECT_EQ(r["leak_control"]["events"][0]["position_mm"][2].get<double>(), 3.0);
}

// The mesh checks of `ido info --json` are the library's form, key for key and value for value.
TEST(ReportJson, InfoChecksAreTheLibrarysForm) {
  const auto ph = segment::make_phantom(segment::PhantomKind::Sphere);
  const auto run = segment::segment_balloon(ph.ct_hu, {ph.seeds_mm.front()});
  const auto dir = test::scratch_dir("report-json-info");
  const auto stl = dir / "s.stl";
  io::write_triangle_mesh(stl, run.surface);
  const auto r = test::run_tool("info --json " + stl.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const io::Json info = io::Json::parse(r.out);
  // The STL stores float coordinates: compare with the checks of the mesh as read back.
  EXPECT_EQ(info["checks"], io::to_json(geometry::check_mesh(io::read_triangle_mesh(stl))));
}

TEST(ReportJson, SegmentReportRecordsTheRequestAndTheSurfaceFigures) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  const std::vector<Vec3> seeds = {ct->index_to_world(Vec3(16, 15, 14))};
  segment::SegmentRequest request{"ct.nii.gz", seeds, segment::Organ::Artery, segment::organ_options(segment::Organ::Artery)};
  const segment::BalloonResult r = segment::segment_balloon(*ct, seeds, request.options);
  const io::Json j = io::segment_report(request, r, "s.stl", "");
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
  const io::Json with_stop = io::segment_report(request, with_controls, "", "");
  EXPECT_EQ(with_stop["leak_control"]["stop_points_mm"], io::Json::parse("[[1.5, -2.25, 40.125]]"));
  EXPECT_EQ(with_stop["leak_control"]["max_radius_mm"].get<double>(), 7.5);
  EXPECT_EQ(with_stop["roi_mm"], io::Json::parse("[[-1, -2, -3], [4, 5, 6]]"));
  expect_documented(j, reports_doc(), "segment report");
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// The workbench's sessions that need no window: drilling, deformation and the balloon session on
// its worker thread (its result equals segment_balloon()'s bit for bit however it was paused and
// stepped), and the segmentation's outputs. Event scripts, the slice layout, the orbit camera
// and the tetrahedral section have their own test files.

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/geometry/aabb.h"
#include "ido/core/error.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"
#include "ido/drill/shapes.h"
#include "ido/io/scene.h"
#include "ido/view/deform_session.h"
#include "ido/view/drill_session.h"
#include "ido/view/segment_output.h"
#include "ido/view/segment_session.h"
#include "support/ball_ct.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

// ---- a drilling session moved by the window ----------------------------------------------------

TEST(DrillSession, WindowMovedBurrDrillsRecordsItsPathAndHandsOverTheSurface) {
  const geometry::TetMesh block = drill::make_shape("block:16,16,8");
  view::DrillSession session(block, view::drill_cli_options(2.0), 20.0);
  EXPECT_FALSE(session.started());
  EXPECT_TRUE(test::rel_near(session.initial_volume_mm3(), 16.0 * 16 * 8, 1e-9));
  // Down from 2 mm above the top to 3 mm into it, as a mouse drag would, then stop.
  session.start(Vec3(8, 8, 10));
  for (int i = 0; i <= 50; ++i) {
    session.move_tool(Vec3(8, 8, 10 - 0.1 * i));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    (void)session.figures();  // read while the haptic thread writes
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const view::DrillFigures live = session.figures();
  EXPECT_GT(live.ticks, 100u);
  EXPECT_TRUE(live.contact) << "the burr is pressed into the block";
  EXPECT_GT(live.force_n.z(), 0.0) << "the block pushes the burr back up";
  session.stop();
  for (auto t0 = std::chrono::steady_clock::now();
       !session.ended() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(session.ended());
  const double removed = session.stats().removed_volume_mm3;
  EXPECT_GT(removed, 10.0);
  // The final surface handed over encloses what is left.
  std::shared_ptr<const view::DrillSnapshot> last;
  for (int i = 0; i < 100 && !(last && last->final); ++i) last = session.latest_surface();
  ASSERT_TRUE(last && last->final);
  EXPECT_TRUE(test::rel_near(last->volume_mm3, session.initial_volume_mm3() - removed, 1e-6));
  // The path: every tick, times strictly increasing, readable by `ido drill --path`.
  const fs::path csv = test::scratch_dir("drill-session") / "path.csv";
  session.write_path_csv(csv);
  const auto replay = drill::ScriptedTrajectory::load_csv(csv);
  EXPECT_GE(replay.times().size(), live.ticks);
  EXPECT_TRUE(test::near(replay.poses().front().position_mm.z(), 10.0, 0.5));  // the first tick may come after a move
  EXPECT_TRUE(test::near(replay.poses().back().position_mm.z(), 5.0, 1e-9));
}

TEST(DrillSession, ReplayedPathMovesTheToolAndEndsWithThePath) {
  const geometry::TetMesh block = drill::make_shape("block:16,16,8");
  const fs::path dir = test::scratch_dir("drill-replay");
  std::ofstream(dir / "path.csv") << "t,x,y,z\n0,8,8,11\n0.4,8,8,6\n0.6,8,8,6\n";
  const drill::SimulatorOptions options = view::drill_cli_options(2.0);
  auto device = view::load_path_device(dir / "path.csv", options);
  const double duration = device->duration();
  EXPECT_DOUBLE_EQ(duration, 0.6);
  view::DrillSession session(block, options, duration + 1.0, std::move(device));
  ASSERT_NE(session.source(), nullptr);
  session.start(Vec3(0, 0, 50));  // the path, not this, places the tool
  session.move_tool(Vec3(0, 0, 50));  // ignored: the path moves the tool
  for (auto t0 = std::chrono::steady_clock::now();
       !session.ended() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(session.ended()) << "the session ends when the path does";
  EXPECT_GT(session.stats().removed_volume_mm3, 5.0) << "2 mm deep into the block";
  EXPECT_TRUE(test::near((session.tool_pose().position_mm - Vec3(8, 8, 6)).norm(), 0.0, 1e-9));
  session.write_path_csv(dir / "recorded.csv");
  const auto recorded = drill::ScriptedTrajectory::load_csv(dir / "recorded.csv");
  for (std::size_t i = 0; i < recorded.times().size(); i += 50)  // every tick on the path at its time
    EXPECT_TRUE(test::near(recorded.poses()[i].position_mm.z(),
                           std::max(6.0, 11.0 - 5.0 * std::min(recorded.times()[i], 0.4) / 0.4), 1e-9))
        << recorded.times()[i];
  EXPECT_THROW((void)view::load_path_device(dir / "missing.csv", options), IoError);
}

// ---- a scene stepped on its worker thread -------------------------------------------------------

std::shared_ptr<const view::DeformState> wait_steps(view::DeformSession& s, std::int64_t steps) {
  for (auto t0 = std::chrono::steady_clock::now(); std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);) {
    auto st = s.latest();
    if (st && st->steps >= steps && !s.busy()) return st;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return s.latest();
}

TEST(DeformSession, StepsPullsSwitchesIntegratorAndReportsEnergy) {
  io::Scene scene = io::parse_scene(R"({
    "dt_s": 0.001, "steps": 1, "integrator": "implicit_euler",
    "damping": {"rayleigh_mass_per_s": 5.0, "rayleigh_stiffness_s": 0.0},
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [40, 10, 10], "cells": [8, 2, 2]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 2e3, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 11, 11]}]}]})",
                                     "beam", ".");
  const std::vector<Vec3> rest = scene.world.particles().positions();
  view::DeformSession session(std::move(scene));
  EXPECT_FALSE(session.running());
  // Paused: nothing moves until a step is asked for; then exactly those steps.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(session.latest()->steps, 0);
  for (int i = 0; i < 3; ++i) session.step_once();
  auto st = wait_steps(session, 3);
  EXPECT_EQ(st->steps, 3);
  EXPECT_EQ(st->integrator, "implicit_euler");
  ASSERT_EQ(st->von_mises_pa.size(), 1u);
  EXPECT_EQ(st->von_mises_pa[0].size(), session.bodies()[0].rest_mesh.tets.size());
  EXPECT_FALSE(st->history.empty());
  EXPECT_TRUE(test::near(st->history.back().total_mj, 0.0, 1e-12)) << "at rest, no load: no energy";
  // Pull the tip corner 5 mm down for 300 steps: it moves down, the body stores elastic energy.
  std::int32_t tip = -1;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if ((rest[i] - Vec3(40, 0, 10)).norm() < 1e-9) tip = std::int32_t(i);
  ASSERT_GE(tip, 0);
  session.set_grab({true, tip, Vec3(40, 0, 5), 0.1});
  for (int i = 0; i < 300; ++i) session.step_once();
  st = wait_steps(session, 303);
  const double pulled = rest[std::size_t(tip)].z() - st->positions_mm[std::size_t(tip)].z();
  EXPECT_GT(pulled, 2.0);
  EXPECT_GT(st->grab_stiffness_n_per_mm, 0.0);
  EXPECT_LE(st->grab_stiffness_n_per_mm, 0.1);
  EXPECT_GT(st->history.back().elastic_mj, 0.0);
  double vm_max = 0;
  for (double v : st->von_mises_pa[0]) vm_max = std::max(vm_max, v);
  EXPECT_GT(vm_max, 0.0);
  // Released, under another integrator switched between steps, it springs back.
  session.set_grab({});
  session.set_integrator("rk4");
  EXPECT_THROW(session.set_integrator("leapfrog"), InvalidInput);
  session.set_running(true);  // 2 s of simulated time (damping 5/s: e^-5 of the swing is left)
  for (auto t0 = std::chrono::steady_clock::now();
       session.latest()->steps < 2303 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  session.set_running(false);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the worker hands over where it stopped
  st = session.latest();
  EXPECT_EQ(st->integrator, "rk4");
  EXPECT_TRUE(st->error.empty()) << st->error;
  const double back = (st->positions_mm[std::size_t(tip)] - rest[std::size_t(tip)]).norm();
  EXPECT_LT(back, 0.25 * pulled) << "after " << st->steps << " steps";
}

TEST(DeformSession, ParametersChangedBetweenStepsContinueAsTheLibraryWithTheNewValues) {
  // A beam clamped at x = 0 sagging under gravity.
  const std::string text = R"({
    "dt_s": 0.005, "steps": 1, "integrator": "implicit_euler", "gravity_mm_s2": [0, 0, -9806.65],
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [30, 6, 6], "cells": [6, 1, 1]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 7, 7]}]}]})";
  const fs::path file = test::scratch_dir("deform-parameters") / "beam.json";
  std::ofstream(file) << text;
  view::DeformSession session(file);
  // What can change: the material's three numbers and the two damping coefficients.
  const auto& params = session.parameters();
  ASSERT_EQ(params.size(), 5u);
  EXPECT_EQ(params[0].pointer, "/bodies/0/material/youngs_modulus_pa");
  EXPECT_EQ(params[0].value, 1e5);
  EXPECT_EQ(params[2].pointer, "/bodies/0/material/density_kg_m3");
  EXPECT_EQ(params[3].pointer, "/damping/rayleigh_mass_per_s");
  EXPECT_EQ(params[3].value, 0.0);
  std::vector<double> values;
  for (const auto& p : params) values.push_back(p.value);
  EXPECT_THROW(session.set_parameters({1.0}), InvalidInput);

  // 7 steps; then a stiffer, denser, damped beam for 9 more.
  for (int i = 0; i < 7; ++i) session.step_once();
  ASSERT_EQ(wait_steps(session, 7)->steps, 7);
  values[0] = 3e5;
  values[2] = 1500;
  values[3] = 4.0;
  session.set_parameters(values);
  for (int i = 0; i < 9; ++i) session.step_once();
  auto st = wait_steps(session, 16);
  ASSERT_EQ(st->steps, 16);
  EXPECT_EQ(st->parameters, values);
  ASSERT_EQ(st->changes.size(), 3u);
  for (const auto& c : st->changes) EXPECT_EQ(c.step, 7);
  EXPECT_TRUE(st->parameter_error.empty()) << st->parameter_error;

  // The library: 7 steps of the file's scene; the scene with the new values from that state on.
  io::Scene a = io::parse_scene(text, "beam.json", file.parent_path());
  for (int i = 0; i < 7; ++i) a.world.step(a.dt_s);
  nlohmann::json doc = nlohmann::json::parse(text);
  doc["bodies"][0]["material"]["youngs_modulus_pa"] = 3e5;
  doc["bodies"][0]["material"]["density_kg_m3"] = 1500;
  doc["damping"]["rayleigh_mass_per_s"] = 4.0;
  io::Scene b = io::parse_scene(doc.dump(), "beam.json", file.parent_path());
  b.world.particles().positions() = a.world.particles().positions();
  b.world.particles().velocities() = a.world.particles().velocities();
  b.world.set_integrator(a.world.integrator());
  for (int i = 0; i < 9; ++i) {
    b.world.step(b.dt_s);
    a.world.step(a.dt_s);
  }
  EXPECT_TRUE(st->positions_mm == b.world.particles().positions()) << "not the library's run with the new values";
  EXPECT_FALSE(st->positions_mm == a.world.particles().positions()) << "the new values made no difference";
  EXPECT_TRUE(test::near(st->time_s, 16 * 0.005, 1e-12)) << "time goes on across the change";

  // A bad value is refused with the scene reader's message (naming its JSON pointer); the run
  // goes on with the values in use.
  std::vector<double> bad = values;
  bad[1] = 0.6;
  session.set_parameters(bad);
  session.step_once();
  st = wait_steps(session, 17);
  EXPECT_EQ(st->steps, 17);
  EXPECT_NE(st->parameter_error.find("/bodies/0/material/poisson_ratio"), std::string::npos) << st->parameter_error;
  EXPECT_EQ(st->parameters, values);
  EXPECT_EQ(st->changes.size(), 3u);
  b.world.step(b.dt_s);
  EXPECT_TRUE(st->positions_mm == b.world.particles().positions());
}

// ---- the balloon on its worker thread -------------------------------------------------------

std::shared_ptr<const view::SegmentState> wait_for(view::SegmentSession& s, view::SegmentStage stage) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    auto st = s.latest();
    if (st->stage == stage || st->stage == view::SegmentStage::Failed) return st;
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(120)) return st;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void expect_identical(const segment::BalloonResult& a, const segment::BalloonResult& b) {
  EXPECT_TRUE(a.surface.vertices == b.surface.vertices) << "vertex positions differ";
  EXPECT_TRUE(a.surface.triangles == b.surface.triangles);
  EXPECT_EQ(a.report.iterations, b.report.iterations);
  EXPECT_EQ(a.report.stop_reason, b.report.stop_reason);
}

TEST(SegmentSession, LiveBalloonEqualsOneCallSegmentation) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  const std::vector<Vec3> seeds = {ct->index_to_world(Vec3(16, 15, 14))};
  const segment::BalloonOptions options = segment::organ_options(segment::Organ::Generic);
  const segment::BalloonResult expected = segment::segment_balloon(*ct, seeds, options);

  view::SegmentSession session(ct);
  EXPECT_EQ(session.latest()->stage, view::SegmentStage::Idle);
  session.start(seeds, options);
  const auto done = wait_for(session, view::SegmentStage::Done);
  ASSERT_EQ(done->stage, view::SegmentStage::Done) << done->error;
  ASSERT_TRUE(done->result);
  expect_identical(*done->result, expected);
  EXPECT_TRUE(done->surface.vertices == expected.surface.vertices);
  EXPECT_GT(done->steps, 10);
  EXPECT_FALSE(session.busy());
}

TEST(SegmentSession, PausedSteppedAndRestartedRunsGiveTheSameResult) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  const std::vector<Vec3> seeds = {ct->index_to_world(Vec3(13, 17, 12))};
  const segment::BalloonOptions options = segment::organ_options(segment::Organ::Generic);
  const segment::BalloonResult expected = segment::segment_balloon(*ct, seeds, options);

  view::SegmentSession session(ct);
  // A run started elsewhere and retired at once (a seed placed, then undone) does not disturb the next.
  session.start({ct->index_to_world(Vec3(2, 2, 2))}, options);
  session.start(seeds, options, /*paused=*/true);
  EXPECT_TRUE(session.paused());
  auto st = wait_for(session, view::SegmentStage::Paused);
  ASSERT_EQ(st->stage, view::SegmentStage::Paused);
  EXPECT_EQ(st->steps, 0);
  for (int i = 0; i < 3; ++i) session.step_once();
  for (auto t0 = std::chrono::steady_clock::now();
       session.latest()->steps < 3 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  st = session.latest();
  EXPECT_EQ(st->steps, 3);
  EXPECT_EQ(st->seeds_mm, seeds);
  EXPECT_FALSE(st->surface.triangles.empty());
  session.set_paused(false);
  const auto done = wait_for(session, view::SegmentStage::Done);
  ASSERT_EQ(done->stage, view::SegmentStage::Done) << done->error;
  expect_identical(*done->result, expected);
  // No seed: back to idle.
  session.start({}, options);
  EXPECT_EQ(session.latest()->stage, view::SegmentStage::Idle);
}

TEST(SegmentSession, ABadSeedFailsWithTheBalloonsMessage) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  view::SegmentSession session(ct);
  session.start({Vec3(1e4, 0, 0)}, {});
  const auto st = wait_for(session, view::SegmentStage::Done);
  EXPECT_EQ(st->stage, view::SegmentStage::Failed);
  EXPECT_FALSE(st->error.empty());
}

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

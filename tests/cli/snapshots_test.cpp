// SPDX-License-Identifier: Apache-2.0
// `--snapshots DIR` on `ido segment` and `ido simulate`: pictures of the evolution, and the
// stepping equivalence the segment pictures rely on (Balloon::step() × k, then run(), gives
// the same surface as a plain run).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/io/volume_io.h"
#include "ido/segment/balloon.h"
#include "support/png_read.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return nlohmann::json::parse(s.str());
}

/// A 32³ CT (1 mm voxels) of a sphere of radius 9 mm, 350 HU in 40 HU, centred at (16,16,16) mm.
image::Volume<float> sphere_ct() {
  image::Volume<float> ct({32, 32, 32}, Vec3::Ones());
  for (std::int64_t k = 0; k < 32; ++k)
    for (std::int64_t j = 0; j < 32; ++j)
      for (std::int64_t i = 0; i < 32; ++i)
        ct(i, j, k) = (Vec3(double(i), double(j), double(k)) - Vec3::Constant(16)).norm() < 9.0 ? 350.f : 40.f;
  return ct;
}

/// Non-background pixels with x in [x0, x1).
int covered(const test::Png& png, int x0, int x1) {
  int n = 0;
  for (int y = 0; y < png.h; ++y)
    for (int x = x0; x < x1; ++x) n += png.background(x, y) ? 0 : 1;
  return n;
}

// ---- the public Balloon API used by `ido segment --snapshots` ------------------------------

void expect_same_result(const segment::BalloonResult& a, const segment::BalloonResult& b) {
  ASSERT_EQ(a.surface.vertices.size(), b.surface.vertices.size());
  ASSERT_EQ(a.surface.triangles.size(), b.surface.triangles.size());
  double worst = 0;
  for (std::size_t i = 0; i < a.surface.vertices.size(); ++i)
    worst = std::max(worst, (a.surface.vertices[i] - b.surface.vertices[i]).cwiseAbs().maxCoeff());
  EXPECT_EQ(worst, 0.0) << "largest vertex difference (mm)";
  EXPECT_TRUE(a.surface.triangles == b.surface.triangles);
  EXPECT_EQ(a.report.iterations, b.report.iterations);
  EXPECT_EQ(a.report.stop_reason, b.report.stop_reason);
  EXPECT_EQ(a.report.converged, b.report.converged);
  EXPECT_EQ(a.report.repairs, b.report.repairs);
}

TEST(BalloonStepping, StepsThenRunEqualsPlainRun) {
  const auto ct = sphere_ct();
  const std::vector<Vec3> seeds = {Vec3(16.2, 15.7, 16.4)};
  for (const bool threaded : {false, true}) {
    segment::BalloonOptions bo;
    bo.threaded = threaded;
    const segment::BalloonResult plain = segment::segment_balloon(ct, seeds, bo);
    // Stepped as the CLI does: step() until it reports done (reading surface() on the way),
    // then run() for the edge stage and the final repair.
    segment::Balloon stepped(ct, seeds, bo);
    std::int64_t steps = 0;
    bool done = false;
    while (!done) {
      done = stepped.step();
      ++steps;
      if (steps % 7 == 0) {
        EXPECT_FALSE(stepped.surface().triangles.empty());
      }
    }
    const segment::BalloonResult continued = stepped.run();
    SCOPED_TRACE(threaded ? "threaded" : "serial");
    expect_same_result(plain, continued);
    // run() counts the inflation steps taken before it plus the edge stage.
    EXPECT_EQ(continued.report.iterations, steps + bo.edge_iterations);
    // Stopping after a few steps (not done) and calling run() also continues exactly.
    segment::Balloon partly(ct, seeds, bo);
    for (int i = 0; i < 10; ++i) ASSERT_FALSE(partly.step());
    expect_same_result(plain, partly.run());
  }
}

// ---- ido segment --snapshots --------------------------------------------------------------

TEST(SegmentSnapshots, PicturesOfTheInflatingBalloon) {
  const fs::path dir = test::scratch_dir("snapshots_segment");
  io::write_volume(dir / "ct.nii.gz", sphere_ct());
  const fs::path snaps = dir / "snaps";
  // A stale picture of an earlier, longer run is removed; other files stay.
  fs::create_directories(snaps);
  std::ofstream(snaps / "snapshot_0999.png") << "stale";
  std::ofstream(snaps / "notes.txt") << "mine";
  const int every = 5;
  const auto r = test::run_tool(fmt::format(
      "segment {} --seed 16.2,15.7,16.4 -o {} --report {} --snapshots {} --snapshot-every {} --snapshot-size 240x120",
      (dir / "ct.nii.gz").string(), (dir / "s.stl").string(), (dir / "r.json").string(), snaps.string(), every));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(snaps / "snapshot_0999.png"));
  EXPECT_TRUE(fs::exists(snaps / "notes.txt"));
  const auto rep = read_json(dir / "r.json");
  const std::int64_t inflation = rep.at("inflation_steps");
  EXPECT_EQ(inflation + 30, rep.at("iterations").get<std::int64_t>()) << "inflation + 30 edge steps";
  const auto files = rep.at("snapshots");
  const auto steps = rep.at("snapshot_steps");
  // One picture every 5 inflation steps, plus the final surface.
  ASSERT_EQ(std::int64_t(files.size()), inflation / every + 1);
  ASSERT_EQ(steps.size(), files.size());
  ASSERT_GE(files.size(), 4u);
  std::vector<int> area;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const fs::path f = files[i].get<std::string>();
    EXPECT_EQ(f.filename().string(), fmt::format("snapshot_{:04d}.png", i));
    EXPECT_EQ(steps[i].get<std::int64_t>(), i + 1 < files.size() ? std::int64_t(every * (i + 1)) : inflation + 30);
    const test::Png png = test::read_png(f);
    ASSERT_EQ(png.w, 240) << f;
    ASSERT_EQ(png.h, 120) << f;
    area.push_back(covered(png, 0, 120));  // left panel: the surface on white
    // Right panel: the CT slice with the contour in red.
    int red = 0;
    for (int y = 0; y < png.h; ++y)
      for (int x = 120; x < 240; ++x) {
        const auto* p = png.at(x, y);
        red += p[0] > 200 && p[1] < 100 && p[2] < 100;
      }
    EXPECT_GT(red, 0) << f << ": no contour on the slice";
  }
  // The balloon inflates: each inflation picture covers more pixels than the one before (a
  // converging balloon may move less than a pixel between the last pictures: allow ties
  // within 1 %), and the final surface is much larger than the first picture.
  for (std::size_t i = 1; i + 1 < area.size(); ++i) EXPECT_GE(area[i], 0.99 * area[i - 1]) << "picture " << i;
  EXPECT_GT(area[1], area[0]);
  EXPECT_GT(area.back(), 2 * area.front());
}

TEST(SegmentSnapshots, DefaultCadenceGivesFifteenToThirtyPictures) {
  const fs::path dir = test::scratch_dir("snapshots_segment_auto");
  io::write_volume(dir / "ct.nii.gz", sphere_ct());
  const auto r = test::run_tool(fmt::format("segment {} --seed 16.2,15.7,16.4 -o {} --report {} --snapshots {} "
                                            "--snapshot-size 80x40",
                                            (dir / "ct.nii.gz").string(), (dir / "s.stl").string(),
                                            (dir / "r.json").string(), (dir / "snaps").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rep = read_json(dir / "r.json");
  const std::int64_t inflation = rep.at("inflation_steps");
  const auto steps = rep.at("snapshot_steps");
  ASSERT_GE(inflation, 30) << "the test needs a run of at least 30 steps";
  EXPECT_GE(steps.size(), 16u);  // 15..30 inflation pictures + the final one
  EXPECT_LE(steps.size(), 31u);
  // Evenly spaced: multiples of one cadence, none missing.
  const std::int64_t every = steps[0];
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) EXPECT_EQ(steps[i].get<std::int64_t>(), every * std::int64_t(i + 1));
  EXPECT_EQ(std::int64_t(steps.size() - 1), inflation / every);
  for (const auto& f : rep.at("snapshots")) EXPECT_EQ(test::read_png(f.get<std::string>()).w, 80);
}

// ---- ido simulate --snapshots -------------------------------------------------------------

/// A 60 × 8 × 8 mm soft beam clamped at x = 0, sagging under gravity along −z.
std::string cantilever_scene(int steps, int output_every) {
  return fmt::format(R"({{
  "dt_s": 0.005, "steps": {}, "output_every": {}, "integrator": "implicit_euler",
  "gravity_mm_s2": [0, 0, -9806.65],
  "damping": {{"rayleigh_mass_per_s": 2.0, "rayleigh_stiffness_s": 0.0}},
  "bodies": [{{
    "name": "beam",
    "mesh": {{"generator": "beam", "size_mm": [60, 8, 8], "cells": [12, 2, 2]}},
    "model": "corotational_fem",
    "material": {{"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
    "fixed": [{{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 9, 9]}}]
  }}]
}})",
                     steps, output_every);
}

/// Centroid row (pixels from the top) of the non-background pixels.
double centroid_row(const test::Png& png) {
  double sum = 0;
  int n = 0;
  for (int y = 0; y < png.h; ++y)
    for (int x = 0; x < png.w; ++x)
      if (!png.background(x, y)) {
        sum += y;
        ++n;
      }
  return n > 0 ? sum / n : -1.0;
}

TEST(SimulateSnapshots, FallingCantileverMovesDownInThePictures) {
  const fs::path dir = test::scratch_dir("snapshots_simulate");
  std::ofstream(dir / "scene.json") << cantilever_scene(100, 10);
  const fs::path snaps = dir / "snaps";
  for (const char* field : {"von_mises", "displacement"}) {
    SCOPED_TRACE(field);
    const auto r = test::run_tool(fmt::format("simulate {} -o {} --snapshots {} --snapshot-every 3 --snapshot-size 200x150 "
                                              "--snapshot-field {}",
                                              (dir / "scene.json").string(), (dir / "out").string(), snaps.string(), field));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto rep = read_json(dir / "out" / "report.json");
    const std::int64_t frames = rep.at("frames");
    ASSERT_EQ(frames, 11);  // the initial state and every 10th of 100 steps
    // Frames 0, 3, 6, 9 and the last one (10).
    EXPECT_EQ(rep.at("snapshot_frames"), nlohmann::json({0, 3, 6, 9, 10}));
    const auto files = rep.at("snapshots");
    ASSERT_EQ(files.size(), 5u);
    std::vector<test::Png> pngs;
    for (const auto& f : files) {
      pngs.push_back(test::read_png(f.get<std::string>()));
      ASSERT_EQ(pngs.back().w, 200);
      ASSERT_EQ(pngs.back().h, 150);
    }
    // Up is +z in the pictures: the sagging beam's pixels move down.
    const double first = centroid_row(pngs.front()), last = centroid_row(pngs.back());
    ASSERT_GT(first, 0);
    EXPECT_GT(last, first + 5.0) << "centroid row first " << first << ", last " << last;
    // One colour range for the whole run: lo < hi, and lo is the run's minimum (0 at rest
    // for the displacement).
    const auto range = rep.at("snapshot_range");
    EXPECT_LT(range[0].get<double>(), range[1].get<double>());
    if (std::string(field) == "displacement") {
      EXPECT_EQ(range[0].get<double>(), 0.0);
    }
  }
}

// ---- bad --snapshots ----------------------------------------------------------------------

TEST(Snapshots, BadFolderExitsTwoNamingTheArgument) {
  const fs::path dir = test::scratch_dir("snapshots_bad");
  io::write_volume(dir / "ct.nii.gz", sphere_ct());
  std::ofstream(dir / "scene.json") << cantilever_scene(10, 5);
  std::ofstream(dir / "a_file") << "x";
  for (const fs::path& bad : {dir / "a_file", dir / "a_file" / "sub"}) {
    SCOPED_TRACE(bad.string());
    const auto seg = test::run_tool(fmt::format("segment {} --seed 16,16,16 -o {} --snapshots {}",
                                                (dir / "ct.nii.gz").string(), (dir / "s.stl").string(), bad.string()));
    EXPECT_EQ(seg.exit_code, 2);
    EXPECT_NE(seg.err.find("--snapshots"), std::string::npos) << seg.err;
    EXPECT_FALSE(fs::exists(dir / "s.stl")) << "nothing is run before the arguments are checked";
    const auto sim = test::run_tool(fmt::format("simulate {} -o {} --snapshots {}", (dir / "scene.json").string(),
                                                (dir / "out").string(), bad.string()));
    EXPECT_EQ(sim.exit_code, 2);
    EXPECT_NE(sim.err.find("--snapshots"), std::string::npos) << sim.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << "nothing is run before the arguments are checked";
  }
  const auto every = test::run_tool(fmt::format("simulate {} -o {} --snapshots {} --snapshot-every 0",
                                                (dir / "scene.json").string(), (dir / "out").string(),
                                                (dir / "snaps").string()));
  EXPECT_EQ(every.exit_code, 2);
  EXPECT_NE(every.err.find("--snapshot-every"), std::string::npos) << every.err;
  const auto size = test::run_tool(fmt::format("segment {} --seed 16,16,16 -o {} --snapshots {} --snapshot-size 10by10",
                                               (dir / "ct.nii.gz").string(), (dir / "s.stl").string(),
                                               (dir / "snaps").string()));
  EXPECT_EQ(size.exit_code, 2);
  EXPECT_NE(size.err.find("--snapshot-size"), std::string::npos) << size.err;
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// `ido view` in a window under Xvfb (Mesa llvmpipe), driven by event scripts: what a user
// sees and gets. A click on the axial slice puts the seed on the voxel under the cursor (its
// world position in the report); the balloon grown in the window and saved with ctrl+s is
// `ido segment`'s surface, mask and report from the same seed, bit for bit; the screenshot
// shows the balloon in the 3-D view and its contour and the seed on the slice; a recorded
// session replays to the same seed; surfaces and tetrahedral meshes show in the Scene view;
// a shift-click places a stop point the balloon stops at as segment_balloon() does (and ctrl+z
// takes one back); a Young's modulus typed into the Deform panel continues the run as the library
// does with that modulus from that step on; a path CSV replayed in the Drill workspace removes
// what `ido drill` removes on it; a region of interest drawn on the slices gives `ido segment
// --roi`'s surface and shows on them; several bodies in the Deform workspace get a legend and
// their numbers; `--snapshot` draws what was opened without a display, with a legend.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/drill/haptic_device.h"
#include "ido/drill/udp_bridge.h"
#include "ido/io/mesh_io.h"
#include "ido/io/scene.h"
#include "ido/io/volume_io.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"
#include "ido/sim/fem_common.h"
#include "ido/view/orbit_camera.h"
#include "ido/view/slice_view.h"
#include "support/ball_ct.h"
#include "support/png_read.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

// The layout docs/viewer.md describes, for a 960×640 window: the panel is 340 px wide, the
// views share the rest in a 2×2 grid (axial top-left, 3-D top-right).
constexpr int kWidth = 960, kHeight = 640;
const view::PixelRect kAxial{340, 0, 310, 320};
const view::PixelRect k3d{650, 0, 310, 320};
const view::PixelRect kCoronal{340, 320, 310, 320};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

/// The volume (mm³) `ido drill` removes from dir/block.vtu along @p path with @p tool: what a
/// session recorded in the window must replay to.
double drill_replay_removed(const fs::path& dir, const fs::path& path, const std::string& tool) {
  const auto cli = test::run_tool(fmt::format("drill {} --tool {} --path {} -o {} --report {} -q",
                                              (dir / "block.vtu").string(), tool, path.string(),
                                              (dir / "out.vtu").string(), (dir / "cli_drill.json").string()));
  EXPECT_EQ(cli.exit_code, 0) << cli.err;
  return read_json(dir / "cli_drill.json")["removed_volume_mm3"].get<double>();
}

/// Runs `ido view ARGS` after @p launcher (a display server, or an environment without one)
/// and captures its output. Mesa's and X11's own allocations are kept for the process's life
/// (sanitizer builds only); intercept_tls_get_addr=0 for the reason given in
/// cmake/IdoHelpers.cmake.
test::CommandResult run_tool_view(const std::string& launcher, const std::string& args, const fs::path& dir) {
  const fs::path out = dir / "view-out.txt", err = dir / "view-err.txt";
  const fs::path supp = test::source_dir() / "tests" / "sanitizer" / "lsan-view.supp";
  const std::string cmd = fmt::format(
      "{} env LSAN_OPTIONS=suppressions={}:print_suppressions=0:intercept_tls_get_addr=0 {} view {} >{} 2>{} </dev/null",
      launcher, supp.string(), test::tool_path().string(), args, out.string(), err.string());
  const int status = std::system(cmd.c_str());
  test::CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

/// Runs `ido view ARGS` in a fresh Xvfb server (24-bit screen).
test::CommandResult run_view(const std::string& args, const fs::path& dir) {
  return run_tool_view("xvfb-run -a -s '-screen 0 1280x1024x24'", args, dir);
}

nlohmann::json event(std::int64_t frame, const char* type) { return {{"frame", frame}, {"type", type}}; }
nlohmann::json mouse(std::int64_t frame, const char* type, double x, double y) {
  nlohmann::json e = event(frame, type);
  e["x"] = x;
  e["y"] = y;
  return e;
}
nlohmann::json ctrl_mouse(std::int64_t frame, const char* type, double x, double y) {
  nlohmann::json e = mouse(frame, type, x, y);
  e["ctrl"] = true;
  return e;
}
nlohmann::json key(std::int64_t frame, const char* type, const char* name, bool ctrl) {
  nlohmann::json e = event(frame, type);
  e["key"] = name;
  e["ctrl"] = ctrl;
  return e;
}
nlohmann::json wait(std::int64_t frame, const char* until) {
  nlohmann::json e = event(frame, "wait");
  e["until"] = until;
  e["timeout"] = 120;
  return e;
}

void write_script(const fs::path& path, const nlohmann::json& events) {
  std::ofstream(path) << nlohmann::json{{"window", {kWidth, kHeight}}, {"events", events}}.dump(1);
}

/// Runs `ido view ARGS` with no display at all (no DISPLAY, no Xvfb): --snapshot.
test::CommandResult run_headless(const std::string& args, const fs::path& dir) {
  return run_tool_view("env -u DISPLAY -u WAYLAND_DISPLAY", args, dir);
}

/// True when pixel (r, g, b) is @p rgb (0..1) as 8 bits, within 2 levels.
bool is_colour(int r, int g, int b, const Vec3& rgb) {
  return std::abs(r - int(std::lround(255 * rgb.x()))) <= 2 && std::abs(g - int(std::lround(255 * rgb.y()))) <= 2 &&
         std::abs(b - int(std::lround(255 * rgb.z()))) <= 2;
}

/// Pixels of @p png inside @p r for which @p pred(r, g, b) holds.
template <class Pred>
int count(const test::Png& png, const view::PixelRect& r, Pred pred) {
  int n = 0;
  for (int y = int(r.y); y < int(r.y + r.height); ++y)
    for (int x = int(r.x); x < int(r.x + r.width); ++x) {
      const auto* p = png.at(x, y);
      n += pred(int(p[0]), int(p[1]), int(p[2])) ? 1 : 0;
    }
  return n;
}

class ViewWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(std::system("command -v xvfb-run >/dev/null 2>&1"), 0)
        << "xvfb-run is missing: scripts/install-deps.sh installs xvfb";
    dir = test::scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    ct_path = dir / "ball.nii.gz";
    io::write_volume(ct_path, test::ball_ct());
    ct = io::read_volume(ct_path);  // as both tools read it
  }
  fs::path dir, ct_path;
  image::Volume<float> ct;
};

TEST_F(ViewWindow, SeedClickBalloonAndSaveEqualIdoSegment) {
  // Scroll the axial slice up by two, then click voxel (16, 15) of it: the seed is voxel
  // (16, 15, 13 + 2) (the window opens at the middle slice, 26 / 2).
  const view::SliceView axial(2, ct.size(), ct.spacing(), kAxial);
  const auto [px, py] = axial.pixel_of(16, 15);
  const Index3 voxel = {16, 15, 15};
  write_script(dir / "seed.json",
               {mouse(1, "mouse_move", px, py), [&] {
                  auto e = mouse(2, "scroll", px, py);
                  e["dy"] = 2;
                  return e;
                }(),
                mouse(3, "mouse_down", px, py), mouse(4, "mouse_up", px, py), wait(5, "segment_done"),
                key(6, "key_down", "s", true), key(7, "key_up", "s", true), wait(8, "idle"),
                [] {
                  auto e = event(9, "screenshot");
                  e["name"] = "segment.png";
                  return e;
                }(),
                event(10, "quit")});
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --surface {} --mask {} --report {}",
                                      ct_path.string(), (dir / "seed.json").string(), (dir / "shots").string(),
                                      (dir / "view.ply").string(), (dir / "view_mask.nii.gz").string(),
                                      (dir / "view.json").string()),
                            dir);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;

  // The seed is the clicked voxel's centre in world coordinates.
  const nlohmann::json view_report = read_json(dir / "view.json");
  const Vec3 expected = ct.index_to_world(Vec3(double(voxel[0]), double(voxel[1]), double(voxel[2])));
  ASSERT_EQ(view_report["seeds_mm"].size(), 1u);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(view_report["seeds_mm"][0][std::size_t(c)].get<double>(), expected[c]) << c;

  // `ido segment` from the same voxel writes the same surface, mask and report.
  const auto cli = test::run_tool(fmt::format("segment {} --seed-voxel {},{},{} -o {} --mask {} --report {} -q",
                                              ct_path.string(), voxel[0], voxel[1], voxel[2],
                                              (dir / "cli.ply").string(), (dir / "cli_mask.nii.gz").string(),
                                              (dir / "cli.json").string()));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  const geometry::TriangleMesh a = io::read_triangle_mesh(dir / "view.ply"), b = io::read_triangle_mesh(dir / "cli.ply");
  ASSERT_GT(a.triangle_count(), 100u);
  EXPECT_TRUE(a.vertices == b.vertices) << "the window's balloon differs from ido segment's";
  EXPECT_TRUE(a.triangles == b.triangles);
  EXPECT_EQ(slurp(dir / "view.ply"), slurp(dir / "cli.ply"));
  const auto mask_a = io::read_volume(dir / "view_mask.nii.gz"), mask_b = io::read_volume(dir / "cli_mask.nii.gz");
  ASSERT_TRUE(mask_a.same_grid(mask_b));
  double sum = 0;
  for (std::int64_t k = 0; k < mask_a.size(2); ++k)
    for (std::int64_t j = 0; j < mask_a.size(1); ++j)
      for (std::int64_t i = 0; i < mask_a.size(0); ++i) {
        EXPECT_EQ(mask_a(i, j, k), mask_b(i, j, k));
        sum += mask_a(i, j, k);
      }
  EXPECT_GT(sum, 1000);  // a ball of radius 9 mm in 1.3 mm³ voxels: about 2300
  const nlohmann::json cli_report = read_json(dir / "cli.json");
  for (const auto& [k, v] : cli_report.items()) {
    ASSERT_TRUE(view_report.contains(k)) << k;
    if (k == "seconds" || k == "phase_seconds" || k == "surface" || k == "mask") continue;
    EXPECT_EQ(view_report[k], v) << k;
  }
  EXPECT_EQ(view_report.size(), cli_report.size());

  // The screenshot: the balloon (orange) in the 3-D view; on the axial slice its contour (red)
  // and the seed's cross (green) where the click was.
  const test::Png png = test::read_png(dir / "shots" / "segment.png");
  ASSERT_EQ(png.w, kWidth);
  ASSERT_EQ(png.h, kHeight);
  EXPECT_GT(count(png, k3d, [](int red, int green, int blue) { return red > 90 && red > green + 25 && green > blue + 10; }), 400);
  EXPECT_GT(count(png, kAxial, [](int red, int green, int blue) { return red > 200 && green < 90 && blue < 90; }), 30);
  const view::PixelRect around{px - 12, py - 12, 25, 25};
  EXPECT_GT(count(png, around, [](int red, int green, int blue) { return green > 200 && red < 120 && blue < 150; }), 3);
  // Outside the ball the slice is dark grey, inside bright: the window/level spans the CT.
  const auto* inside = png.at(int(px) + 7, int(py) + 7);
  EXPECT_GT(int(inside[0]), 150);
}

TEST_F(ViewWindow, RecordedSessionReplaysToTheSameSeed) {
  const view::SliceView axial(2, ct.size(), ct.spacing(), kAxial);
  const auto [px, py] = axial.pixel_of(12, 18);
  const nlohmann::json input = {mouse(1, "mouse_move", px, py), mouse(2, "mouse_down", px, py),
                                mouse(3, "mouse_up", px, py)};
  nlohmann::json events = input;
  events.push_back(wait(4, "segment_done"));
  events.push_back(event(5, "quit"));
  write_script(dir / "live.json", events);
  const auto r = run_view(fmt::format("{} --script {} --record {}", ct_path.string(), (dir / "live.json").string(),
                                      (dir / "rec.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The recording holds the input events (not the script's instructions), where they happened.
  nlohmann::json rec = read_json(dir / "rec.json");
  ASSERT_EQ(rec["events"].size(), input.size()) << rec.dump();
  for (std::size_t i = 0; i < input.size(); ++i) {
    EXPECT_EQ(rec["events"][i]["type"], input[i]["type"]);
    EXPECT_EQ(rec["events"][i]["x"].get<double>(), px);
    EXPECT_EQ(rec["events"][i]["y"].get<double>(), py);
  }
  EXPECT_EQ(rec["window"], nlohmann::json({kWidth, kHeight}));
  // Replayed (with a save added at its end), the recording places the same seed.
  const std::int64_t last = rec["events"].back()["frame"].get<std::int64_t>();
  rec["events"].push_back(wait(last + 1, "segment_done"));
  rec["events"].push_back(key(last + 2, "key_down", "s", true));
  rec["events"].push_back(wait(last + 3, "idle"));
  std::ofstream(dir / "replay.json") << rec.dump(1);
  const auto replay = run_view(fmt::format("{} --script {} --report {}", ct_path.string(),
                                           (dir / "replay.json").string(), (dir / "replay_report.json").string()),
                               dir);
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  const nlohmann::json report = read_json(dir / "replay_report.json");
  const Vec3 expected = ct.index_to_world(Vec3(12, 18, 13));
  for (int c = 0; c < 3; ++c) EXPECT_EQ(report["seeds_mm"][0][std::size_t(c)].get<double>(), expected[c]);
}

TEST_F(ViewWindow, SurfacesAndTetMeshesShowInTheSceneView) {
  io::write_triangle_mesh(dir / "ball.stl", segment::balloon_icosphere(Vec3(0, 0, 0), 10.0, 3));
  geometry::TetMesh cube;  // a cube [25, 45]³ in 5 tetrahedra
  for (int c = 0; c < 8; ++c) cube.vertices.push_back(Vec3(c & 1 ? 45 : 25, c & 2 ? 45 : 25, c & 4 ? 45 : 25) - Vec3(0, 35, 35));
  cube.tets = {{0, 1, 2, 4}, {1, 3, 2, 7}, {1, 4, 5, 7}, {2, 4, 7, 6}, {1, 2, 4, 7}};
  for (Tet& t : cube.tets) {
    const auto& v = cube.vertices;
    const Vec3 a = v[std::size_t(t[0])];
    if ((v[std::size_t(t[1])] - a).cross(v[std::size_t(t[2])] - a).dot(v[std::size_t(t[3])] - a) < 0) std::swap(t[2], t[3]);
  }
  io::write_tet_mesh(dir / "cube.vtu", cube);
  write_script(dir / "scene.json", {[] {
                                      auto e = event(2, "screenshot");
                                      e["name"] = "scene.png";
                                      return e;
                                    }(),
                                    event(3, "quit")});
  const auto r = run_view(fmt::format("{} {} --script {} --screenshots {}", (dir / "ball.stl").string(),
                                      (dir / "cube.vtu").string(), (dir / "scene.json").string(), (dir / "shots").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const test::Png png = test::read_png(dir / "shots" / "scene.png");
  ASSERT_EQ(png.w, kWidth);
  const view::PixelRect views{340, 0, 620, 640};
  // The first object is drawn light grey, the second light blue; both are in view.
  const int grey_px = count(png, views, [](int red, int green, int blue) { return red > 70 && std::abs(red - green) < 12 && blue >= green && blue - green < 20; });
  const int blue_px = count(png, views, [](int red, int green, int blue) { return blue > 80 && blue > red + 40 && green > red + 15; });
  EXPECT_GT(grey_px, 2000);
  EXPECT_GT(blue_px, 2000);
}

TEST_F(ViewWindow, MeshWorkspaceTetrahedralisesLikeIdoTetmeshAndShowsTheSection) {
  io::write_triangle_mesh(dir / "ball.ply", segment::balloon_icosphere(Vec3(3, -2, 5), 10.0, 3));
  nlohmann::json shot = event(8, "screenshot");
  shot["name"] = "mesh.png";
  write_script(dir / "mesh.json", {key(1, "key_down", "f3", false), key(2, "key_up", "f3", false),
                                   key(3, "key_down", "t", false), key(4, "key_up", "t", false), wait(5, "idle"),
                                   key(6, "key_down", "s", true), wait(7, "idle"), shot, event(9, "quit")});
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --tet-output {}", (dir / "ball.ply").string(),
                                      (dir / "mesh.json").string(), (dir / "shots").string(),
                                      (dir / "view.vtu").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The tetrahedra saved from the window are `ido tetmesh`'s for the same surface, byte for byte.
  const auto cli = test::run_tool(fmt::format("tetmesh {} -o {} -q", (dir / "ball.ply").string(), (dir / "cli.vtu").string()));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  const std::string view_bytes = slurp(dir / "view.vtu");
  EXPECT_GT(view_bytes.size(), 1000u);
  EXPECT_EQ(view_bytes, slurp(dir / "cli.vtu"));
  // The clip plane through the middle removes the half nearer the camera: the section's faces
  // (yellow, with the cut tetrahedra's edges dark) fill the middle of the view.
  const test::Png png = test::read_png(dir / "shots" / "mesh.png");
  ASSERT_EQ(png.w, kWidth);
  auto section = [](int red, int green, int blue) { return red > 150 && green > 110 && blue < 110 && red > blue + 80; };
  const view::PixelRect views{340, 0, 620, 640};
  EXPECT_GT(count(png, views, section), 5000);
  EXPECT_GT(count(png, {640, 310, 20, 20}, section), 200);
  // Around it the boundary of the kept half (light blue).
  EXPECT_GT(count(png, views, [](int red, int green, int blue) { return blue > 80 && blue > red + 40 && green > red + 15; }), 1000);
}

TEST_F(ViewWindow, DrillSessionByMouseReplaysInIdoDrillToTheSameRemovedVolume) {
  // A 16 × 16 × 8 mm block; the burr (radius 2 mm) starts 4 mm above its top centre.
  ASSERT_EQ(test::run_tool(fmt::format("tetmesh --shape block:16,16,8 -o {} -q", (dir / "block.vtu").string())).exit_code, 0);
  // Drill workspace (f4), start (d), drag the burr down into the block over 20 frames, hold,
  // stop (d), wait until the session has drained (20 frames: the session lasts as long as they do).
  nlohmann::json events = nlohmann::json::array(
      {key(1, "key_down", "f4", false), key(2, "key_up", "f4", false), key(3, "key_down", "d", false),
       key(4, "key_up", "d", false), mouse(5, "mouse_down", 650, 320)});
  double y = 320;
  for (int f = 6; f < 26; ++f) events.push_back(mouse(f, "mouse_move", 650, y += 9));
  events.push_back(mouse(26, "mouse_up", 650, y));
  for (const auto& e : {key(30, "key_down", "d", false), key(31, "key_up", "d", false), wait(32, "idle")}) events.push_back(e);
  nlohmann::json shot = event(33, "screenshot");
  shot["name"] = "drill.png";
  events.push_back(shot);
  events.push_back(event(34, "quit"));
  write_script(dir / "drill.json", events);
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --drill-path {} --drill-report {}",
                                      (dir / "block.vtu").string(), (dir / "drill.json").string(),
                                      (dir / "shots").string(), (dir / "path.csv").string(),
                                      (dir / "view_drill.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json view_report = read_json(dir / "view_drill.json");
  const double removed = view_report["removed_volume_mm3"].get<double>();
  EXPECT_GT(removed, 20.0) << "the burr went 7 mm deep: a hole of tens of mm³";
  EXPECT_LT(removed, 2048.0);
  // The path, one row per haptic tick, replayed by `ido drill` removes the same volume (the
  // threads sample it at their own instants: within 2 %).
  const std::string csv = slurp(dir / "path.csv");
  // One row per 1 kHz tick: the rows cover the session's duration (which is as long as the
  // window's frames take, so it is read from the path's own time column, not assumed).
  std::vector<double> times;
  {
    std::istringstream lines(csv);
    std::string line;
    while (std::getline(lines, line)) {
      char* end = nullptr;
      const double t = std::strtod(line.c_str(), &end);
      if (end != line.c_str()) times.push_back(t);
    }
  }
  ASSERT_GT(times.size(), 50u);
  EXPECT_GE(double(times.size()), 0.9 * (times.back() - times.front()) * 1000.0);
  const double replayed = drill_replay_removed(dir, dir / "path.csv", "sphere:radius=2");
  EXPECT_TRUE(test::rel_near(removed, replayed, 0.02)) << removed << " vs " << replayed;
  // The window shows the drilled block (flat-shaded material colour) with the hole in its top.
  const test::Png png = test::read_png(dir / "shots" / "drill.png");
  ASSERT_EQ(png.w, kWidth);
  const view::PixelRect views{340, 0, 620, 640};
  EXPECT_GT(count(png, views, [](int red, int green, int blue) { return red > 100 && red >= green && green > blue + 10 && red - blue < 90; }), 20000);
}

TEST_F(ViewWindow, PulledPointMovesAndSpringsBackWithAColourBar) {
  // A 40 × 10 × 10 mm soft beam clamped at x = 0, no gravity, damped: at rest until pulled.
  // dt is small enough for the explicit RK4 the test switches to (the next name after
  // implicit_euler).
  std::ofstream(dir / "beam.json") << R"({
    "dt_s": 0.001, "steps": 1, "integrator": "implicit_euler",
    "damping": {"rayleigh_mass_per_s": 5.0, "rayleigh_stiffness_s": 0.0},
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [40, 10, 10], "cells": [8, 2, 2]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 2e3, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 11, 11]}]}]})";
  // Where the window shows the tip's top corner (the 3-D view frames the scene's box).
  view::OrbitCamera cam;
  cam.frame(Vec3(0, 0, 0), Vec3(40, 10, 10));
  const viz::Camera c = cam.camera();
  // The Deform workspace's 3-D view leaves the view area's right 120 px to the colour bar.
  const Vec4 clip = c.projection_matrix(500.0 / 640.0) * c.view_matrix() * Vec4(40, 0, 10, 1);
  const double tx = 340 + (clip.x() / clip.w() + 1) / 2 * 500, ty = (1 - clip.y() / clip.w()) / 2 * 640;
  // Deform workspace (f5), run (space), press on the tip and drag 150 px down, hold, release.
  nlohmann::json events = nlohmann::json::array({key(1, "key_down", "f5", false), key(2, "key_up", "f5", false),
                                                 key(3, "key_down", "space", false), key(4, "key_up", "space", false),
                                                 mouse(10, "mouse_down", tx, ty)});
  for (int f = 11; f <= 30; ++f) events.push_back(mouse(f, "mouse_move", tx, ty + 7.5 * (f - 10)));
  nlohmann::json pulled = event(80, "screenshot");
  pulled["name"] = "pulled.png";
  events.push_back(pulled);
  events.push_back(mouse(81, "mouse_up", tx, ty + 150));
  // Switch the integrator (i) while it swings back: between two steps, and the run goes on.
  events.push_back(key(84, "key_down", "i", false));
  events.push_back(key(85, "key_up", "i", false));
  nlohmann::json settle = wait(86, "deform_steps");  // 1.5 s of simulated time (damping 5/s)
  settle["steps"] = 1500;
  events.push_back(settle);
  events.push_back(event(90, "quit"));
  write_script(dir / "pull.json", events);
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --deform-log {}", (dir / "beam.json").string(),
                                      (dir / "pull.json").string(), (dir / "shots").string(), (dir / "log.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json log = read_json(dir / "log.json");
  ASSERT_GE(log["particle"].get<int>(), 0) << "the press found no surface point";
  const Vec3 rest(log["rest_mm"][0].get<double>(), log["rest_mm"][1].get<double>(), log["rest_mm"][2].get<double>());
  EXPECT_GT(rest.x(), 35.0) << "the grabbed point is at the free end";
  double pulled_mm = 0, last_mm = -1;
  bool released = false;
  std::set<std::string> integrators;
  std::int64_t steps_at_release = 0, last_steps = 0;
  for (const auto& s : log["samples"]) {
    const Vec3 p(s["position_mm"][0].get<double>(), s["position_mm"][1].get<double>(), s["position_mm"][2].get<double>());
    const double d = (p - rest).norm();
    integrators.insert(s["integrator"].get<std::string>());
    if (s["grabbed"].get<bool>()) {
      pulled_mm = std::max(pulled_mm, d);
    } else if (pulled_mm > 0) {
      if (!released) steps_at_release = s["steps"].get<std::int64_t>();
      released = true;
      last_mm = d;
      last_steps = s["steps"].get<std::int64_t>();
    }
  }
  EXPECT_GT(pulled_mm, 2.0) << "the spring to the cursor pulls the tip down";
  ASSERT_TRUE(released);
  EXPECT_GT(last_steps, steps_at_release + 50);
  EXPECT_LT(last_mm, 0.25 * pulled_mm) << "released, the beam springs back towards its rest shape";
  EXPECT_EQ(integrators.size(), 2u) << "the integrator was switched between steps";
  // The picture has the colour bar (viridis, maximum at the top) beside the beam.
  const test::Png png = test::read_png(dir / "shots" / "pulled.png");
  ASSERT_EQ(png.w, kWidth);
  const auto* top = png.at(960 - 100 + 11, 70);
  const auto* bottom = png.at(960 - 100 + 11, 640 - 70);
  EXPECT_TRUE(top[0] > 180 && top[1] > 180 && top[2] < 120) << int(top[0]) << "," << int(top[1]) << "," << int(top[2]);
  EXPECT_TRUE(bottom[0] > 40 && bottom[1] < 60 && bottom[2] > 70) << int(bottom[0]) << "," << int(bottom[1]) << "," << int(bottom[2]);
}

/// A CT of a tube (radius 4 mm, 350 HU in 40 HU) along k from k = 3 to k = 44, through voxel
/// columns (12, 12); anisotropic voxels, off-origin.
image::Volume<float> tube_ct() {
  image::Volume<float> ct({24, 24, 48}, Vec3(1.0, 1.1, 1.2), Vec3(5, -3, 10));
  const Vec3 a = ct.index_to_world(Vec3(12, 12, 3)), b = ct.index_to_world(Vec3(12, 12, 44));
  for (std::int64_t k = 0; k < ct.size(2); ++k)
    for (std::int64_t j = 0; j < ct.size(1); ++j)
      for (std::int64_t i = 0; i < ct.size(0); ++i) {
        const Vec3 p = ct.index_to_world(Vec3(double(i), double(j), double(k)));
        const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
        ct(i, j, k) = (p - (a + t * (b - a))).norm() < 4.0 ? 350.f : 40.f;
      }
  return ct;
}

nlohmann::json shift_click(std::int64_t frame, const char* type, double x, double y) {
  nlohmann::json e = mouse(frame, type, x, y);
  e["shift"] = true;
  return e;
}

std::array<double, 2> z_range(const geometry::TriangleMesh& m) {
  std::array<double, 2> r = {INFINITY, -INFINITY};
  for (const Vec3& v : m.vertices) r = {std::min(r[0], v.z()), std::max(r[1], v.z())};
  return r;
}

TEST_F(ViewWindow, StopPointShiftClickStopsTheBalloonAsTheLibraryDoes) {
  io::write_volume(ct_path, tube_ct());
  ct = io::read_volume(ct_path);
  // A seed on the axial slice (scrolled from the middle, 24, down to 22); then shift-clicks on the
  // coronal slice (now through the seed, j = 12) put a stop point above it at k = 34 and one below
  // at k = 8; ctrl+z takes the second back.
  const Index3 seed = {12, 12, 22}, stop = {12, 12, 34}, undone = {12, 12, 8};
  const view::SliceView axial(2, ct.size(), ct.spacing(), kAxial), coronal(1, ct.size(), ct.spacing(), kCoronal);
  const auto [sx, sy] = axial.pixel_of(12, 12);
  const auto [tx, ty] = coronal.pixel_of(12, 34);
  const auto [ux, uy] = coronal.pixel_of(12, 8);
  nlohmann::json scroll = mouse(1, "scroll", sx, sy);
  scroll["dy"] = -2;
  nlohmann::json shot = event(20, "screenshot");
  shot["name"] = "stop.png";
  write_script(dir / "stop.json",
               {scroll, mouse(2, "mouse_down", sx, sy), mouse(3, "mouse_up", sx, sy), shift_click(5, "mouse_down", tx, ty),
                shift_click(6, "mouse_up", tx, ty), shift_click(8, "mouse_down", ux, uy), shift_click(9, "mouse_up", ux, uy),
                key(11, "key_down", "z", true), key(12, "key_up", "z", true), wait(13, "segment_done"),
                key(14, "key_down", "s", true), key(15, "key_up", "s", true), wait(16, "idle"), shot, event(21, "quit")});
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --surface {} --report {}", ct_path.string(),
                                      (dir / "stop.json").string(), (dir / "shots").string(),
                                      (dir / "view.ply").string(), (dir / "view.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;

  // The library's balloon from the same seed with that stop point (the voxels' centres).
  auto world = [&](const Index3& v) { return ct.index_to_world(Vec3(double(v[0]), double(v[1]), double(v[2]))); };
  segment::BalloonOptions options = segment::organ_options(segment::Organ::Generic);
  options.leak.stop_points_mm = {world(stop)};
  const segment::BalloonResult expected = segment::segment_balloon(ct, {world(seed)}, options);
  io::write_triangle_mesh(dir / "library.ply", expected.surface);
  ASSERT_GT(expected.surface.triangle_count(), 100u);
  EXPECT_EQ(slurp(dir / "view.ply"), slurp(dir / "library.ply")) << "the window's balloon differs from segment_balloon's";
  const geometry::TriangleMesh got = io::read_triangle_mesh(dir / "view.ply");
  EXPECT_EQ(got.vertex_count(), expected.surface.vertex_count());

  // The stop point matters: the front halts below it, where without it the balloon fills the
  // tube past it; and the undone stop point is gone: the balloon reaches below where it was.
  const auto [zmin, zmax] = z_range(got);
  EXPECT_LT(zmax, world(stop).z());
  EXPECT_GT(zmax, world(seed).z() + 5.0);
  EXPECT_LT(zmin, world(undone).z() - 2.0);
  const auto free_run = segment::segment_balloon(ct, {world(seed)}, segment::organ_options(segment::Organ::Generic));
  EXPECT_GT(z_range(free_run.surface)[1], world(stop).z() + 3.0);

  // The report lists the seed and the stop point, and the leak the stop point held.
  const nlohmann::json report = read_json(dir / "view.json");
  ASSERT_EQ(report["seeds_mm"].size(), 1u);
  ASSERT_EQ(report["leak_control"]["stop_points_mm"].size(), 1u) << report["leak_control"].dump();
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(report["seeds_mm"][0][std::size_t(c)].get<double>(), world(seed)[c]);
    EXPECT_EQ(report["leak_control"]["stop_points_mm"][0][std::size_t(c)].get<double>(), world(stop)[c]);
  }
  EXPECT_EQ(report["iterations"].get<std::int64_t>(), expected.report.iterations);
  bool stop_event = false;
  for (const auto& e : report["leak_control"]["events"]) stop_event |= e["cause"] == "stop_point";
  EXPECT_TRUE(stop_event) << report["leak_control"].dump();

  // The picture: the stop point's blue x on the coronal slice where the click was, none where
  // the undone one was.
  const test::Png png = test::read_png(dir / "shots" / "stop.png");
  ASSERT_EQ(png.w, kWidth);
  auto stop_blue = [](int red, int green, int blue) { return blue > 200 && green > 140 && green < 230 && red < 110; };
  EXPECT_GT(count(png, {tx - 12, ty - 12, 25, 25}, stop_blue), 3);
  EXPECT_EQ(count(png, {ux - 12, uy - 12, 25, 25}, stop_blue), 0);
}

TEST_F(ViewWindow, ModulusTypedInTheDeformPanelContinuesTheRunAsTheLibraryDoes) {
  // A beam clamped at x = 0 sagging under gravity (implicit Euler, damped).
  const std::string scene_text = R"({
    "dt_s": 0.005, "steps": 1, "integrator": "implicit_euler",
    "gravity_mm_s2": [0, 0, -9806.65],
    "damping": {"rayleigh_mass_per_s": 2.0},
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [40, 10, 10], "cells": [8, 2, 2]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 11, 11]}]}]})";
  std::ofstream(dir / "beam.json") << scene_text;
  // Deform workspace (f5), run, pause after 30 steps or more; e gives the keyboard to the first
  // parameter (the beam's Young's modulus): type 4e5, enter; run 30 steps more and pause.
  nlohmann::json first = wait(5, "deform_steps"), second = wait(24, "deform_steps");
  first["steps"] = 30;
  second["steps"] = 30;
  nlohmann::json events = nlohmann::json::array(
      {key(1, "key_down", "f5", false), key(2, "key_up", "f5", false), key(3, "key_down", "space", false),
       key(4, "key_up", "space", false), first, key(6, "key_down", "space", false), key(7, "key_up", "space", false),
       wait(8, "idle"), key(10, "key_down", "e", false), key(11, "key_up", "e", false)});
  std::int64_t frame = 14;
  for (char c : std::string("4e5")) {
    nlohmann::json ch = event(frame++, "char");
    ch["codepoint"] = int(c);
    events.push_back(ch);
  }
  for (const auto& e : {key(18, "key_down", "enter", false), key(19, "key_up", "enter", false),
                        key(22, "key_down", "space", false), key(23, "key_up", "space", false), second,
                        key(25, "key_down", "space", false), key(26, "key_up", "space", false), wait(27, "idle"),
                        event(32, "quit")})
    events.push_back(e);
  write_script(dir / "modulus.json", events);
  const auto r = run_view(fmt::format("{} --script {} --deform-log {}", (dir / "beam.json").string(),
                                      (dir / "modulus.json").string(), (dir / "log.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json log = read_json(dir / "log.json");
  ASSERT_EQ(log["changes"].size(), 1u) << log["changes"].dump();
  const nlohmann::json& change = log["changes"][0];
  EXPECT_EQ(change["pointer"], "/bodies/0/material/youngs_modulus_pa");
  EXPECT_EQ(change["value"].get<double>(), 4e5);
  EXPECT_EQ(log["parameters"][0]["value"].get<double>(), 4e5);
  const std::int64_t at = change["step"].get<std::int64_t>(), steps = log["final"]["steps"].get<std::int64_t>();
  EXPECT_GE(at, 30);
  ASSERT_GE(steps, at + 30);

  // The library: the scene for `at` steps, then the model's set_youngs_modulus and on to the
  // window's last step (the same world: the implicit solver's warm start and the rotations go
  // on); beside it the run the change did not happen in.
  io::Scene a = io::parse_scene(scene_text, "beam.json", dir);
  for (std::int64_t i = 0; i < at; ++i) a.world.step(a.dt_s);
  io::Scene b = io::parse_scene(scene_text, "beam.json", dir);
  for (std::int64_t i = 0; i < at; ++i) b.world.step(b.dt_s);
  dynamic_cast<sim::TetFemModel&>(*b.world.models()[b.bodies[0].model_index]).set_youngs_modulus(4e5);
  for (std::int64_t i = at; i < steps; ++i) {
    b.world.step(b.dt_s);
    a.world.step(a.dt_s);
  }
  const auto& window = log["final"]["positions_mm"];
  ASSERT_EQ(window.size(), b.world.particles().size());
  double moved = 0.0;  // how far the stiffer beam is from where the softer one would be
  for (std::size_t i = 0; i < window.size(); ++i) {
    const Vec3& p = b.world.particles().positions()[i];
    for (int c = 0; c < 3; ++c) EXPECT_EQ(window[i][std::size_t(c)].get<double>(), p[c]) << "particle " << i;
    moved = std::max(moved, (p - a.world.particles().positions()[i]).norm());
  }
  EXPECT_GT(moved, 0.05) << "the new modulus changed the motion";
}

TEST_F(ViewWindow, PathReplayedInTheDrillWorkspaceRemovesWhatIdoDrillRemoves) {
  ASSERT_EQ(test::run_tool(fmt::format("tetmesh --shape block:16,16,8 -o {} -q", (dir / "block.vtu").string())).exit_code, 0);
  // Down into the block's top (z = 8) from 4 mm above it to 3 mm in, across 2 mm, then hold.
  std::ofstream(dir / "path.csv") << "t,x,y,z\n0,8,8,12\n0.8,8,8,5\n1.2,10,8,5\n1.4,10,8,5\n";
  nlohmann::json shot = event(8, "screenshot");
  shot["name"] = "replay.png";
  write_script(dir / "replay.json", {key(1, "key_down", "f4", false), key(2, "key_up", "f4", false),
                                     key(3, "key_down", "p", false), key(4, "key_up", "p", false), wait(5, "idle"), shot,
                                     event(9, "quit")});
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --drill-replay {} --drill-report {} --drill-path {}",
                                      (dir / "block.vtu").string(), (dir / "replay.json").string(),
                                      (dir / "shots").string(), (dir / "path.csv").string(),
                                      (dir / "view_drill.json").string(), (dir / "recorded.csv").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json view_report = read_json(dir / "view_drill.json");
  EXPECT_EQ(view_report["source"], "path:" + (dir / "path.csv").string());
  const double removed = view_report["removed_volume_mm3"].get<double>();
  EXPECT_GT(removed, 20.0) << "the burr went 3 mm deep and 2 mm across: tens of mm³";
  const double replayed = drill_replay_removed(dir, dir / "path.csv", "sphere:radius=2");
  EXPECT_TRUE(test::rel_near(removed, replayed, 0.02)) << removed << " vs " << replayed;
  // The tool followed the path: the recorded path ends where the replayed one does.
  const auto recorded = drill::ScriptedTrajectory::load_csv(dir / "recorded.csv");
  EXPECT_TRUE(test::near((recorded.poses().back().position_mm - Vec3(10, 8, 5)).norm(), 0.0, 1e-9));
  EXPECT_GE(recorded.duration(), 1.35);
  // The window shows the drilled block.
  const test::Png png = test::read_png(dir / "shots" / "replay.png");
  ASSERT_EQ(png.w, kWidth);
  const view::PixelRect views{340, 0, 620, 640};
  EXPECT_GT(count(png, views, [](int red, int green, int blue) { return red > 100 && red >= green && green > blue + 10 && red - blue < 90; }), 20000);
}

TEST_F(ViewWindow, TurnedToolWithAShaftRecordsItsOrientationAndReplaysInIdoDrill) {
  ASSERT_EQ(test::run_tool(fmt::format("tetmesh --shape block:16,16,8 -o {} -q", (dir / "block.vtu").string())).exit_code, 0);
  // Drill workspace (f4); tilt the tool's axis (its shaft, radius 1 mm) by 3 × 15° (k); start
  // (d), drag the burr down into the block over 20 frames, stop (d), wait for the drain.
  nlohmann::json events = nlohmann::json::array({key(1, "key_down", "f4", false), key(2, "key_up", "f4", false)});
  for (int i = 0; i < 3; ++i) {
    events.push_back(key(3 + 2 * i, "key_down", "k", false));
    events.push_back(key(4 + 2 * i, "key_up", "k", false));
  }
  for (const auto& e : {key(10, "key_down", "d", false), key(11, "key_up", "d", false), mouse(12, "mouse_down", 650, 320)})
    events.push_back(e);
  double y = 320;
  for (int f = 13; f < 33; ++f) events.push_back(mouse(f, "mouse_move", 650, y += 9));
  for (const auto& e : {mouse(33, "mouse_up", 650, y), key(36, "key_down", "d", false), key(37, "key_up", "d", false),
                        wait(38, "idle"), event(39, "quit")})
    events.push_back(e);
  write_script(dir / "turned.json", events);
  const auto r = run_view(fmt::format("{} --script {} --shaft-radius 1 --drill-path {} --drill-report {}",
                                      (dir / "block.vtu").string(), (dir / "turned.json").string(),
                                      (dir / "path.csv").string(), (dir / "view_drill.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json view_report = read_json(dir / "view_drill.json");
  EXPECT_EQ(view_report["shaft_radius_mm"].get<double>(), 1.0);
  const double removed = view_report["removed_volume_mm3"].get<double>();
  EXPECT_GT(removed, 10.0);
  // The path has the orientation: the axis tilted 45° from +z towards +x.
  EXPECT_EQ(slurp(dir / "path.csv").substr(0, 20), "t,x,y,z,qx,qy,qz,qw\n");
  const auto path = drill::ScriptedTrajectory::load_csv(dir / "path.csv");
  const Vec3 axis = path.poses().back().orientation * Vec3::UnitZ();
  EXPECT_TRUE(test::near((axis - Vec3(std::sqrt(0.5), 0, std::sqrt(0.5))).norm(), 0.0, 1e-12)) << axis.transpose();
  // `ido drill` with the same tool replays it to the same removed volume.
  const double replayed = drill_replay_removed(dir, dir / "path.csv", "sphere:radius=2,shaft=1");
  EXPECT_TRUE(test::rel_near(removed, replayed, 0.02)) << removed << " vs " << replayed;
}

/// A UDP socket on 127.0.0.1 for the test's device: sends pose packets to @p port, receives forces.
class TestDevice {
 public:
  explicit TestDevice(std::uint16_t port) {
    m_socket = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    timeval tv{0, 1000};  // 1 ms: receiving paces the sending
    ::setsockopt(m_socket, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
    m_to.sin_family = AF_INET;
    m_to.sin_port = htons(port);
    m_to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~TestDevice() { ::close(m_socket); }
  TestDevice(const TestDevice&) = delete;
  TestDevice& operator=(const TestDevice&) = delete;
  /// Sends the pose; true when a force packet came back within 1 ms.
  bool send(const Vec3& position_mm, bool end = false) {
    drill::PosePacket p;
    p.sequence = ++m_sequence;
    p.flags = end ? 1U : 0U;
    p.pose.position_mm = position_mm;
    const auto bytes = drill::encode_pose(p);
    (void)::sendto(m_socket, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&m_to), sizeof(m_to));
    std::array<std::uint8_t, 256> buf{};
    const ssize_t n = ::recv(m_socket, buf.data(), buf.size(), 0);
    drill::ForcePacket f;
    return n > 0 && drill::decode_force(buf.data(), std::size_t(n), f);
  }

 private:
  int m_socket = -1;
  sockaddr_in m_to{};
  std::uint32_t m_sequence = 0;
};

/// A UDP port free on 127.0.0.1 now.
std::uint16_t free_udp_port() {
  const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  (void)::bind(s, reinterpret_cast<const sockaddr*>(&a), sizeof(a));
  socklen_t len = sizeof(a);
  ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(s);
  return ntohs(a.sin_port);
}

TEST_F(ViewWindow, DeviceOverTheUdpBridgeDrillsAndItsRecordedPathReplaysInIdoDrill) {
  ASSERT_EQ(test::run_tool(fmt::format("tetmesh --shape block:16,16,8 -o {} -q", (dir / "block.vtu").string())).exit_code, 0);
  const std::uint16_t port = free_udp_port();
  // Drill workspace (f4), connect the device (u); the session ends with the device's last packet.
  write_script(dir / "device.json", {key(1, "key_down", "f4", false), key(2, "key_up", "f4", false),
                                     key(3, "key_down", "u", false), key(4, "key_up", "u", false), wait(5, "idle"),
                                     event(6, "quit")});
  test::CommandResult r;
  std::thread window([&] {
    r = run_view(fmt::format("{} --script {} --drill-udp {} --drill-path {} --drill-report {}", (dir / "block.vtu").string(),
                             (dir / "device.json").string(), port, (dir / "recorded.csv").string(),
                             (dir / "view_drill.json").string()),
                 dir);
  });
  // The device: above the block until the bridge answers, then 3 mm into the block's top and
  // 2 mm across over about a second, then the end-of-session packet.
  TestDevice device(port);
  const Vec3 hover(8, 8, 12);
  bool answered = false;
  for (auto t0 = std::chrono::steady_clock::now();
       !answered && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    answered = device.send(hover);
  const auto start = std::chrono::steady_clock::now();
  Vec3 p = hover;
  for (double t = 0; answered && t < 1.2;) {
    t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    p = t < 0.8 ? Vec3(8, 8, 12 - 7 * t / 0.8) : Vec3(8 + 2 * std::min(1.0, (t - 0.8) / 0.3), 8, 5);
    (void)device.send(p);
  }
  (void)device.send(p, /*end=*/true);
  window.join();
  ASSERT_TRUE(answered) << "the bridge never sent a force back";
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json view_report = read_json(dir / "view_drill.json");
  EXPECT_EQ(view_report["source"], fmt::format("udp:{}", port));
  const double removed = view_report["removed_volume_mm3"].get<double>();
  EXPECT_GT(removed, 20.0) << "the device took the burr 3 mm deep and 2 mm across";
  // The tool followed the device: the recorded path starts at the hover pose and ends at the last.
  const auto recorded = drill::ScriptedTrajectory::load_csv(dir / "recorded.csv");
  EXPECT_TRUE(test::near((recorded.poses().front().position_mm - hover).norm(), 0.0, 1e-12));
  EXPECT_TRUE(test::near((recorded.poses().back().position_mm - p).norm(), 0.0, 1e-12));
  // Replayed by `ido drill`, the recorded session removes the same volume (the threads' sampling: 2 %).
  const double replayed = drill_replay_removed(dir, dir / "recorded.csv", "sphere:radius=2");
  EXPECT_TRUE(test::rel_near(removed, replayed, 0.02)) << removed << " vs " << replayed;
}

TEST_F(ViewWindow, RegionOfInterestDrawnOnTheSlicesGivesIdoSegmentsSurfaceWithThatRegion) {
  // ctrl+drag on the axial slice (k = 13) from voxel (8, 6) to (20, 26): the region spans those
  // voxels in i and j, edge to edge; then ctrl+drag on the coronal slice (j = 16) from (8, 7) to
  // (20, 18) sets i again and k. A click at voxel (14, 16) of the axial slice places the seed.
  const view::SliceView axial(2, ct.size(), ct.spacing(), kAxial), coronal(1, ct.size(), ct.spacing(), kCoronal);
  const auto [a0x, a0y] = axial.pixel_of(8, 6);
  const auto [a1x, a1y] = axial.pixel_of(20, 26);
  const auto [c0x, c0y] = coronal.pixel_of(8, 7);
  const auto [c1x, c1y] = coronal.pixel_of(20, 18);
  const auto [sx, sy] = axial.pixel_of(14, 16);
  nlohmann::json shot = event(14, "screenshot");
  shot["name"] = "roi.png";
  write_script(dir / "roi.json",
               {ctrl_mouse(1, "mouse_down", a0x, a0y), mouse(2, "mouse_move", (a0x + a1x) / 2, (a0y + a1y) / 2),
                mouse(3, "mouse_move", a1x, a1y), ctrl_mouse(4, "mouse_up", a1x, a1y), ctrl_mouse(5, "mouse_down", c0x, c0y),
                mouse(6, "mouse_move", c1x, c1y), ctrl_mouse(7, "mouse_up", c1x, c1y), mouse(8, "mouse_down", sx, sy),
                mouse(9, "mouse_up", sx, sy), wait(10, "segment_done"), key(11, "key_down", "s", true),
                key(12, "key_up", "s", true), wait(13, "idle"), shot, event(15, "quit")});
  const auto r = run_view(fmt::format("{} --script {} --screenshots {} --surface {} --report {}", ct_path.string(),
                                      (dir / "roi.json").string(), (dir / "shots").string(), (dir / "view.ply").string(),
                                      (dir / "view.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  // The report has the region: the dragged voxels' edges in world coordinates.
  const Vec3 lo = ct.index_to_world(Vec3(7.5, 5.5, 6.5)), hi = ct.index_to_world(Vec3(20.5, 26.5, 18.5));
  const nlohmann::json report = read_json(dir / "view.json");
  ASSERT_TRUE(report["roi_mm"].is_array()) << report["roi_mm"].dump();
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(report["roi_mm"][0][std::size_t(c)].get<double>(), lo[c]) << c;
    EXPECT_EQ(report["roi_mm"][1][std::size_t(c)].get<double>(), hi[c]) << c;
  }
  // `ido segment --roi` with that region and the same seed writes the same surface and report.
  const std::string roi = fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  const auto cli = test::run_tool(fmt::format("segment {} --seed-voxel 14,16,13 --roi {} -o {} --report {} -q", ct_path.string(),
                                              roi, (dir / "cli.ply").string(), (dir / "cli.json").string()));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_EQ(slurp(dir / "view.ply"), slurp(dir / "cli.ply")) << "the window's balloon differs from ido segment --roi's";
  const nlohmann::json cli_report = read_json(dir / "cli.json");
  for (const auto& [k, v] : cli_report.items()) {
    if (k == "seconds" || k == "phase_seconds" || k == "surface" || k == "mask") continue;
    EXPECT_EQ(report[k], v) << k;
  }
  // The region held the balloon: the ball (radius 9 mm) reaches past it in x, the surface does not.
  const geometry::TriangleMesh surface = io::read_triangle_mesh(dir / "view.ply");
  ASSERT_GT(surface.triangle_count(), 100u);
  const geometry::Aabb box = geometry::Aabb::of(surface.vertices);
  const Vec3 centre = ct.index_to_world(Vec3(14, 16, 13));
  EXPECT_LT(centre.x() - 9.0, lo.x() - 1.0);
  EXPECT_GT(box.min.x(), lo.x() - 1.1) << "one voxel of slack at the region's face";
  EXPECT_LT(box.max.x(), hi.x() + 1.1);
  EXPECT_LT(box.max.z() - box.min.z(), hi.z() - lo.z() + 2.4);
  // The region shows as an orange rectangle on the axial slice.
  const test::Png png = test::read_png(dir / "shots" / "roi.png");
  ASSERT_EQ(png.w, kWidth);
  EXPECT_GT(count(png, kAxial, [](int red, int green, int blue) { return red > 220 && green > 110 && green < 170 && blue < 40; }), 150);
}

TEST_F(ViewWindow, MaxRadiusGoesToTheBalloonAndTheReport) {
  // --max-radius sets the panel's bound at start; the saved surface is segment_balloon()'s with
  // BalloonChoices::max_radius_mm, and the report records it. (On this ball the bound does not
  // bind: the seed region itself is what it is measured against.)
  write_script(dir / "radius.json", {wait(1, "segment_done"), key(2, "key_down", "s", true), key(3, "key_up", "s", true),
                                     wait(4, "idle"), event(5, "quit")});
  const auto r = run_view(fmt::format("{} --seed-voxel 14,16,13 --max-radius 7 --script {} --surface {} --report {}",
                                      ct_path.string(), (dir / "radius.json").string(), (dir / "view.ply").string(),
                                      (dir / "view.json").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_EQ(read_json(dir / "view.json")["leak_control"]["max_radius_mm"].get<double>(), 7.0);
  segment::BalloonChoices choices;
  choices.max_radius_mm = 7.0;
  const auto expected = segment::segment_balloon(ct, {ct.index_to_world(Vec3(14, 16, 13))}, segment::balloon_options(choices));
  const geometry::TriangleMesh a = io::read_triangle_mesh(dir / "view.ply");
  ASSERT_GT(a.triangle_count(), 0u);
  io::write_triangle_mesh(dir / "lib.ply", expected.surface);
  EXPECT_EQ(slurp(dir / "view.ply"), slurp(dir / "lib.ply"));
  // (The report's bound is the one the run used: SegmentState::options, handed over by the worker.)
}

TEST_F(ViewWindow, SeveralBodiesInTheDeformWorkspaceGetALegendAndTheirNumbers) {
  // Two beams side by side: coloured by displacement (all zero at rest), so only the legend's
  // markers tell them apart: a swatch per body in the legend, and its number on the body.
  std::ofstream(dir / "two.json") << R"({
    "dt_s": 0.001, "steps": 1, "integrator": "implicit_euler",
    "bodies": [{"name": "left", "mesh": {"generator": "beam", "size_mm": [40, 10, 10], "cells": [4, 1, 1]},
                "model": "corotational_fem", "material": {"youngs_modulus_pa": 2e3, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
               {"name": "right", "mesh": {"generator": "beam", "size_mm": [40, 10, 10], "cells": [4, 1, 1], "origin_mm": [0, 30, 0]},
                "model": "corotational_fem", "material": {"youngs_modulus_pa": 2e3, "poisson_ratio": 0.3, "density_kg_m3": 1000}}]})";
  nlohmann::json shot = event(4, "screenshot");
  shot["name"] = "bodies.png";
  write_script(dir / "bodies.json", {key(1, "key_down", "f5", false), key(2, "key_up", "f5", false), shot, event(5, "quit")});
  const auto r = run_view(fmt::format("{} --script {} --screenshots {}", (dir / "two.json").string(),
                                      (dir / "bodies.json").string(), (dir / "shots").string()),
                          dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const test::Png png = test::read_png(dir / "shots" / "bodies.png");
  ASSERT_EQ(png.w, kWidth);
  // The Deform view is the view area less the colour bar's 120 px: x 340..840; the legend at its top right.
  const view::PixelRect legend{640, 40, 200, 60};
  const Vec3 first(1.0, 0.3, 0.3), second(0.2, 0.9, 1.0);  // the markers of bodies 1 and 2
  auto of = [&](const Vec3& c) { return [c](int red, int green, int blue) { return is_colour(red, green, blue, c); }; };
  EXPECT_GE(count(png, legend, of(first)), 100) << "body 1's swatch";
  EXPECT_GE(count(png, legend, of(second)), 100) << "body 2's swatch";
  // Each number sits on its body's centre as the camera shows it.
  view::OrbitCamera cam;
  cam.frame(Vec3(0, 0, 0), Vec3(40, 40, 10));
  const viz::Camera c = cam.camera();
  for (const auto& [centre, colour] : {std::pair{Vec3(20, 5, 5), first}, {Vec3(20, 35, 5), second}}) {
    const Vec4 clip = c.projection_matrix(500.0 / 640.0) * c.view_matrix() * Vec4(centre.x(), centre.y(), centre.z(), 1);
    const double x = 340 + (clip.x() / clip.w() + 1) / 2 * 500, y = (1 - clip.y() / clip.w()) / 2 * 640;
    EXPECT_GT(count(png, {x - 10, y - 10, 21, 21}, of(colour)), 40) << centre.transpose();
  }
}

TEST_F(ViewWindow, SnapshotDrawsWhatWasOpenedWithoutADisplay) {
  // Two surfaces: light grey and light blue, with a legend naming both; no DISPLAY, no Xvfb.
  io::write_triangle_mesh(dir / "ball.stl", segment::balloon_icosphere(Vec3(0, 0, 0), 10.0, 3));
  io::write_triangle_mesh(dir / "small.ply", segment::balloon_icosphere(Vec3(25, 0, 0), 6.0, 3));
  auto r = run_headless(fmt::format("{} {} --snapshot {} --size 640x480 -q", (dir / "ball.stl").string(),
                                    (dir / "small.ply").string(), (dir / "scene.png").string()),
                        dir);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  test::Png png = test::read_png(dir / "scene.png");
  ASSERT_EQ(png.w, 640);
  ASSERT_EQ(png.h, 480);
  const view::PixelRect all{0, 0, 640, 480}, legend{400, 40, 240, 60};
  const Vec3 grey(0.8, 0.8, 0.85), blue(0.55, 0.75, 0.95);  // the first two objects' colours
  auto of = [](const Vec3& c) { return [c](int red, int green, int blue_) { return is_colour(red, green, blue_, c); }; };
  EXPECT_GE(count(png, legend, of(grey)), 100) << "the first surface's swatch";
  EXPECT_GE(count(png, legend, of(blue)), 100) << "the second surface's swatch";
  // Both surfaces are drawn, lit (shades of their colours) over the whole picture (no panel).
  EXPECT_GT(count(png, all, [](int red, int green, int blue_) { return red > 70 && std::abs(red - green) < 12 && blue_ >= green && blue_ - green < 20; }), 5000);
  EXPECT_GT(count(png, all, [](int red, int green, int blue_) { return blue_ > 80 && blue_ > red + 40 && green > red + 15; }), 1500);
  // A CT with a seed: the snapshot waits for the balloon and shows it in the 3-D view (top
  // right) and its contour on the axial slice (top left).
  r = run_headless(fmt::format("{} --seed-voxel 14,16,13 --snapshot {} --size 640x480", ct_path.string(),
                               (dir / "segment.png").string()),
                   dir);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("segment.png"), std::string::npos) << r.out;
  png = test::read_png(dir / "segment.png");
  ASSERT_EQ(png.w, 640);
  EXPECT_GT(count(png, {320, 0, 320, 240}, [](int red, int green, int blue_) { return red > 90 && red > green + 25 && green > blue_ + 10; }), 400);
  EXPECT_GT(count(png, {0, 0, 320, 240}, [](int red, int green, int blue_) { return red > 200 && green < 90 && blue_ < 90; }), 30);
  // Bad: not a PNG name; a script (a snapshot has no window to replay into).
  r = run_headless(fmt::format("{} --snapshot {}", ct_path.string(), (dir / "x.jpg").string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--snapshot"), std::string::npos) << r.err;
}

TEST_F(ViewWindow, BadInputIsExitTwoAndNoDisplayIsExitOne) {
  auto r = run_view(fmt::format("{} --script {}", ct_path.string(), (dir / "missing.json").string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;
  nlohmann::json shot = event(1, "screenshot");
  shot["name"] = "x.png";
  write_script(dir / "shot.json", nlohmann::json::array({shot}));
  r = run_view(fmt::format("{} --script {}", ct_path.string(), (dir / "shot.json").string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--screenshots"), std::string::npos) << r.err;
  r = run_view(fmt::format("{} --seed-voxel 99,0,0 --frames 1", ct_path.string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--seed-voxel 99,0,0"), std::string::npos) << r.err;
  r = run_view(fmt::format("{} --surface {} --frames 1", ct_path.string(), (dir / "s.txt").string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  r = run_view(fmt::format("{} --stop-voxel 0,0,99 --frames 1", ct_path.string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--stop-voxel 0,0,99"), std::string::npos) << r.err;
  r = run_view(fmt::format("{} --drill-replay {} --frames 1", ct_path.string(), (dir / "no-path.csv").string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no-path.csv"), std::string::npos) << r.err;
  r = run_view(fmt::format("{} --max-radius -1 --frames 1", ct_path.string()), dir);  // refused as the library refuses it
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--max-radius"), std::string::npos) << r.err;
  r = run_view(fmt::format("{} --roi 0,0,0,1,1 --frames 1", ct_path.string()), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--roi"), std::string::npos) << r.err;
  r = run_view(fmt::format("{} --shaft-radius 2 --frames 1", ct_path.string()), dir);  // not thinner than the burr
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--shaft-radius"), std::string::npos) << r.err;
  // Without a display the window cannot open: one line saying so, exit 1.
  const int status = std::system(fmt::format("env -u DISPLAY -u WAYLAND_DISPLAY {} view {} --frames 1 >{} 2>&1",
                                             test::tool_path().string(), ct_path.string(),
                                             (dir / "nodisplay.txt").string())
                                     .c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1);
  EXPECT_NE(slurp(dir / "nodisplay.txt").find("display"), std::string::npos) << slurp(dir / "nodisplay.txt");
}

}  // namespace
}  // namespace ido

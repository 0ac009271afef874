// SPDX-License-Identifier: Apache-2.0
// The workbench's parts that need no window: event scripts, the slice layout (which voxel a
// click lands on), the orbit camera's pick ray, and the balloon session on its worker thread
// (its result equals segment_balloon()'s bit for bit however it was paused and stepped).

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"
#include "ido/drill/shapes.h"
#include "ido/io/scene.h"
#include "ido/view/deform_session.h"
#include "ido/view/drill_session.h"
#include "ido/view/event_script.h"
#include "ido/view/orbit_camera.h"
#include "ido/view/segment_output.h"
#include "ido/view/segment_session.h"
#include "ido/view/slice_view.h"
#include "ido/view/tet_section.h"
#include "support/ball_ct.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

using view::EventKind;

// ---- event scripts ---------------------------------------------------------------------------

TEST(EventScript, RoundTripKeepsEveryField) {
  view::EventScript s;
  s.window_width_px = 900;
  s.window_height_px = 600;
  auto add = [&](std::int64_t frame, EventKind kind) -> view::InputEvent& {
    view::InputEvent e;
    e.frame = frame;
    e.kind = kind;
    s.events.push_back(e);
    return s.events.back();
  };
  add(1, EventKind::MouseMove).x_px = 10.5;
  s.events.back().y_px = 20.25;
  auto& down = add(2, EventKind::MouseDown);
  down.x_px = 11;
  down.y_px = 21;
  down.button = 1;
  down.shift = true;  // a shift-click (a stop point on a slice)
  auto& up = add(3, EventKind::MouseUp);
  up.x_px = 12;
  up.y_px = 22;
  up.button = 1;
  auto& scroll = add(3, EventKind::Scroll);
  scroll.x_px = 5;
  scroll.scroll_y = -2;
  auto& key = add(4, EventKind::KeyDown);
  key.key = "s";
  key.ctrl = true;
  key.alt = true;
  add(5, EventKind::KeyUp).key = "s";
  add(5, EventKind::Char).codepoint = 0x41;
  auto& wait = add(6, EventKind::Wait);
  wait.until = "segment_done";
  wait.timeout_s = 30;
  auto& steps = add(6, EventKind::Wait);
  steps.until = "deform_steps";
  steps.steps = 250;
  add(7, EventKind::Screenshot).name = "a.png";
  add(8, EventKind::Quit);
  const view::EventScript back = view::EventScript::parse(s.to_json(), "test");
  EXPECT_EQ(back.window_width_px, 900);
  EXPECT_EQ(back.window_height_px, 600);
  ASSERT_EQ(back.events.size(), s.events.size());
  for (std::size_t i = 0; i < s.events.size(); ++i) {
    const auto &a = s.events[i], &b = back.events[i];
    EXPECT_EQ(a.frame, b.frame);
    EXPECT_EQ(a.kind, b.kind) << i;
    EXPECT_EQ(a.x_px, b.x_px);
    EXPECT_EQ(a.y_px, b.y_px);
    EXPECT_EQ(a.button, b.button);
    EXPECT_EQ(a.scroll_y, b.scroll_y);
    EXPECT_EQ(a.key, b.key);
    EXPECT_EQ(a.ctrl, b.ctrl);
    EXPECT_EQ(a.shift, b.shift) << i;
    EXPECT_EQ(a.alt, b.alt) << i;
    EXPECT_EQ(a.codepoint, b.codepoint);
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.until, b.until);
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_EQ(a.timeout_s, b.timeout_s);
  }
}

TEST(EventScript, MalformedScriptsNameTheEvent) {
  auto message = [](const std::string& text) -> std::string {
    try {
      (void)view::EventScript::parse(text, "s.json");
    } catch (const Error& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"fly\"}]}").find("/events/0/type"), std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 3, \"type\": \"quit\"}, {\"frame\": 2, \"type\": \"quit\"}]}")
                .find("/events/1/frame"),
            std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"mouse_down\", \"button\": \"fourth\"}]}").find("button"),
            std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"screenshot\", \"name\": \"../x.png\"}]}").find("name"),
            std::string::npos);
  EXPECT_NE(message("{\"window\": [10, 10], \"events\": []}").find("/window"), std::string::npos);
  EXPECT_NE(message("{\"events\": [").find("s.json"), std::string::npos);
  EXPECT_NE(message("{\"events\": [{\"frame\": 1, \"type\": \"key_down\", \"key\": \"a\", \"ctrl\": 1}]}").find("/events/0/ctrl"),
            std::string::npos);
  EXPECT_EQ(message("{\"events\": []}"), "accepted");
}

// ---- slice layout --------------------------------------------------------------------------

TEST(SliceView, PixelAndVoxelAreInverseAndMillimetresSquare) {
  const Index3 size = {40, 30, 20};
  const Vec3 spacing(0.8, 1.2, 2.5);
  for (int axis = 0; axis < 3; ++axis) {
    const view::SliceView v(axis, size, spacing, {100, 50, 400, 300});
    const int u = v.u_axis(), w = v.v_axis();
    EXPECT_NE(u, axis);
    EXPECT_NE(w, axis);
    EXPECT_NE(u, w);
    for (std::int64_t a = 0; a < size[std::size_t(u)]; a += 3)
      for (std::int64_t b = 0; b < size[std::size_t(w)]; b += 3) {
        const auto p = v.pixel_of(double(a), double(b));
        EXPECT_TRUE(v.rect().contains(p[0], p[1]));
        const auto back = v.voxel_at(p[0], p[1]);
        ASSERT_TRUE(back);
        EXPECT_EQ((*back)[0], a);
        EXPECT_EQ((*back)[1], b);
        // A quarter of a voxel off the centre still lands on the voxel.
        const auto near = v.voxel_at(p[0] + 0.24 * spacing[u] * v.scale_px_per_mm(), p[1]);
        ASSERT_TRUE(near);
        EXPECT_EQ((*near)[0], a);
      }
    // One voxel step is its spacing in pixels along each axis: millimetres are square.
    const auto p0 = v.pixel_of(0, 0), p1 = v.pixel_of(1, 1);
    EXPECT_TRUE(test::near(std::abs(p1[0] - p0[0]), spacing[u] * v.scale_px_per_mm(), 1e-9));
    EXPECT_TRUE(test::near(std::abs(p1[1] - p0[1]), spacing[w] * v.scale_px_per_mm(), 1e-9));
    // Outside the slice nothing is hit.
    EXPECT_FALSE(v.voxel_at(p0[0] - spacing[u] * v.scale_px_per_mm(), p0[1]));
  }
  // Axial: j grows downwards; coronal and sagittal: k grows upwards (superior up).
  const view::SliceView axial(2, size, spacing, {0, 0, 400, 300}), coronal(1, size, spacing, {0, 0, 400, 300});
  EXPECT_GT(axial.pixel_of(0, 5)[1], axial.pixel_of(0, 0)[1]);
  EXPECT_LT(coronal.pixel_of(0, 5)[1], coronal.pixel_of(0, 0)[1]);
}

TEST(SliceView, NdcMatrixMapsVoxelsWhereThePixelsAre) {
  const view::SliceView v(1, {40, 30, 20}, Vec3(0.8, 1.2, 2.5), {100, 50, 400, 300});
  const Mat4 m = v.ndc_from_index();
  for (const auto& [a, b] : {std::pair{0.0, 0.0}, {39.0, 19.0}, {12.5, 7.0}}) {
    const Vec4 ndc = m * Vec4(a, b, 0, 1);
    const auto p = v.pixel_of(a, b);
    EXPECT_TRUE(test::near(v.rect().x + (ndc.x() + 1) / 2 * v.rect().width, p[0], 1e-9));
    EXPECT_TRUE(test::near(v.rect().y + (1 - ndc.y()) / 2 * v.rect().height, p[1], 1e-9));
  }
}

// ---- orbit camera --------------------------------------------------------------------------

TEST(OrbitCamera, CentreRayHitsTheTargetAndTurningKeepsTheDistance) {
  view::OrbitCamera cam;
  cam.frame(Vec3(-10, -20, 0), Vec3(30, 20, 50));
  const Vec3 target = cam.target();
  for (int turn = 0; turn < 4; ++turn) {
    const auto [origin, dir] = cam.pick_ray(200, 150, 400, 300);
    const double along = (target - origin).dot(dir);
    EXPECT_TRUE(test::near((origin + along * dir - target).norm(), 0.0, 1e-9));
    EXPECT_TRUE(test::near((cam.camera().eye() - target).norm(), cam.distance_mm(), 1e-9));
    cam.rotate(37, -11);
  }
  // A pixel right of the centre looks right of the target.
  const auto [o, d] = cam.pick_ray(300, 150, 400, 300);
  const Mat4 view = cam.camera().view_matrix();
  const Vec3 right = view.block<1, 3>(0, 0).transpose();
  EXPECT_GT(d.dot(right), 0.0);
  const double before = cam.distance_mm();
  cam.zoom(2);
  EXPECT_TRUE(test::near(cam.distance_mm(), before * 0.81, 1e-9));
}

// ---- the Mesh workspace's section and histogram ---------------------------------------------

/// The unit cube in 5 positively oriented tetrahedra (four corners and a regular one inside).
geometry::TetMesh unit_cube() {
  geometry::TetMesh m;
  for (int c = 0; c < 8; ++c) m.vertices.push_back(Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1));
  m.tets = {{0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}, {1, 2, 4, 7}};
  for (Tet& t : m.tets) {
    const auto& v = m.vertices;
    const Vec3 a = v[std::size_t(t[0])];
    if ((v[std::size_t(t[1])] - a).cross(v[std::size_t(t[2])] - a).dot(v[std::size_t(t[3])] - a) < 0) std::swap(t[2], t[3]);
  }
  return m;
}

double area(const geometry::TriangleMesh& m, const Vec3& n, bool* facing) {
  double total = 0;
  *facing = true;
  for (const Tri& t : m.triangles) {
    const Vec3 c = (m.vertices[std::size_t(t[1])] - m.vertices[std::size_t(t[0])])
                       .cross(m.vertices[std::size_t(t[2])] - m.vertices[std::size_t(t[0])]);
    total += 0.5 * c.norm();
    if (c.dot(n) <= 0) *facing = false;
  }
  return total;
}

TEST(TetSection, CutsThroughTetrahedraWithTheCrossSectionsArea) {
  const geometry::TetMesh cube = unit_cube();
  // Parallel to a face: every tetrahedron is cut and the section is the unit square.
  viz::ClipPlane plane{Vec3(0.3, 0.6, 0.37), Vec3(0, 0, 2)};
  view::TetSection s = view::tet_section(cube, plane);
  EXPECT_EQ(s.cut_tets, 5u);
  bool facing = false;
  EXPECT_TRUE(test::near(area(s.faces, Vec3::UnitZ(), &facing), 1.0, 1e-12));
  EXPECT_TRUE(facing) << "section faces face along the normal";
  for (const Vec3& p : s.faces.vertices) EXPECT_TRUE(test::near(p.z(), 0.37, 1e-12));
  EXPECT_GE(s.edges.size(), 15u);  // 4 triangles and a quadrilateral: 3·4 + 4 edges
  // Oblique: x + y + z = 1.5 cuts the cube in a regular hexagon of side √2/2, area 3√3/4.
  plane = {Vec3(0.5, 0.5, 0.5), Vec3(1, 1, 1)};
  s = view::tet_section(cube, plane);
  EXPECT_TRUE(test::near(area(s.faces, Vec3(1, 1, 1), &facing), 3.0 * std::sqrt(3.0) / 4.0, 1e-12));
  EXPECT_TRUE(facing);
  // Beside the mesh: nothing.
  plane = {Vec3(0, 0, 2), Vec3(0, 0, 1)};
  EXPECT_EQ(view::tet_section(cube, plane).cut_tets, 0u);
  EXPECT_THROW((void)view::tet_section(cube, {Vec3::Zero(), Vec3::Zero()}), InvalidInput);
}

TEST(TetSection, DihedralHistogramCountsEveryAngle) {
  const auto h = view::dihedral_histogram(unit_cube(), 36);
  ASSERT_EQ(h.size(), 36u);
  std::size_t total = 0;
  for (std::size_t c : h) total += c;
  EXPECT_EQ(total, 30u);
  EXPECT_EQ(h[14], 6u);   // the regular tetrahedron inside: acos(1/3) = 70.53° (bin 70-75°)
  EXPECT_EQ(h[10], 12u);  // the corner tetrahedra's atan(√2) = 54.74° angles (three each): bin 50-55°
  EXPECT_EQ(h[18], 12u);  // and their 90° angles in bin 90-95°
  EXPECT_THROW((void)view::dihedral_histogram(unit_cube(), 0), InvalidInput);
}

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
  // Stop points the balloon was given are listed with the leak control's figures.
  request.options.leak.stop_points_mm = {Vec3(1.5, -2.25, 40.125)};
  const nlohmann::json with_stop = view::segment_report_json(request, r, {});
  EXPECT_EQ(with_stop["leak_control"]["stop_points_mm"], nlohmann::json::parse("[[1.5, -2.25, 40.125]]"));
  EXPECT_THROW(view::check_segment_outputs({"s.txt", "", ""}), InvalidInput);
  EXPECT_THROW(view::check_segment_outputs({"", "m.stl", ""}), InvalidInput);
  EXPECT_NO_THROW(view::check_segment_outputs({"s.ply", "m.nii.gz", "r.json"}));
}

}  // namespace
}  // namespace ido

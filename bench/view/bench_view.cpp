// SPDX-License-Identifier: Apache-2.0
// Frame rate of the workbench `ido view` (issue 28), one benchmark per workspace, in a
// 1280 × 800 window on whatever display DISPLAY names — in CI and on the project's machine
// Xvfb with Mesa's llvmpipe:
//
//   xvfb-run -a -s '-screen 0 1280x1024x24' build/h-view/bench/view/bench_view
//
// Each benchmark writes its inputs, replays an event script through view::run_workbench (the
// tool's own frame loop, scripted frame time, no vsync), and measures the wall time of the
// frame loop's iterations over a run of frames in which the script waits for nothing; the
// iteration time reported is the median frame, the counters its frames per second and p90.
// The scenes:
//   Scene   a torus of 200 000 triangles (100 000 vertices), the issue's "200 k-triangle surface",
//           still (the 3-D view's picture is copied while nothing in it changes);
//   SceneTurning  the same torus turned by a left drag in the 3-D view, a few pixels every frame
//           (the view is drawn anew each frame: what rasterising 200 k triangles costs);
//   Segment a 128 × 128 × 96 CT of a ball, the balloon finished: three slices and the 3-D view;
//   Mesh    a 60 × 60 × 30 mm block of 81 000 tetrahedra cut by the clip plane through the tetrahedra;
//   Drill   a 32 × 32 × 16 mm block of 1 536 tetrahedra while an 8 s path CSV is replayed on the
//           drilling Simulator's threads (1 kHz haptic loop, collision/erosion, render consumer);
//   Deform  a 120 × 30 × 30 mm beam of 5 184 tetrahedra (corotational FEM, implicit Euler, gravity)
//           running as fast as its worker can step.
// Drill also runs the same path headless (drill::Simulator as `ido drill` runs it) and prints
// the collision update p99 and the haptic force-compute p99.9 of both, the issue's check that
// the window leaves the haptic loop its figures.
// Each benchmark prints a fixed-format line:
//   BENCH view/<workspace> frames=<n> median_ms=<..> fps=<..> p90_ms=<..> <scene figures>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ido/core/math.h"
#include "ido/drill/shapes.h"
#include "ido/drill/simulator.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "ido/view/drill_session.h"
#include "ido/view/workbench.h"

namespace {

using namespace ido;
namespace fs = std::filesystem;

constexpr int kWidth = 1280, kHeight = 800;
constexpr int kMeasuredFrames = 150;  // frames measured per workspace

fs::path work_dir() {
  const char* env = std::getenv("IDO_BENCH_VIEW_DIR");
  fs::path d = env ? env : "bench_view_inputs";
  fs::create_directories(d);
  return d;
}

/// A torus (major radius 40 mm, minor 15 mm) of 2 · nu · nv triangles.
geometry::TriangleMesh torus(int nu, int nv) {
  geometry::TriangleMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.vertices.emplace_back((40 + 15 * std::cos(v)) * std::cos(u), (40 + 15 * std::cos(v)) * std::sin(u), 15 * std::sin(v));
    }
  auto id = [&](int i, int j) { return std::int32_t((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

nlohmann::json key(std::int64_t frame, const char* type, const char* name) {
  return {{"frame", frame}, {"type", type}, {"key", name}};
}
nlohmann::json press(std::int64_t frame, const char* name) {
  return nlohmann::json::array({key(frame, "key_down", name), key(frame + 1, "key_up", name)});
}
nlohmann::json wait(std::int64_t frame, const char* until) {
  return {{"frame", frame}, {"type", "wait"}, {"until", until}, {"timeout", 600}};
}

struct FrameFigures {
  std::size_t frames = 0;
  double median_ms = 0, p90_ms = 0;
  std::size_t drawn = 0;  // frames whose 3-D view was drawn anew
};

/// Runs the workbench on @p files with @p events (then kMeasuredFrames frames and a quit from
/// script frame @p measure_from on) and measures the frames of @p workspace from that frame on.
FrameFigures run(std::vector<fs::path> files, nlohmann::json events, std::int64_t measure_from, view::Workspace workspace,
                 view::WorkbenchOptions options = {}) {
  events.push_back({{"frame", measure_from + kMeasuredFrames + 2}, {"type", "quit"}});
  const fs::path script = work_dir() / "script.json";
  std::ofstream(script) << nlohmann::json{{"window", {kWidth, kHeight}}, {"events", events}}.dump(1);
  options.files = std::move(files);
  options.script = script;
  options.quiet = true;
  const view::WorkbenchStats stats = view::run_workbench(options);
  // Script frames advance on the frames that do not wait.
  std::vector<double> ms;
  std::int64_t script_frame = 0;
  std::size_t drawn = 0;
  for (const view::FrameRecord& f : stats.frames) {
    if (!f.script_waiting && f.workspace == workspace && script_frame >= measure_from + 2 &&
        script_frame < measure_from + kMeasuredFrames) {
      ms.push_back(f.ms);
      drawn += f.view_drawn ? 1 : 0;
    }
    if (!f.script_waiting) ++script_frame;
  }
  FrameFigures out;
  out.frames = ms.size();
  out.drawn = drawn;
  if (ms.empty()) return out;
  std::sort(ms.begin(), ms.end());
  out.median_ms = ms[ms.size() / 2];
  out.p90_ms = ms[std::min(ms.size() - 1, ms.size() * 9 / 10)];
  return out;
}

void report(benchmark::State& state, const std::string& name, const FrameFigures& f, const std::string& extra) {
  state.SetIterationTime(f.median_ms * 1e-3);
  state.counters["fps_median"] = f.median_ms > 0 ? 1e3 / f.median_ms : 0.0;
  state.counters["frame_ms_p90"] = f.p90_ms;
  state.counters["frames"] = double(f.frames);
  std::printf("BENCH view/%s frames=%zu median_ms=%.2f fps=%.1f p90_ms=%.2f drawn=%zu %s\n", name.c_str(), f.frames,
              f.median_ms, f.median_ms > 0 ? 1e3 / f.median_ms : 0.0, f.p90_ms, f.drawn, extra.c_str());
}

nlohmann::json concat(std::initializer_list<nlohmann::json> parts) {
  nlohmann::json all = nlohmann::json::array();
  for (const auto& p : parts)
    for (const auto& e : p) all.push_back(e);
  return all;
}

void BM_Scene(benchmark::State& state) {
  const geometry::TriangleMesh surface = torus(500, 200);
  const fs::path file = work_dir() / "torus_200k.ply";
  io::write_triangle_mesh(file, surface);
  for (auto _ : state) {
    const FrameFigures f = run({file}, press(1, "f2"), 5, view::Workspace::Scene);
    report(state, "scene", f, "triangles=" + std::to_string(surface.triangle_count()));
  }
}

void BM_SceneTurning(benchmark::State& state) {
  const geometry::TriangleMesh surface = torus(500, 200);
  const fs::path file = work_dir() / "torus_200k.ply";
  io::write_triangle_mesh(file, surface);
  // Press in the 3-D view at frame 4, then 3 px to the right every frame: the camera turns.
  nlohmann::json events = press(1, "f2");
  events.push_back({{"frame", 4}, {"type", "mouse_down"}, {"x", 800}, {"y", 400}, {"button", "left"}});
  for (int i = 1; i <= kMeasuredFrames + 2; ++i)
    events.push_back({{"frame", 4 + i}, {"type", "mouse_move"}, {"x", 800 + 3 * (i % 100)}, {"y", 400}});
  for (auto _ : state) {
    const FrameFigures f = run({file}, events, 5, view::Workspace::Scene);
    report(state, "scene_turning", f, "triangles=" + std::to_string(surface.triangle_count()));
  }
}

void BM_Segment(benchmark::State& state) {
  image::Volume<float> ct({128, 128, 96}, Vec3(0.8, 0.8, 1.0), Vec3::Zero());
  const Vec3 centre = ct.index_to_world(Vec3(64, 64, 48));
  for (std::int64_t k = 0; k < ct.size(2); ++k)
    for (std::int64_t j = 0; j < ct.size(1); ++j)
      for (std::int64_t i = 0; i < ct.size(0); ++i)
        ct(i, j, k) = (ct.index_to_world(Vec3(double(i), double(j), double(k))) - centre).norm() < 20.0 ? 350.f : 40.f;
  const fs::path file = work_dir() / "ball_ct.nii.gz";
  io::write_volume(file, ct);
  view::WorkbenchOptions o;
  o.seed_voxels = {{64, 64, 48}};
  for (auto _ : state) {
    const FrameFigures f = run({file}, nlohmann::json::array({wait(1, "segment_done")}), 3, view::Workspace::Segment, o);
    report(state, "segment", f, "voxels=128x128x96");
  }
}

void BM_Mesh(benchmark::State& state) {
  const geometry::TetMesh block = drill::make_block(Vec3(60, 60, 30), 2.0);
  const fs::path file = work_dir() / "block_81k.vtu";
  io::write_tet_mesh(file, block);
  for (auto _ : state) {
    const FrameFigures f = run({file}, concat({press(1, "f3"), press(3, "t"), {wait(5, "idle")}}), 7, view::Workspace::Mesh);
    report(state, "mesh", f, "tets=" + std::to_string(block.tets.size()));
  }
}

/// Percentiles (ms) of seconds.
drill::Percentiles ms(std::vector<double> s) {
  for (double& x : s) x *= 1e3;
  return drill::percentiles(std::move(s));
}

void BM_Drill(benchmark::State& state) {
  const geometry::TetMesh block = drill::make_block(Vec3(32, 32, 16), 4.0);
  const fs::path file = work_dir() / "drill_block.vtu", path = work_dir() / "drill_path.csv",
                 report_file = work_dir() / "drill_window.json";
  io::write_tet_mesh(file, block);
  // 2 mm deep along the top, 24 mm in 6 s (4 mm/s), after 1 s going down; 8 s in all.
  std::ofstream(path) << "t,x,y,z\n0,4,16,20\n1,4,16,14\n7,28,16,14\n8,28,16,14\n";
  view::WorkbenchOptions o;
  o.drill_replay = path;
  o.drill_report = report_file;
  for (auto _ : state) {
    // Replay (p) from script frame 3 on; frames measured while it runs; then wait for its end.
    nlohmann::json events = concat({press(1, "f4"), press(3, "p")});
    events.push_back(wait(5 + kMeasuredFrames, "idle"));
    const FrameFigures f = run({file}, events, 5, view::Workspace::Drill, o);
    // The same path headless, as `ido drill` runs it.
    const drill::SimulatorOptions so = view::drill_cli_options(2.0);
    auto device = view::load_path_device(path, so);
    drill::TetHierarchy hierarchy(block);
    drill::SimulatorOptions headless = so;
    const auto ticks = static_cast<std::size_t>((device->duration() + so.drain_limit_s + 1.0) / so.haptic_period_s) + 1024;
    headless.max_haptic_ticks = std::min(ticks, so.max_haptic_ticks);
    drill::Simulator sim(hierarchy, *device, headless);
    sim.run(device->duration() + so.drain_limit_s + 30.0);
    const drill::SessionStats& st = sim.stats();
    std::ifstream in(report_file);
    const nlohmann::json w = nlohmann::json::parse(in);
    const drill::Percentiles upd = ms(st.update_time_s), force = ms(st.force_compute_time_s), period = ms(st.haptic_period_s);
    const double w_update = w["update_time_ms"]["p99"].get<double>(), w_force = w["force_compute_ms"]["p999"].get<double>();
    char extra[768];
    std::snprintf(extra, sizeof extra,
                  "tets=%zu window: update_p50_ms=%.3f update_p99_ms=%.3f force_p999_ms=%.4f period_p99_ms=%.3f missed=%lld "
                  "removed_mm3=%.2f headless: update_p50_ms=%.3f update_p99_ms=%.3f force_p999_ms=%.4f period_p99_ms=%.3f "
                  "missed=%zu removed_mm3=%.2f ratio: update_p99=%.3f force_p999=%.3f",
                  block.tets.size(), w["update_time_ms"]["p50"].get<double>(), w_update, w_force,
                  w["haptic_period_ms"]["p99"].get<double>(), w["missed_deadlines"].get<long long>(),
                  w["removed_volume_mm3"].get<double>(), upd.p50, upd.p99, force.p999, period.p99, st.missed_deadlines,
                  st.removed_volume_mm3, w_update / upd.p99, w_force / force.p999);
    state.counters["window_update_p99_ms"] = w_update;
    state.counters["headless_update_p99_ms"] = upd.p99;
    state.counters["ratio_update_p99"] = w_update / upd.p99;
    state.counters["ratio_force_p999"] = w_force / force.p999;
    report(state, "drill", f, extra);
  }
}

void BM_Deform(benchmark::State& state) {
  const fs::path file = work_dir() / "beam.json";
  std::ofstream(file) << R"({
    "dt_s": 0.01, "steps": 1, "integrator": "implicit_euler", "gravity_mm_s2": [0, 0, -9806.65],
    "damping": {"rayleigh_mass_per_s": 1.0},
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [120, 30, 30], "cells": [24, 6, 6]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.45, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 31, 31]}]}]})";
  for (auto _ : state) {
    // Run (space) from script frame 3 on, measured while the worker steps.
    const FrameFigures f = run({file}, concat({press(1, "f5"), press(3, "space")}), 5, view::Workspace::Deform);
    report(state, "deform", f, "tets=5184");
  }
}

BENCHMARK(BM_Scene)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SceneTurning)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Segment)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Mesh)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Drill)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

// SPDX-License-Identifier: Apache-2.0
// Simulation benchmarks (issue 3): corotational FEM + implicit Euler (CG to 1e-6) on beams
// of ~1k, 6.1k/7.4k (8×26×8 vertices, SOFA's benchmark beam) and ~50k tetrahedra; explicit
// mass–spring at 100k springs; shape matching and MLS at 10k particles. Single thread
// (World::set_threaded(false)) unless the name says "threads".
//
// Each beam mesh is written to $IDO_BENCH_MESH_DIR (default ./bench_sim_meshes) as .vtu and
// TetGen .node/.ele so other engines can run the same meshes, and each benchmark prints a
// fixed-format line:  BENCH <name> ms/step=<median> cg_iterations=<mean>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "ido/io/mesh_io.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/mls.h"
#include "ido/sim/shape_matching.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"

namespace {

using namespace ido;

std::filesystem::path mesh_dir() {
  const char* env = std::getenv("IDO_BENCH_MESH_DIR");
  std::filesystem::path d = env ? env : "bench_sim_meshes";
  std::filesystem::create_directories(d);
  return d;
}

void report_line(const std::string& name, std::vector<double> ms, double cg_mean) {
  std::sort(ms.begin(), ms.end());
  std::printf("BENCH %s ms/step=%.3f cg_iterations=%.1f\n", name.c_str(), ms[ms.size() / 2], cg_mean);
}

/// Beam along y, fixed at y = 0, sagging under gravity; 10 mm cells, E = 100 kPa, ν = 0.45,
/// 1000 kg/m³, dt = 10 ms, Rayleigh mass damping 1/s.
void BM_BeamCorotationalImplicit(benchmark::State& state) {
  const Vec3i cells(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                    static_cast<int>(state.range(2)));
  const auto split = state.range(3) == 5 ? sim::HexSplit::Five : sim::HexSplit::Six;
  const bool threaded = state.range(4) != 0;
  const int cg_cap = state.range(5) > 0 ? static_cast<int>(state.range(5)) : 1000;
  const bool jacobi = state.range(6) != 0;
  const auto mesh = sim::make_beam(10.0 * cells.cast<double>(), cells, Vec3::Zero(), split);
  const std::string name = "beam_" + std::to_string(cells.x() + 1) + "x" + std::to_string(cells.y() + 1) +
                           "x" + std::to_string(cells.z() + 1) + "v_" + std::to_string(mesh.tets.size()) + "t";
  io::write_tet_mesh(mesh_dir() / (name + ".vtu"), mesh);
  io::write_tet_mesh(mesh_dir() / (name + ".node"), mesh);
  sim::World w;
  w.set_threaded(threaded);
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<sim::CorotationalFem>(mesh.tets, w.particles().positions(), sim::ElasticMaterial{1e5, 0.45});
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (mesh.vertices[i].y() < 1e-9) w.particles().set_fixed(i, true);
  w.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  w.external().damping.mass_per_s = 1.0;
  w.set_integrator("implicit_euler");
  w.implicit_options().cg_tolerance = 1e-6;
  w.implicit_options().cg_max_iterations = cg_cap;
  w.implicit_options().preconditioner =
      jacobi ? sim::CgPreconditioner::Jacobi : sim::CgPreconditioner::SymmetricGaussSeidel;
  std::vector<double> ms;
  double cg = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    w.step(0.01);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    cg += w.last_step().cg_iterations;
  }
  state.counters["tets"] = static_cast<double>(mesh.tets.size());
  state.counters["cg_iterations"] = cg / static_cast<double>(state.iterations());
  report_line(name + (threaded ? "_threads" : "_1core") + (cg_cap < 1000 ? "_cg" + std::to_string(cg_cap) : "") +
                        (jacobi ? "_jacobi" : "_sgs"), ms, cg / static_cast<double>(state.iterations()));
}
BENCHMARK(BM_BeamCorotationalImplicit)
    // cells x, y, z; tets per hex; threads; CG iteration cap (0: none, CG runs to 1e-6);
    // preconditioner (0: symmetric block SOR, ω = 1.3, the default; 1: Jacobi)
    ->Args({4, 12, 4, 5, 0, 0, 0})     // 5×13×5 vertices, 960 tets
    ->Args({4, 12, 4, 5, 0, 0, 1})
    ->Args({7, 25, 7, 5, 0, 0, 0})     // 8×26×8 vertices, 6125 tets (5 per hex)
    ->Args({7, 25, 7, 5, 0, 0, 1})
    ->Args({7, 25, 7, 6, 0, 0, 0})     // 8×26×8 vertices, 7350 tets (6 per hex)
    ->Args({7, 25, 7, 6, 0, 0, 1})
    ->Args({7, 25, 7, 6, 0, 25, 0})    // same, CG capped at 25 iterations as in SOFA's scene
    ->Args({7, 25, 7, 6, 0, 25, 1})
    ->Args({14, 50, 14, 5, 0, 0, 0})   // 15×51×15 vertices, 49000 tets
    ->Args({14, 50, 14, 5, 1, 0, 0})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

/// 100k springs (tet edges of a 22×22×30-cell block), symplectic Euler.
void BM_MassSpringExplicit(benchmark::State& state) {
  const auto mesh = sim::make_beam({220, 220, 300}, {22, 22, 30});
  sim::World w;
  w.set_threaded(false);
  w.add_tet_body(mesh, 1000.0);
  auto& ms_model = w.emplace_model<sim::MassSpring>(sim::MassSpring::from_tet_edges(mesh, 0, 1.0, 1e-3));
  w.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  w.set_integrator("symplectic_euler");
  std::vector<double> ms;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    w.step(1e-4);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  state.counters["springs"] = static_cast<double>(ms_model.springs().size());
  state.counters["steps_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  report_line("mass_spring_" + std::to_string(ms_model.springs().size()) + "springs", ms, 0.0);
}
BENCHMARK(BM_MassSpringExplicit)->Unit(benchmark::kMillisecond)->MinTime(2.0);

sim::Particles grid_particles(int n, double spacing) {
  sim::Particles p;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) p.add(spacing * Vec3(i, j, k) + 0.01 * Vec3((i * 7) % 3, (j * 5) % 3, (k * 3) % 3), 1e-3);
  return p;
}

/// 10k particles (22³ = 10648), linear shape matching with overlapping grid clusters.
void BM_ShapeMatching(benchmark::State& state) {
  sim::World w;
  w.set_threaded(false);
  w.particles() = grid_particles(22, 2.0);
  sim::ShapeMatchingOptions o;
  o.mode = sim::ShapeMatchingMode::Linear;
  w.emplace_model<sim::ShapeMatching>(w.particles(), sim::grid_clusters(w.particles().positions(), 6.0), o);
  w.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  std::vector<double> ms;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    w.step(1e-3);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  state.counters["steps_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  report_line("shape_matching_" + std::to_string(w.particles().size()) + "particles", ms, 0.0);
}
BENCHMARK(BM_ShapeMatching)->Unit(benchmark::kMillisecond)->MinTime(2.0);

/// 10k particles, MLS elasticity with h = 2.2 × spacing.
void BM_Mls(benchmark::State& state) {
  sim::World w;
  w.set_threaded(false);
  w.particles() = grid_particles(22, 2.0);
  std::vector<std::int32_t> ids(w.particles().size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::int32_t>(i);
  sim::MlsOptions o;
  o.support_radius_mm = 4.4;
  o.material = {1e5, 0.3};
  w.emplace_model<sim::MlsElasticity>(w.particles(), ids, o);
  w.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  std::vector<double> ms;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    w.step(1e-4);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  state.counters["steps_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  report_line("mls_" + std::to_string(w.particles().size()) + "particles", ms, 0.0);
}
BENCHMARK(BM_Mls)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();

// SPDX-License-Identifier: Apache-2.0
// Marching cubes throughput on a 256³ field (the union distance field of 24 random spheres),
// ido::meshing::marching_cubes against VTK's vtkFlyingEdges3D on the same buffer, each
// single-threaded and threaded. Throughput counter: voxels per second.
//
//   bench_marching_cubes --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "ido/core/parallel.h"
#include "ido/meshing/marching_cubes.h"

#ifdef IDO_BENCH_WITH_VTK
#include "vtk_flying_edges_peer.h"
#endif

namespace {

constexpr std::int64_t kN = 256;

/// Signed distance (mm) to the union of 24 random spheres, on a 256³ grid of 1 mm voxels.
const ido::image::Volume<float>& field() {
  static const ido::image::Volume<float> f = [] {
    ido::image::Volume<float> v({kN, kN, kN});
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> pos(30.0, kN - 30.0), rad(8.0, 28.0);
    std::vector<std::pair<ido::Vec3, double>> balls;
    for (int s = 0; s < 24; ++s) balls.push_back({ido::Vec3(pos(rng), pos(rng), pos(rng)), rad(rng)});
    ido::parallel_for(static_cast<std::size_t>(kN * kN), [&](std::size_t r) {
      const double j = double(std::int64_t(r) % kN), k = double(std::int64_t(r) / kN);
      float* row = v.data().data() + r * kN;
      for (std::int64_t i = 0; i < kN; ++i) {
        double d = 1e30;
        for (const auto& [c, rr] : balls) d = std::min(d, (ido::Vec3(double(i), j, k) - c).norm() - rr);
        row[i] = float(d);
      }
    });
    return v;
  }();
  return f;
}

void report(benchmark::State& state, std::size_t vertices, std::size_t triangles) {
  state.counters["voxels_per_s"] =
      benchmark::Counter(double(kN * kN * kN), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = double(triangles);
  state.counters["vertices"] = double(vertices);
}

void BM_ido_marching_cubes(benchmark::State& state) {
  const auto& f = field();
  const bool threaded = state.range(0) != 0;
  std::size_t nv = 0, nt = 0;
  for (auto _ : state) {
    auto mesh = ido::meshing::marching_cubes(f, {.iso_value = 0.f, .threaded = threaded});
    nv = mesh.vertices.size();
    nt = mesh.triangles.size();
    benchmark::DoNotOptimize(mesh.vertices.data());
  }
  report(state, nv, nt);
}
BENCHMARK(BM_ido_marching_cubes)->ArgName("threaded")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef IDO_BENCH_WITH_VTK
void BM_vtk_flying_edges(benchmark::State& state) {
  const auto& f = field();
  const bool threaded = state.range(0) != 0;
  const std::string backend = ido::bench::vtk_set_threads(threaded ? int(std::thread::hardware_concurrency()) : 1);
  ido::bench::vtk_prepare(f.data().data(), int(kN));
  ido::bench::PeerResult r;
  for (auto _ : state) {
    r = ido::bench::vtk_flying_edges(0.0);
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel("vtkSMPTools " + backend);
  report(state, r.vertices, r.triangles);
}
BENCHMARK(BM_vtk_flying_edges)->ArgName("threaded")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

}  // namespace

BENCHMARK_MAIN();

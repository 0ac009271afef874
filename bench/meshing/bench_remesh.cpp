// SPDX-License-Identifier: Apache-2.0
// Isotropic remeshing of a marching-cubes level to the grid's spacing, three rounds: what the
// balloon's topology repair does after every rebuild (segment::repair_topology). The level is
// a bent tube (a torus, R = 30 mm, r = 6 mm) and a sphere on a 1-mm grid, about 13k vertices,
// like the repaired vessels of the real cases. Counter: input vertices per second.
//
//   bench_remesh --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <algorithm>
#include <cmath>

#include <benchmark/benchmark.h>

#include "ido/meshing/marching_cubes.h"
#include "ido/meshing/remesh.h"

namespace {

const ido::geometry::TriangleMesh& level() {
  static const ido::geometry::TriangleMesh m = [] {
    constexpr std::int64_t n = 96;
    ido::image::Volume<float> f({n, n, n});
    const ido::Vec3 c(48.0, 48.0, 48.0), ball(48.0, 48.0, 70.0);
    for (std::int64_t k = 0; k < n; ++k)
      for (std::int64_t j = 0; j < n; ++j)
        for (std::int64_t i = 0; i < n; ++i) {
          const ido::Vec3 p(double(i) + 0.3, double(j) + 0.1, double(k) + 0.2);  // off-grid, as a real level
          const ido::Vec3 q = p - c;
          const double ring = std::hypot(std::hypot(q.x(), q.y()) - 30.0, q.z()) - 6.0;
          const double sphere = (p - ball).norm() - 12.0;
          f(i, j, k) = float(std::min(ring, sphere));
        }
    return ido::meshing::marching_cubes(f, {.iso_value = 0.0f, .threaded = false});
  }();
  return m;
}

void BM_remesh_marching_cubes_level(benchmark::State& state) {
  const auto& m = level();
  ido::meshing::RemeshOptions o;
  o.target_edge_mm = 1.0;
  o.iterations = 3;
  std::size_t out = 0;
  for (auto _ : state) {
    auto r = ido::meshing::remesh(m, o);
    out = r.vertices.size();
    benchmark::DoNotOptimize(r);
  }
  state.counters["vertices_in"] = double(m.vertices.size());
  state.counters["vertices_out"] = double(out);
  state.counters["vertices_per_s"] =
      benchmark::Counter(double(m.vertices.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_remesh_marching_cubes_level)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

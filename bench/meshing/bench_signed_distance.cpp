// SPDX-License-Identifier: Apache-2.0
// The balloon's topology-repair signed distance on a repair-sized input: three overlapping
// spheres (a self-intersecting closed surface, 46 k triangles) on a 1-mm grid around them,
// the intersecting triangles left out of the distance as the repair does. Side by side in
// one run: the sign by exact crossing parity (SignMethod::automatic on this closed surface)
// against the hierarchical generalised winding number, at the repair's band (1.05 h) and the
// earlier one (2 h), single-threaded and threaded.
//
//   bench_signed_distance --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "ido/geometry/self_intersection.h"
#include "ido/meshing/signed_distance.h"
#include "ido/segment/balloon.h"

namespace {

using ido::Tri;
using ido::Vec3;

void add_sphere(ido::geometry::TriangleMesh& m, const Vec3& c, double r, int subdivisions) {
  const auto sphere = ido::segment::balloon_icosphere(c, r, subdivisions);  // 20 · 4^s triangles
  const auto base = static_cast<std::int32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), sphere.vertices.begin(), sphere.vertices.end());
  for (const Tri& t : sphere.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

struct Input {
  ido::geometry::TriangleMesh mesh;
  std::vector<std::uint8_t> counted;
  ido::image::Volume<float> grid;
};

const Input& input() {
  static const Input in = [] {
    Input r;
    add_sphere(r.mesh, Vec3(0, 0, 0), 30, 5);
    add_sphere(r.mesh, Vec3(40, 5, 0), 28, 5);
    add_sphere(r.mesh, Vec3(18, 35, 6), 25, 4);
    r.counted.assign(r.mesh.triangles.size(), 1);
    for (const auto& [a, b] : ido::geometry::self_intersections(r.mesh)) r.counted[std::size_t(a)] = r.counted[std::size_t(b)] = 0;
    r.grid = ido::image::Volume<float>({108, 102, 66}, Vec3::Ones(), Vec3(-33, -33, -33));
    return r;
  }();
  return in;
}

// Args: sign (0 crossing parity, 1 winding number), band (× h, in hundredths), threaded.
void BM_RepairSignedDistance(benchmark::State& state) {
  const Input& in = input();
  ido::meshing::SignedDistanceOptions o;
  o.sign = state.range(0) == 0 ? ido::meshing::SignMethod::automatic : ido::meshing::SignMethod::winding_number;
  o.band_mm = double(state.range(1)) / 100.0;
  o.threaded = state.range(2) != 0;
  o.distance_triangles = in.counted;
  std::size_t inside = 0;
  for (auto _ : state) {
    const auto f = ido::meshing::signed_distance(in.mesh, in.grid, o);
    inside = 0;
    for (const float x : f.data()) inside += x < 0 ? 1 : 0;
    benchmark::DoNotOptimize(inside);
  }
  state.counters["triangles"] = double(in.mesh.triangles.size());
  state.counters["inside_voxels"] = double(inside);  // the same for every variant
}
BENCHMARK(BM_RepairSignedDistance)
    ->ArgNames({"winding", "band_hundredths", "threaded"})
    ->ArgsProduct({{0, 1}, {105, 200}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

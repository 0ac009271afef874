// SPDX-License-Identifier: Apache-2.0
// Self-intersection detection on a ~82k-triangle noisy sphere with local folds: ido against
// CGAL's Polygon Mesh Processing (does_self_intersect / self_intersections) in one binary.
//
//   build/bench/bench/geometry/bench_self_intersection --benchmark_repetitions=5 \
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>

#include "ido/geometry/primitives.h"
#include "ido/geometry/self_intersection.h"

#ifdef IDO_BENCH_WITH_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#endif

namespace {

using namespace ido;
using namespace ido::geometry;

/// Icosphere (subdivision 6: 81 920 triangles, radius 10 mm, edges about 0.19 mm) with
/// 0.02 mm of uniform noise on every vertex and 300 vertices dragged 0.4 mm sideways (about
/// two edge lengths, tangent to the sphere), which folds their fans through the
/// neighbouring triangles.
const TriangleMesh& test_mesh() {
  static const TriangleMesh mesh = [] {
    TriangleMesh m = icosphere(Vec3::Zero(), 10.0, 6);
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> noise(-0.02, 0.02);
    for (Vec3& v : m.vertices) v += Vec3(noise(rng), noise(rng), noise(rng));
    std::uniform_int_distribution<std::size_t> pick(0, m.vertices.size() - 1);
    std::normal_distribution<double> dir(0.0, 1.0);
    for (int k = 0; k < 300; ++k) {
      Vec3& v = m.vertices[pick(rng)];
      Vec3 t(dir(rng), dir(rng), dir(rng));
      t -= t.dot(v.normalized()) * v.normalized();
      v += 0.4 * t.normalized();
    }
    return m;
  }();
  return mesh;
}

void BM_ido_self_intersections(benchmark::State& state) {
  const TriangleMesh& m = test_mesh();
  const bool threaded = state.range(0) != 0;
  std::size_t pairs = 0;
  for (auto _ : state) {
    const auto r = self_intersections(m, {.threaded = threaded});
    pairs = r.size();
    benchmark::DoNotOptimize(r.data());
  }
  state.counters["pairs"] = static_cast<double>(pairs);
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
}
BENCHMARK(BM_ido_self_intersections)->Arg(0)->Arg(1)->ArgName("threaded")->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ido_has_self_intersections(benchmark::State& state) {
  const TriangleMesh& m = test_mesh();
  const bool threaded = state.range(0) != 0;
  for (auto _ : state) benchmark::DoNotOptimize(has_self_intersections(m, {.threaded = threaded}));
}
BENCHMARK(BM_ido_has_self_intersections)->Arg(0)->Arg(1)->ArgName("threaded")->Unit(benchmark::kMillisecond)->UseRealTime();

#ifdef IDO_BENCH_WITH_CGAL
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

const SurfaceMesh& cgal_mesh() {
  static const SurfaceMesh mesh = [] {
    const TriangleMesh& m = test_mesh();
    SurfaceMesh s;
    std::vector<SurfaceMesh::Vertex_index> vid;
    vid.reserve(m.vertices.size());
    for (const Vec3& v : m.vertices) vid.push_back(s.add_vertex(Kernel::Point_3(v.x(), v.y(), v.z())));
    for (const Tri& t : m.triangles) {
      s.add_face(vid[static_cast<std::size_t>(t[0])], vid[static_cast<std::size_t>(t[1])],
                 vid[static_cast<std::size_t>(t[2])]);
    }
    return s;
  }();
  return mesh;
}

void BM_cgal_self_intersections(benchmark::State& state) {
  const SurfaceMesh& s = cgal_mesh();
  const bool parallel = state.range(0) != 0;
  std::size_t pairs = 0;
  for (auto _ : state) {
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> r;
    if (parallel) {
      PMP::self_intersections<CGAL::Parallel_tag>(faces(s), s, std::back_inserter(r));
    } else {
      PMP::self_intersections<CGAL::Sequential_tag>(faces(s), s, std::back_inserter(r));
    }
    pairs = r.size();
    benchmark::DoNotOptimize(r.data());
  }
  state.counters["pairs"] = static_cast<double>(pairs);
  state.counters["triangles"] = static_cast<double>(num_faces(s));
}
BENCHMARK(BM_cgal_self_intersections)->Arg(0)->Arg(1)->ArgName("threaded")->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_cgal_does_self_intersect(benchmark::State& state) {
  const SurfaceMesh& s = cgal_mesh();
  const bool parallel = state.range(0) != 0;
  for (auto _ : state) {
    if (parallel) {
      benchmark::DoNotOptimize(PMP::does_self_intersect<CGAL::Parallel_tag>(faces(s), s));
    } else {
      benchmark::DoNotOptimize(PMP::does_self_intersect<CGAL::Sequential_tag>(faces(s), s));
    }
  }
}
BENCHMARK(BM_cgal_does_self_intersect)->Arg(0)->Arg(1)->ArgName("threaded")->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

}  // namespace

BENCHMARK_MAIN();

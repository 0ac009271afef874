// SPDX-License-Identifier: Apache-2.0
// Self-intersection detection on 102 400-triangle tori: ido against CGAL's Polygon Mesh
// Processing (self_intersections / does_self_intersect) in one binary, on the same meshes;
// and ido's incremental search (self_intersections_touching) against its whole search.
//
//   build/bench/bench/geometry/bench_self_intersection --benchmark_repetitions=5 \
//       --benchmark_report_aggregates_only=true
//
// Arguments: mesh (0 clean, 1 folded, 2 folded with vertices and triangles shuffled) and
// threaded (0: one thread, ido threaded = false and CGAL Sequential_tag; 1: oneTBB's default
// arena for both, ido threaded = true and CGAL Parallel_tag). Single-threaded rows report the
// calling thread's CPU time; threaded rows the whole process's CPU time (all threads).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "ido/geometry/primitives.h"
#include "ido/geometry/self_intersection.h"
#include "geometry/test_meshes.h"  // tests/: shuffled()

#ifdef IDO_BENCH_WITH_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#endif

namespace {

using namespace ido;
using namespace ido::geometry;

constexpr double kMajorMm = 10.0;

/// Torus (major radius 10 mm, tube 4 mm, 320 × 160 segments: 102 400 triangles, edges
/// 0.12–0.27 mm) with 0.01 mm of uniform noise on every vertex: no self-intersection.
TriangleMesh clean_torus() {
  TriangleMesh m = torus_surface(Vec3::Zero(), kMajorMm, 4.0, 320, 160);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> noise(-0.01, 0.01);
  for (Vec3& v : m.vertices) v += Vec3(noise(rng), noise(rng), noise(rng));
  return m;
}

/// The clean torus with 400 vertices dragged 0.4 mm along the surface (a random tangent
/// direction, 1.5–3 edge lengths), which folds their fans through neighbouring triangles.
TriangleMesh folded_torus() {
  TriangleMesh m = clean_torus();
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, m.vertices.size() - 1);
  std::normal_distribution<double> dir(0.0, 1.0);
  for (int k = 0; k < 400; ++k) {
    Vec3& v = m.vertices[pick(rng)];
    const Vec3 ring = kMajorMm * Vec3(v.x(), v.y(), 0.0).normalized();  // tube centre line
    const Vec3 normal = (v - ring).normalized();
    Vec3 t(dir(rng), dir(rng), dir(rng));
    t -= t.dot(normal) * normal;
    v += 0.4 * t.normalized();
  }
  return m;
}

/// The folded torus with its vertices and triangles in random order (no index locality).
TriangleMesh shuffled(const TriangleMesh& m) { return test::shuffled(m, std::mt19937_64(11)); }

const TriangleMesh& test_mesh(std::int64_t kind) {
  static const std::array<TriangleMesh, 3> meshes{clean_torus(), folded_torus(), shuffled(folded_torus())};
  return meshes[static_cast<std::size_t>(kind)];
}

void BM_ido_self_intersections(benchmark::State& state) {
  const TriangleMesh& m = test_mesh(state.range(0));
  const bool threaded = state.range(1) != 0;
  std::size_t pairs = 0;
  for (auto _ : state) {
    const auto r = self_intersections(m, {.threaded = threaded});
    pairs = r.size();
    benchmark::DoNotOptimize(r.data());
  }
  state.counters["pairs"] = static_cast<double>(pairs);
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
}

/// The incremental search (self_intersections_touching) on the folded torus with the
/// triangles of one end flagged (those whose centroid has the largest x, state.range(2) % of
/// them: a region that moved, as the balloon's active front), beside the whole search of the
/// same mesh (BM_ido_self_intersections, mesh 1).
void BM_ido_self_intersections_touching(benchmark::State& state) {
  const TriangleMesh& m = test_mesh(1);
  const bool threaded = state.range(1) != 0;
  std::vector<std::pair<double, std::size_t>> by_x(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const Tri& tr = m.triangles[t];
    by_x[t] = {m.vertices[std::size_t(tr[0])].x() + m.vertices[std::size_t(tr[1])].x() + m.vertices[std::size_t(tr[2])].x(), t};
  }
  std::sort(by_x.begin(), by_x.end());
  std::vector<std::uint8_t> changed(m.triangles.size(), 0);
  const std::size_t flagged = m.triangles.size() * static_cast<std::size_t>(state.range(2)) / 100;
  for (std::size_t k = m.triangles.size() - flagged; k < m.triangles.size(); ++k) changed[by_x[k].second] = 1;
  std::size_t pairs = 0;
  for (auto _ : state) {
    const auto r = self_intersections_touching(m, changed, {.threaded = threaded});
    pairs = r.size();
    benchmark::DoNotOptimize(r.data());
  }
  state.counters["pairs"] = static_cast<double>(pairs);
  state.counters["flagged"] = static_cast<double>(flagged);
}

void BM_ido_has_self_intersections(benchmark::State& state) {
  const TriangleMesh& m = test_mesh(state.range(0));
  const bool threaded = state.range(1) != 0;
  bool any = false;
  for (auto _ : state) {
    any = has_self_intersections(m, {.threaded = threaded});
    benchmark::DoNotOptimize(any);
  }
  state.counters["intersects"] = any ? 1.0 : 0.0;
}

#ifdef IDO_BENCH_WITH_CGAL
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

SurfaceMesh to_surface_mesh(const TriangleMesh& m) {
  SurfaceMesh s;
  std::vector<SurfaceMesh::Vertex_index> vid;
  vid.reserve(m.vertices.size());
  for (const Vec3& v : m.vertices) vid.push_back(s.add_vertex(Kernel::Point_3(v.x(), v.y(), v.z())));
  for (const Tri& t : m.triangles) {
    s.add_face(vid[static_cast<std::size_t>(t[0])], vid[static_cast<std::size_t>(t[1])],
               vid[static_cast<std::size_t>(t[2])]);
  }
  return s;
}

/// The same meshes as Surface_mesh, converted once (outside the timing).
const SurfaceMesh& cgal_mesh(std::int64_t kind) {
  static const std::array<SurfaceMesh, 3> meshes{to_surface_mesh(test_mesh(0)), to_surface_mesh(test_mesh(1)),
                                                 to_surface_mesh(test_mesh(2))};
  return meshes[static_cast<std::size_t>(kind)];
}

void BM_cgal_self_intersections(benchmark::State& state) {
  const SurfaceMesh& s = cgal_mesh(state.range(0));
  const bool parallel = state.range(1) != 0;
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

void BM_cgal_does_self_intersect(benchmark::State& state) {
  const SurfaceMesh& s = cgal_mesh(state.range(0));
  const bool parallel = state.range(1) != 0;
  bool any = false;
  for (auto _ : state) {
    any = parallel ? PMP::does_self_intersect<CGAL::Parallel_tag>(faces(s), s)
                   : PMP::does_self_intersect<CGAL::Sequential_tag>(faces(s), s);
    benchmark::DoNotOptimize(any);
  }
  state.counters["intersects"] = any ? 1.0 : 0.0;
}
#endif

/// Registers ido and CGAL next to each other for every (mesh, threaded) pair, so that one run
/// interleaves them; threaded rows measure the CPU time of the whole process.
void register_all() {
  for (int mesh = 0; mesh < 3; ++mesh) {
    for (int threaded = 0; threaded < 2; ++threaded) {
      std::vector<benchmark::internal::Benchmark*> runs;
      runs.push_back(benchmark::RegisterBenchmark("ido_self_intersections", BM_ido_self_intersections));
#ifdef IDO_BENCH_WITH_CGAL
      runs.push_back(benchmark::RegisterBenchmark("cgal_self_intersections", BM_cgal_self_intersections));
#endif
      runs.push_back(benchmark::RegisterBenchmark("ido_has_self_intersections", BM_ido_has_self_intersections));
#ifdef IDO_BENCH_WITH_CGAL
      runs.push_back(benchmark::RegisterBenchmark("cgal_does_self_intersect", BM_cgal_does_self_intersect));
#endif
      for (auto* b : runs) {
        b->ArgNames({"mesh", "threaded"})->Args({mesh, threaded})->Unit(benchmark::kMillisecond)->UseRealTime();
        if (threaded != 0) b->MeasureProcessCPUTime();
      }
    }
  }
}

}  // namespace

/// The incremental search with 2 % and 10 % of the triangles flagged, next to the whole search.
void register_touching() {
  for (int threaded = 0; threaded < 2; ++threaded) {
    for (int percent : {2, 10}) {
      auto* b = benchmark::RegisterBenchmark("ido_self_intersections_touching", BM_ido_self_intersections_touching);
      b->ArgNames({"mesh", "threaded", "percent"})->Args({1, threaded, percent})->Unit(benchmark::kMillisecond)->UseRealTime();
      if (threaded != 0) b->MeasureProcessCPUTime();
    }
  }
}

int main(int argc, char** argv) {
  register_all();
  register_touching();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

// SPDX-License-Identifier: Apache-2.0
// A like-for-like OpenVDB row for the drilling update (issue 5): per collision update the
// same three jobs as ours (BM_UpdateTime in drill_update_bench.cpp) — test the 1000 burr
// samples against the grid, switch off the voxels in each sub-step sphere, and bring the
// surface of the changed region up to date — on the same trace at the same resolution as
// BM_OpenVdbUpdateTime (which does the first two only and stays as it is).
//
// Surface scheme (what a fair OpenVDB user would write for a renderer that keeps one mesh
// per 8³ leaf brick, as ours keeps one face list per chunk): the mesh of the whole grid is
// made once at setup (openvdb::tools::volumeToMesh, uniform, quads) and split by brick. Per
// update, the bricks whose quads can change are those within 3 voxels of a switched-off
// voxel (a quad belongs to the brick of its rounded centroid and reads only voxels within
// 3 of it: its points lie in the 4 cells around the voxel edge it crosses). Those bricks
// and their 26 neighbours (the quads' cells read one voxel beyond the brick) are copied
// into a small grid (leaf nodes copied, tiles filled), volumeToMesh meshes it, and the quads
// that belong to a dirty brick replace that brick's list; the others (including the false
// surface where the small grid ends, which lies in the neighbour bricks) are dropped.
// OpenVDB runs single-threaded (tbb::global_control): the figures are the calling
// thread's CPU time, as ours. After the trace, the bricks' quads are compared with a full
// volumeToMesh of the final grid (counter surface_matches_full = 1).
#include <benchmark/benchmark.h>

#ifdef IDO_BENCH_OPENVDB

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <string>
#include <unordered_map>
#include <limits>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>

#include "ido/drill/simulator.h"
#include "ido/drill/tool.h"
#include "drill_trace.h"

namespace {

using namespace ido;
using namespace ido::drill;
using namespace ido::drill::bench;

using Quad = std::array<openvdb::Vec3s, 4>;

struct CoordHash {
  std::size_t operator()(const openvdb::Coord& c) const noexcept {
    return static_cast<std::size_t>(static_cast<std::uint32_t>(c.x()) * 73856093U ^ static_cast<std::uint32_t>(c.y()) * 19349663U ^
                                    static_cast<std::uint32_t>(c.z()) * 83492791U);
  }
};
using BrickMeshes = std::unordered_map<openvdb::Coord, std::vector<Quad>, CoordHash>;

constexpr int kLeafDim = static_cast<int>(openvdb::BoolTree::LeafNodeType::DIM);  // 8

openvdb::Coord brick_of(const openvdb::Coord& v) { return v & ~(kLeafDim - 1); }
constexpr int kReach = 3;  // voxels: how far from a quad's rounded centroid its inputs lie (< kLeafDim)

// The brick a quad belongs to: the brick holding its centroid, rounded to voxel
// coordinates (index space of a linear transform of voxel size h). A quad's points lie in
// the four cells around the voxel edge it crosses, so the centroid is within 1.5 voxels of
// that edge and the quad depends only on voxels within 3 of the rounded centroid.
openvdb::Coord quad_brick(const Quad& q, double h) {
  const openvdb::Vec3s c = 0.25f * (q[0] + q[1] + q[2] + q[3]);
  return brick_of(openvdb::Coord(static_cast<int>(std::floor(c.x() / h + 0.5)), static_cast<int>(std::floor(c.y() / h + 0.5)),
                                 static_cast<int>(std::floor(c.z() / h + 0.5))));
}

// Meshes @p grid (uniform: quads only) and hands each quad to @p take(brick, quad).
// (VolumeToMesh::setSurfaceMask restricted to the dirty bricks was tried: it drops quads
// whose cells lie just outside the mask, and dilated by a brick it is slower.)
template <class Take>
void mesh_quads(const openvdb::BoolGrid& grid, double h, Take&& take) {
  openvdb::tools::VolumeToMesh mesher(0.5);
  mesher(grid);
  const auto& points = mesher.pointList();
  const auto& pools = mesher.polygonPoolList();
  for (std::size_t n = 0; n < mesher.polygonPoolListSize(); ++n) {
    for (std::size_t i = 0; i < pools[n].numQuads(); ++i) {
      const auto& q = pools[n].quad(i);
      const Quad quad{points[q[0]], points[q[1]], points[q[2]], points[q[3]]};
      take(quad_brick(quad, h), quad);
    }
  }
}

// Sorted copy of every quad (each rotated to start at its smallest point) for comparison.
std::vector<Quad> canonical(std::vector<Quad> quads) {
  auto less = [](const openvdb::Vec3s& a, const openvdb::Vec3s& b) {
    return std::lexicographical_compare(a.asPointer(), a.asPointer() + 3, b.asPointer(), b.asPointer() + 3);
  };
  for (auto& q : quads) {
    const auto m = std::min_element(q.begin(), q.end(), less);
    std::rotate(q.begin(), m, q.end());
  }
  std::sort(quads.begin(), quads.end(), [&](const Quad& a, const Quad& b) {
    return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), less);
  });
  return quads;
}

// Per update: collide the 1000 burr samples (value accessor; inside count and the inward
// direction sum, as ours), switch off the voxels in each sub-step sphere (as
// BM_OpenVdbUpdateTime), re-mesh the dirty bricks (see the file comment). Arg: depth.
void BM_OpenVdbPipeline(benchmark::State& state) {
  openvdb::initialize();
  const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int depth = static_cast<int>(state.range(0));
  const double h = voxel_edge(depth);
  std::vector<double> cpu_times, collide_cpu, remove_cpu, surface_cpu;
  double dirty_sum = 0.0, copied_sum = 0.0, quads = 0.0, matches = 0.0, mem = 0.0;
  for (auto _ : state) {
    auto grid = make_block_grid(h);
    BrickMeshes bricks;
    mesh_quads(*grid, h, [&](const openvdb::Coord& b, const Quad& q) { bricks[b].push_back(q); });
    const Tool tool({.burr_radius_mm = kRadius, .sample_count = 1000});
    auto acc = grid->getAccessor();
    cpu_times.clear();
    collide_cpu.clear();
    remove_cpu.clear();
    surface_cpu.clear();
    dirty_sum = copied_sum = 0.0;
    std::vector<openvdb::Coord> dirty, copied;
    Vec3 last = trace(0);
    for (int i = 0; i < kUpdates; ++i) {
      const double c0 = thread_cpu_s();
      // Collision: the burr samples against the grid.
      const Vec3 c = trace(i);
      Vec3 dir = Vec3::Zero();
      const int inside = samples_inside(acc, tool, c, h, &dir);
      benchmark::DoNotOptimize(inside);
      benchmark::DoNotOptimize(dir);
      const double c1 = thread_cpu_s();
      // Removal: voxels inside each sub-step sphere; the bricks whose quads can change.
      dirty.clear();
      const int n = substep_count(last, c);
      for (int k = 1; k <= n; ++k) {
        switch_off_sphere(acc, last + (c - last) * (double(k) / n), h, [&](const openvdb::Coord& v) {
          // Every brick within kReach voxels of v (its quads may read v).
          for (int ex = -kReach; ex <= kReach; ex += kReach)
            for (int ey = -kReach; ey <= kReach; ey += kReach)
              for (int ez = -kReach; ez <= kReach; ez += kReach) {
                const openvdb::Coord b = brick_of(v.offsetBy(ex, ey, ez));
                if (dirty.empty() || dirty.back() != b) dirty.push_back(b);
              }
        });
      }
      last = c;
      const double c2 = thread_cpu_s();
      // Surface: re-mesh the dirty bricks on a small grid holding them and their neighbours.
      std::sort(dirty.begin(), dirty.end());
      dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
      if (!dirty.empty()) {
        copied.clear();
        for (const auto& b : dirty)
          for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dz = -1; dz <= 1; ++dz) copied.push_back(b.offsetBy(dx * kLeafDim, dy * kLeafDim, dz * kLeafDim));
        std::sort(copied.begin(), copied.end());
        copied.erase(std::unique(copied.begin(), copied.end()), copied.end());
        auto sub = openvdb::BoolGrid::create(false);
        sub->setTransform(grid->transformPtr());
        for (const auto& b : copied) {
          if (const auto* leaf = acc.probeConstLeaf(b)) {
            sub->tree().addLeaf(new openvdb::BoolTree::LeafNodeType(*leaf));
          } else if (acc.isValueOn(b)) {  // inside a tile of material
            sub->tree().touchLeaf(b)->fill(true, true);
          }
        }
        for (const auto& b : dirty) bricks[b].clear();
        mesh_quads(*sub, h, [&](const openvdb::Coord& b, const Quad& q) {
          if (std::binary_search(dirty.begin(), dirty.end(), b)) bricks[b].push_back(q);
        });
        copied_sum += static_cast<double>(copied.size());
      }
      dirty_sum += static_cast<double>(dirty.size());
      const double c3 = thread_cpu_s();
      cpu_times.push_back(c3 - c0);
      collide_cpu.push_back(c1 - c0);
      remove_cpu.push_back(c2 - c1);
      surface_cpu.push_back(c3 - c2);
    }
    // Check: the bricks' quads are exactly the mesh of the final grid.
    std::vector<Quad> kept, full;
    for (const auto& [b, list] : bricks) kept.insert(kept.end(), list.begin(), list.end());
    mesh_quads(*grid, h, [&](const openvdb::Coord&, const Quad& q) { full.push_back(q); });
    quads = static_cast<double>(kept.size());
    matches = canonical(kept) == canonical(full) ? 1.0 : 0.0;
    mem = static_cast<double>(grid->memUsage());
  }
  add_ms_counters(state, "cpu_", cpu_times);
  double total = 0.0;
  for (const double t : cpu_times) total += t;
  state.counters["cpu_total_s"] = total;
  add_ms_counters(state, "collide_cpu_", collide_cpu);
  add_ms_counters(state, "remove_cpu_", remove_cpu);
  add_ms_counters(state, "surface_cpu_", surface_cpu);
  state.counters["dirty_bricks_per_update"] = dirty_sum / kUpdates;
  state.counters["copied_leaves_per_update"] = copied_sum / kUpdates;
  state.counters["quads"] = quads;
  state.counters["surface_matches_full"] = matches;
  state.counters["memory_kB"] = mem / 1024.0;
  state.counters["voxel_mm"] = h;
}
BENCHMARK(BM_OpenVdbPipeline)->DenseRange(4, 8)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

#endif  // IDO_BENCH_OPENVDB

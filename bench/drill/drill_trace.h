// SPDX-License-Identifier: Apache-2.0
// The drilling benchmarks' shared setup: the block, burr, trace and sub-steps every drilling
// row runs (ours in drill_update_bench.cpp and OpenVDB's in both files), the leaf edge at a
// depth, the thread-CPU clock, the percentile counters, and (with OpenVDB) the voxel grid of
// the block with its collision and removal steps.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/simulator.h"
#include "ido/drill/tool.h"

#ifdef IDO_BENCH_OPENVDB
#include <openvdb/openvdb.h>
#endif

namespace ido::drill::bench {

inline constexpr double kBlockCell = 4.0;  ///< root cube edge (mm)
inline const Vec3 kBlock(32.0, 32.0, 16.0);  ///< block size (mm), corner at the origin
inline constexpr double kRadius = 2.0;       ///< burr radius (mm)
inline constexpr double kSpeedMmPerS = 20.0;  ///< tool speed along the trace
inline constexpr int kUpdates = 1000;         ///< collision updates (1 ms apart)

/// Burr centre (mm) at update @p i: a plunge 3 mm into the top face, then a curve, one pose
/// per millisecond.
inline Vec3 trace(int i) {
  const double t = i * 1e-3;
  const double s = kSpeedMmPerS * t;  // arc length (mm)
  if (s < 3.0) return {8.0, 16.0, kBlock.z() + kRadius - s};
  const double u = s - 3.0;
  return {8.0 + u, 16.0 + 4.0 * std::sin(u / 4.0), kBlock.z() + kRadius - 3.0};
}

/// Sub-steps (each at most r/4 long, the simulator's rule) the move from @p from to @p to
/// (mm) is split into; sub-step k of n ends at from + (to − from) · k / n.
inline int substep_count(const Vec3& from, const Vec3& to) {
  return std::max(1, static_cast<int>(std::ceil((to - from).norm() / (0.25 * kRadius))));
}

/// CPU time of the calling thread (s): robust against other processes on a loaded machine.
inline double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// Leaf size (mm) quoted for @p depth: the block cell's diagonal halved per level.
inline double leaf_edge(int depth) { return kBlockCell * std::sqrt(3.0) / std::ldexp(1.0, depth); }

/// Counters PREFIXp50_ms, PREFIXp99_ms and (with @p with_max) PREFIXmax_ms of times in seconds.
inline void add_ms_counters(benchmark::State& state, const std::string& prefix, const std::vector<double>& seconds,
                            bool with_max = true) {
  const auto p = percentiles(seconds);
  state.counters[prefix + "p50_ms"] = p.p50 * 1e3;
  state.counters[prefix + "p99_ms"] = p.p99 * 1e3;
  if (with_max) state.counters[prefix + "max_ms"] = p.max * 1e3;
}

#ifdef IDO_BENCH_OPENVDB
/// OpenVDB voxel edge (mm) for @p depth: about the leaves' mean edge.
inline double voxel_edge(int depth) { return leaf_edge(depth) / std::sqrt(3.0) * std::sqrt(2.0); }

/// The block as a BoolGrid of voxel edge @p h_mm (voxels on, as tiles where they can be).
/// Filled sparsely (Grid::fill: tiles where a whole node is covered), as an OpenVDB user
/// would: denseFill made every leaf first and pruned them afterwards, the same tree in the
/// end but a peak of 519 MiB at depth 8 for a 20 MiB grid.
inline openvdb::BoolGrid::Ptr make_block_grid(double h_mm) {
  auto grid = openvdb::BoolGrid::create(false);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(h_mm));
  const openvdb::Coord hi(static_cast<int>(kBlock.x() / h_mm) - 1, static_cast<int>(kBlock.y() / h_mm) - 1,
                          static_cast<int>(kBlock.z() / h_mm) - 1);
  grid->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), hi), true, true);
  grid->tree().prune();
  return grid;
}

/// The voxel holding @p p_mm.
inline openvdb::Coord voxel_of(const Vec3& p_mm, double h_mm) {
  return {static_cast<int>(std::floor(p_mm.x() / h_mm)), static_cast<int>(std::floor(p_mm.y() / h_mm)),
          static_cast<int>(std::floor(p_mm.z() / h_mm))};
}

/// Collision against the grid: the burr samples about @p centre_mm whose voxel is on, and
/// (when @p inward is given) the sum of −sample over them.
template <class Accessor>
int samples_inside(Accessor& acc, const Tool& tool, const Vec3& centre_mm, double h_mm, Vec3* inward = nullptr) {
  int inside = 0;
  for (const auto& s : tool.burr_samples()) {
    if (!acc.isValueOn(voxel_of(centre_mm + s, h_mm))) continue;
    ++inside;
    if (inward != nullptr) *inward -= s;
  }
  return inside;
}

/// Removal: switches off every on voxel whose centre lies in the burr sphere about @p q_mm,
/// calling @p switched(voxel) after each.
template <class Accessor, class Switched>
void switch_off_sphere(Accessor& acc, const Vec3& q_mm, double h_mm, Switched&& switched) {
  const int r = static_cast<int>(std::ceil(kRadius / h_mm)) + 1;
  const openvdb::Coord ctr = voxel_of(q_mm, h_mm);
  for (int dx = -r; dx <= r; ++dx)
    for (int dy = -r; dy <= r; ++dy)
      for (int dz = -r; dz <= r; ++dz) {
        const openvdb::Coord v = ctr.offsetBy(dx, dy, dz);
        const Vec3 centre((v.x() + 0.5) * h_mm, (v.y() + 0.5) * h_mm, (v.z() + 0.5) * h_mm);
        if ((centre - q_mm).squaredNorm() <= kRadius * kRadius && acc.isValueOn(v)) {
          acc.setValueOff(v, false);
          switched(v);
        }
      }
}
#endif

}  // namespace ido::drill::bench

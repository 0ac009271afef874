// SPDX-License-Identifier: Apache-2.0
// The drilling benchmarks' shared setup: the block, burr and trace every drilling row runs
// (ours in drill_update_bench.cpp and OpenVDB's in both files), the leaf edge at a depth,
// the thread-CPU clock and the percentile counters.
#pragma once

#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/simulator.h"

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

}  // namespace ido::drill::bench

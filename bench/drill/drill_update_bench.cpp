// SPDX-License-Identifier: Apache-2.0
// Drilling figures: update time (collide + erode + v_list rebuild) per collision update at
// depths 4–8, bytes per node, the haptic loop over a scripted trace, and voxel removal in
// OpenVDB on the same trace at the same resolution (when built with OpenVDB).
#include <benchmark/benchmark.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "ido/drill/boundary_surface.h"
#include "ido/drill/collision.h"
#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/simulator.h"
#include "ido/drill/tet_hierarchy.h"
#include "drill_trace.h"

#ifdef IDO_BENCH_OPENVDB
#include <openvdb/openvdb.h>
#endif

namespace {

using namespace ido;
using namespace ido::drill;
using namespace ido::drill::bench;

// CPU time of the whole process (s).
double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// One collision update as the simulator's collision thread does it: collide the 1000 burr
// samples, queue the erosion sub-steps, run erosion within the visit budget (0 = unlimited),
// rebuild the changed v_list chunks. After the trace, updates continue (no new pose) until
// the erosion and v_list backlogs are done; they are timed too. Args: depth, erosion visit
// budget, chunk level, v_list visit budget (0 = unlimited); BM_UpdateTimeThreads takes the
// v_list rebuild's worker threads as a fifth (BoundarySurfaceOptions::threads; 1 = serial).
// Wall-clock percentiles (p50_ms, p99_ms) are the update's latency; the cpu_ ones are the
// calling thread's CPU time, which leaves out what other workers did.
void update_time(benchmark::State& state, int threads) {
  const int depth = static_cast<int>(state.range(0));
  const auto budget = static_cast<std::size_t>(state.range(1));
  const int chunk_level = static_cast<int>(state.range(2));
  const auto surface_budget = static_cast<std::size_t>(state.range(3));
  std::vector<double> times;
  std::vector<double> cpu_times;
  std::vector<double> collide_cpu, erode_cpu, surface_cpu;  // the three parts of cpu_times
  double bytes = 0.0, nodes = 0.0, storage = 0.0, removed = 0.0, faces = 0.0, hash_bytes = 0.0;
  std::size_t backlog_updates = 0, max_queue = 0;
  const double process_cpu0 = process_cpu_s();
  for (auto _ : state) {
    TetHierarchy h(make_block(kBlock, kBlockCell));
    const double before = h.material_volume();
    BoundarySurface surface(h, {.chunk_level = chunk_level, .threads = threads});
    const Tool tool({.burr_radius_mm = kRadius, .sample_count = 1000});
    Eroder eroder({.force_threshold_n = 0.0, .removal_rate_mm3_per_s = 0.0, .max_depth = depth, .max_node_visits = budget});
    times.clear();
    cpu_times.clear();
    collide_cpu.clear();
    erode_cpu.clear();
    surface_cpu.clear();
    backlog_updates = 0;
    max_queue = 0;
    Vec3 last = trace(0);
    for (int i = 0; i < kUpdates || eroder.has_pending() || surface.has_pending(); ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = thread_cpu_s();
      if (i < kUpdates) {
        ToolPose pose;
        pose.position_mm = trace(i);
        const ContactModel m = collide(h, tool, pose);
        benchmark::DoNotOptimize(m);
        const int n = substep_count(last, pose.position_mm);
        for (int k = 1; k <= n; ++k) eroder.enqueue(last + (pose.position_mm - last) * (double(k) / n), kRadius, 1.0, 1e-3 / n);
        last = pose.position_mm;
      } else {
        ++backlog_updates;
      }
      max_queue = std::max(max_queue, eroder.queued());
      const double c1 = thread_cpu_s();
      (void)eroder.run(h, budget);
      const double c2 = thread_cpu_s();
      surface.update(h, eroder.changed_nodes(), surface_budget);
      eroder.clear_changed_roots();
      times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      const double c3 = thread_cpu_s();
      cpu_times.push_back(c3 - c0);
      collide_cpu.push_back(c1 - c0);
      erode_cpu.push_back(c2 - c1);
      surface_cpu.push_back(c3 - c2);
    }
    bytes = h.bytes_per_node();
    storage = static_cast<double>(h.node_storage_bytes());
    nodes = static_cast<double>(h.node_count());
    removed = before - h.material_volume();
    faces = static_cast<double>(surface.face_count());
    hash_bytes = static_cast<double>(h.root_hash().memory_bytes());
  }
  add_ms_counters(state, "", times);
  add_ms_counters(state, "cpu_", cpu_times);
  double total = 0.0;
  for (const double t : cpu_times) total += t;
  state.counters["cpu_total_s"] = total;  // all updates, backlog included
  add_ms_counters(state, "collide_cpu_", collide_cpu, false);
  add_ms_counters(state, "erode_cpu_", erode_cpu, false);
  add_ms_counters(state, "surface_cpu_", surface_cpu, false);
  state.counters["updates"] = static_cast<double>(times.size());
  state.counters["backlog_updates"] = static_cast<double>(backlog_updates);
  state.counters["max_queued"] = static_cast<double>(max_queue);
  state.counters["removed_mm3"] = removed;
  state.counters["faces"] = faces;
  state.counters["bytes_per_node"] = bytes;
  state.counters["node_storage_kB"] = storage / 1024.0;
  // Beyond the node words: the roots' spatial hash and the v_list faces (the surface).
  state.counters["hash_kB"] = hash_bytes / 1024.0;
  state.counters["v_list_kB"] = faces * static_cast<double>(sizeof(SurfaceFace)) / 1024.0;
  state.counters["nodes"] = nodes;
  state.counters["leaf_edge_mm"] = leaf_edge(depth);
  state.counters["process_cpu_s"] = process_cpu_s() - process_cpu0;
}
void BM_UpdateTime(benchmark::State& state) { update_time(state, 0); }
void BM_UpdateTimeThreads(benchmark::State& state) { update_time(state, static_cast<int>(state.range(4))); }
// Unlimited erosion with whole-root v_lists (chunk level 0: the previous algorithm's work,
// in the new code), unlimited erosion with chunked v_lists, the default budgets, half, one
// and a half and about two thirds of them (4000 / 5500: what a p99 of 1 ms at depth 8 would
// take at the per-visit cost measured on 2026-12-02).
BENCHMARK(BM_UpdateTime)
    ->Args({4, 0, 0, 0})
    ->Args({5, 0, 0, 0})
    ->Args({6, 0, 0, 0})
    ->Args({4, 0, 3, 0})
    ->Args({5, 0, 3, 0})
    ->Args({6, 0, 3, 0})
    ->ArgsProduct({{4, 5, 6, 7, 8}, {6000}, {3}, {8000}})
    ->ArgsProduct({{5, 6, 7}, {3000}, {3}, {4000}})
    ->ArgsProduct({{6, 7, 8}, {9000}, {3}, {12000}})
    ->ArgsProduct({{4, 5, 6, 7, 8}, {4000}, {3}, {5500}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
// The default budgets with the v_list chunks rebuilt by the calling thread alone (1) and by
// two workers (2), side by side in one run.
BENCHMARK(BM_UpdateTimeThreads)
    ->ArgsProduct({{4, 5, 6, 7, 8}, {6000}, {3}, {8000}, {1, 2}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Squared distance (mm²) from p to the triangle (a, b, c) (Ericson, Real-Time Collision
// Detection, 5.1.5).
double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - ab * (d1 / (d1 - d3))).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - ac * (d2 / (d2 - d6))).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return (bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))).squaredNorm();
  const double denom = 1.0 / (va + vb + vc);
  return (ap - ab * (vb * denom) - ac * (vc * denom)).squaredNorm();
}

// True when the sphere (c, r) and the tetrahedron x share a point (distance from c to the
// solid tetrahedron ≤ r).
bool sphere_touches_tet(const std::array<Vec3, 4>& x, const Vec3& c, double r) {
  const double vol = signed_volume(x[0], x[1], x[2], x[3]);
  bool inside = true;
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int f = 0; f < 4 && inside; ++f) {
    std::array<Vec3, 4> y = x;
    y[static_cast<std::size_t>(f)] = c;
    inside = signed_volume(y[0], y[1], y[2], y[3]) * vol >= 0.0;
  }
  if (inside) return true;
  for (const auto& f : kFace)
    if (point_triangle_distance2(c, x[static_cast<std::size_t>(f[0])], x[static_cast<std::size_t>(f[1])],
                                 x[static_cast<std::size_t>(f[2])]) <= r * r)
      return true;
  return false;
}

#ifdef IDO_BENCH_OPENVDB
// Voxel removal in OpenVDB on the same trace: voxels of edge = leaf edge at `depth`; per
// update, 1000 sample points are looked up (collision) and the voxels inside the sphere
// switched off (erosion). No surface extraction (ours includes the v_list rebuild). Fills
// the per-update wall and thread-CPU times (s) and returns the grid's memUsage() (bytes)
// after the trace; *voxel_mm gets the voxel edge.
double run_openvdb_trace(int depth, std::vector<double>& times, std::vector<double>& cpu_times, double* voxel_mm) {
  openvdb::initialize();
  const double h = voxel_edge(depth);
  if (voxel_mm != nullptr) *voxel_mm = h;
  auto grid = make_block_grid(h);
  const Tool tool({.burr_radius_mm = kRadius, .sample_count = 1000});
  auto acc = grid->getAccessor();
  times.clear();
  cpu_times.clear();
  Vec3 last = trace(0);
  for (int i = 0; i < kUpdates; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_s();
    const Vec3 c = trace(i);
    const int inside = samples_inside(acc, tool, c, h);
    benchmark::DoNotOptimize(inside);
    const int n = substep_count(last, c);
    for (int k = 1; k <= n; ++k)
      switch_off_sphere(acc, last + (c - last) * (double(k) / n), h, [](const openvdb::Coord&) {});
    last = c;
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    cpu_times.push_back(thread_cpu_s() - c0);
  }
  return static_cast<double>(grid->memUsage());
}

// See run_openvdb_trace.
void BM_OpenVdbUpdateTime(benchmark::State& state) {
  const int depth = static_cast<int>(state.range(0));
  std::vector<double> times;
  std::vector<double> cpu_times;
  double mem = 0.0, h = 0.0;
  for (auto _ : state) mem = run_openvdb_trace(depth, times, cpu_times, &h);
  add_ms_counters(state, "", times);
  add_ms_counters(state, "cpu_", cpu_times);
  double total = 0.0;
  for (const double t : cpu_times) total += t;
  state.counters["cpu_total_s"] = total;
  state.counters["memory_kB"] = mem / 1024.0;
  state.counters["voxel_mm"] = h;
}
#endif

// After the trace of BM_UpdateTime (default budgets, backlog finished), what the node
// storage holds: sibling blocks by kind — (a) 8 full leaves, (b) 8 leaves, some erased,
// (c) at least one internal child, (d) 8 erased leaves (must be 0: they merge) — and the
// full leaves below a root that no burr position touched (exact sphere–tetrahedron test
// against every queued sub-step sphere): material refined only because its parent
// straddled the burr. Then the node storage's real bytes (TetHierarchy::node_storage_bytes:
// root words, page table, every page byte handed out — live groups, free lists, short page
// tails; and the capacity with the last page's unused rest) against the memUsage() of
// OpenVDB's BoolGrid after the same trace at the same resolution (run_openvdb_trace), and
// for reference the estimate of the encoding from the counts alone (1 byte per node with 8
// leaf children, 6 per other internal node, no slack) and 2 bits per node (static). Arg: depth.
void BM_BlockCensus(benchmark::State& state) {
  const int depth = static_cast<int>(state.range(0));
  std::size_t all_full = 0, mixed = 0, with_internal = 0, all_erased = 0, full_leaves = 0, full_untouched = 0,
              erased_leaves = 0, internal_nodes = 0, full_in_mixed = 0, erased_in_mixed = 0, untouched_all_full = 0;
  std::size_t nodes = 0, storage = 0, capacity = 0, roots = 0, live_group_bytes = 0, free_bytes = 0, pages = 0;
  double bytes = 0.0;
  for (auto _ : state) {
    TetHierarchy h(make_block(kBlock, kBlockCell));
    BoundarySurface surface(h, {.chunk_level = 3});
    Eroder eroder({.force_threshold_n = 0.0, .removal_rate_mm3_per_s = 0.0, .max_depth = depth, .max_node_visits = 6000});
    std::vector<Vec3> centres;
    Vec3 last = trace(0);
    for (int i = 0; i < kUpdates || eroder.has_pending() || surface.has_pending(); ++i) {
      if (i < kUpdates) {
        const Vec3 c = trace(i);
        const int n = substep_count(last, c);
        for (int k = 1; k <= n; ++k) {
          centres.push_back(last + (c - last) * (double(k) / n));
          eroder.enqueue(centres.back(), kRadius, 1.0, 1e-3 / n);
        }
        last = c;
      }
      (void)eroder.run(h, 6000);
      surface.update(h, eroder.changed_nodes(), 8000);
      eroder.clear_changed_roots();
    }
    // Burr centres bucketed in 1 mm cells for the touch test.
    const double cell = 1.0;
    auto key = [&](const Vec3& p) {
      return std::array<int, 3>{static_cast<int>(std::floor(p.x() / cell)), static_cast<int>(std::floor(p.y() / cell)),
                                static_cast<int>(std::floor(p.z() / cell))};
    };
    std::map<std::array<int, 3>, std::vector<Vec3>> buckets;
    for (const auto& c : centres) buckets[key(c)].push_back(c);
    auto touched = [&](const NodeRef& n) {
      const auto x = h.world_vertices(n);
      const Vec3 centroid = 0.25 * (x[0] + x[1] + x[2] + x[3]);
      double rad = 0.0;
      for (const auto& v : x) rad = std::max(rad, (v - centroid).norm());
      const double reach = kRadius + rad;
      const auto lo = key(centroid - Vec3::Constant(reach)), hi = key(centroid + Vec3::Constant(reach));
      for (int i = lo[0]; i <= hi[0]; ++i)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int k = lo[2]; k <= hi[2]; ++k) {
            const auto it = buckets.find({i, j, k});
            if (it == buckets.end()) continue;
            for (const auto& c : it->second)
              if ((c - centroid).squaredNorm() <= reach * reach && sphere_touches_tet(x, c, kRadius)) return true;
          }
      return false;
    };
    all_full = mixed = with_internal = all_erased = full_leaves = full_untouched = erased_leaves = internal_nodes = 0;
    full_in_mixed = erased_in_mixed = untouched_all_full = 0;
    for (std::size_t r = 0; r < h.root_count(); ++r) {
      struct Item {
        NodeRef node;
        std::uint32_t word;
      };
      std::vector<Item> stack{{NodeRef{static_cast<std::uint32_t>(r), 0, 0}, h.root_word(r)}};
      while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const NodeState s = TetHierarchy::state_of_word(it.word);
        if (s == NodeState::Full) {
          ++full_leaves;
          if (it.node.depth > 0 && !touched(it.node)) ++full_untouched;
          continue;
        }
        if (s == NodeState::Erased) {
          ++erased_leaves;
          continue;
        }
        ++internal_nodes;
        int full = 0, erased = 0;
        for (int c = 0; c < 8; ++c) {
          const std::uint32_t w = h.child_word(it.word, c);
          full += w == TetHierarchy::kFull ? 1 : 0;
          erased += w == TetHierarchy::kErased ? 1 : 0;
          stack.push_back({it.node.child(c), w});
        }
        if (full == 8) {
          ++all_full;
          bool any = false;
          for (int c = 0; c < 8 && !any; ++c) any = touched(it.node.child(c));
          if (!any) ++untouched_all_full;
        } else if (erased == 8) {
          ++all_erased;
        } else if (full + erased == 8) {
          ++mixed;
          full_in_mixed += static_cast<std::size_t>(full);
          erased_in_mixed += static_cast<std::size_t>(erased);
        } else {
          ++with_internal;
        }
      }
    }
    nodes = h.node_count();
    storage = h.node_storage_bytes();
    capacity = h.node_storage_capacity_bytes();
    roots = h.root_count();
    live_group_bytes = h.live_group_bytes();
    free_bytes = h.free_bytes();
    pages = h.page_count();
    bytes = h.bytes_per_node();
  }
  state.counters["blocks_all_full"] = static_cast<double>(all_full);
  state.counters["blocks_all_full_untouched"] = static_cast<double>(untouched_all_full);
  state.counters["blocks_mixed_leaves"] = static_cast<double>(mixed);
  state.counters["blocks_with_internal"] = static_cast<double>(with_internal);
  state.counters["blocks_all_erased"] = static_cast<double>(all_erased);
  state.counters["full_in_mixed"] = static_cast<double>(full_in_mixed);
  state.counters["erased_in_mixed"] = static_cast<double>(erased_in_mixed);
  state.counters["full_leaves"] = static_cast<double>(full_leaves);
  state.counters["full_leaves_untouched"] = static_cast<double>(full_untouched);
  state.counters["erased_leaves"] = static_cast<double>(erased_leaves);
  state.counters["internal_nodes"] = static_cast<double>(internal_nodes);
  state.counters["nodes"] = static_cast<double>(nodes);
  state.counters["bytes_per_node"] = bytes;
  state.counters["node_storage_kB"] = static_cast<double>(storage) / 1024.0;
  state.counters["node_capacity_kB"] = static_cast<double>(capacity) / 1024.0;
  state.counters["live_groups_kB"] = static_cast<double>(live_group_bytes) / 1024.0;
  state.counters["free_lists_kB"] = static_cast<double>(free_bytes) / 1024.0;
  state.counters["pages"] = static_cast<double>(pages);
#ifdef IDO_BENCH_OPENVDB
  std::vector<double> vdb_times, vdb_cpu;
  const double vdb = run_openvdb_trace(depth, vdb_times, vdb_cpu, nullptr);
  state.counters["vdb_memory_kB"] = vdb / 1024.0;
  state.counters["storage_over_vdb"] = static_cast<double>(storage) / vdb;
  state.counters["capacity_over_vdb"] = static_cast<double>(capacity) / vdb;
#endif
  // Estimate from the counts: 2-bit codes full / erased / internal with 8 leaf children /
  // other internal; a node of the third kind is one byte (its children's full/erased mask),
  // of the fourth 6 bytes (its children's codes + the index of their records); no slack.
  state.counters["est_leaf_mask_kB"] = static_cast<double>(4 * roots + mixed + 6 * with_internal) / 1024.0;
  state.counters["est_2bit_per_node_kB"] = static_cast<double>(nodes) / 4.0 / 1024.0;
}
BENCHMARK(BM_BlockCensus)->DenseRange(4, 8)->Iterations(1)->Unit(benchmark::kMillisecond);

// The haptic loop over a scripted trace through the three threads. Args: seconds, hybrid
// wait spin (µs; 0 = plain sleep_until), SCHED_FIFO priority of the haptic thread (0 =
// ordinary scheduling), v_list rebuild workers (SimulatorOptions::surface.threads: 0 = the
// hardware threads less one, i.e. serial on 2 cores; 1 = serial; 2 = two workers).
void BM_HapticLoop(benchmark::State& state) {
  const double seconds = static_cast<double>(state.range(0));
  const double spin_s = 1e-6 * static_cast<double>(state.range(1));
  const int priority = static_cast<int>(state.range(2));
  const int surface_threads = static_cast<int>(state.range(3));
  SessionStats st;
  const double cpu0 = process_cpu_s();
  for (auto _ : state) {
    TetHierarchy h(make_block(kBlock, kBlockCell));
    std::vector<double> t;
    std::vector<ToolPose> poses;
    for (int i = 0; i <= static_cast<int>(seconds * 100); ++i) {
      t.push_back(i * 0.01);
      ToolPose p;
      // Back and forth over x = 6…26 mm at 10 mm/s, 1 mm into the top face.
      const double x = 6.0 + std::abs(std::fmod(i * 0.1, 40.0) - 20.0);
      p.position_mm = Vec3(x, 16.0 + 3.0 * std::sin(i * 0.01), kBlock.z() + kRadius - 1.0);
      poses.push_back(p);
    }
    ScriptedTrajectory device(t, poses);
    SimulatorOptions o;
    o.tool.burr_radius_mm = kRadius;
    o.erosion = {.force_threshold_n = 0.2, .removal_rate_mm3_per_s = 30.0, .max_depth = 6};
    o.haptic_spin_s = spin_s;
    o.haptic_realtime_priority = priority;
    o.surface.threads = surface_threads;
    Simulator sim(h, device, o);
    sim.run(seconds + 30.0);
    st = sim.stats();
  }
  const auto force = percentiles(st.force_compute_time_s);
  state.counters["ticks"] = static_cast<double>(st.haptic_ticks);
  state.counters["missed_1ms"] = static_cast<double>(st.missed_deadlines);
  state.counters["realtime"] = st.haptic_realtime ? 1.0 : 0.0;
  add_ms_counters(state, "period_", st.haptic_period_s);
  state.counters["force_p99_9_ms"] = force.p999 * 1e3;
  state.counters["force_max_ms"] = force.max * 1e3;
  add_ms_counters(state, "update_", st.update_time_s);
  state.counters["removed_mm3"] = st.removed_volume_mm3;
  state.counters["backlog_max"] = static_cast<double>(st.erosion_backlog_max);
  state.counters["collision_updates"] = static_cast<double>(st.collision_updates);
  state.counters["process_cpu_s"] = process_cpu_s() - cpu0;  // all threads, incl. the spin
}
BENCHMARK(BM_HapticLoop)
    ->Args({10, 0, 80, 0})
    ->Args({60, 0, 80, 0})
    ->Args({60, 0, 80, 2})
    ->Args({60, 0, 0, 0})
    ->Args({60, 0, 0, 2})
    ->Args({60, 150, 80, 0})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

#ifdef IDO_BENCH_OPENVDB
BENCHMARK(BM_OpenVdbUpdateTime)->DenseRange(4, 8)->Iterations(1)->Unit(benchmark::kMillisecond);
#endif

}  // namespace

BENCHMARK_MAIN();

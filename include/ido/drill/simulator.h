// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

#include "ido/core/progress.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/collision.h"
#include "ido/drill/erosion.h"
#include "ido/drill/force.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/lock_free.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/drill/tool.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::drill {

/// Settings of a drilling session.
struct SimulatorOptions {
  ToolOptions tool;
  CouplingOptions coupling;
  ErosionOptions erosion;
  double haptic_period_s = 0.001;      ///< fixed haptic period (s); ≤ 0.001 for ≥ 1 kHz
  /// Hybrid wait of the haptic thread (s): it sleeps until this long before the next tick,
  /// then spins (with a pause instruction) until the tick, so a late wake-up from sleep
  /// eats into this margin instead of the period; costs up to this much CPU per tick.
  /// 0 (default) = sleep until the tick. Must be < haptic_period_s. Off by default: on the
  /// shared 2-core reference machine 150 µs doubled the missed deadlines (the spinning
  /// thread competes with the collision thread and is preempted more; see
  /// bench/results/drill.md); it is meant for a core of its own.
  double haptic_spin_s = 0.0;
  /// Real-time priority requested for the haptic thread: SCHED_FIFO at this priority
  /// (1–99), so that ordinary processes (a compiler, a browser) cannot delay its wake-ups;
  /// 0 = ordinary scheduling. Default 80. A refused request (no CAP_SYS_NICE and
  /// RLIMIT_RTPRIO below it, or not Linux) leaves the thread ordinary, and
  /// SessionStats::haptic_realtime says so. The kernel's real-time throttling
  /// (sched_rt_runtime_us) still bounds what a real-time thread can take from the rest.
  int haptic_realtime_priority = 80;
  /// The same for the collision/erosion thread; 0 (default) = ordinary. Give it a lower
  /// priority than the haptic thread: while a backlog lasts it runs without sleeping.
  int collision_realtime_priority = 0;
  double max_substep_mm = 0.0;         ///< erosion sub-steps along the motion; 0 = burr radius / 4
  std::size_t max_haptic_ticks = 1U << 20;  ///< timing samples kept (preallocated)
  double render_period_s = 1.0 / 60.0;  ///< render consumer polling period (s)
  /// v_list chunking and rebuild workers. Here `surface.threads` = 0 (default) means one
  /// less than the machine's hardware threads, at least 1, so that the haptic thread keeps a
  /// core: on 2 cores the rebuild runs serially on the collision thread
  /// (bench/results/drill.md, haptic loop with 1 and 2 workers).
  BoundarySurfaceOptions surface;
  /// v_list rebuild work per collision update (node visits; 0 = unlimited): chunks not
  /// rebuilt yet wait for the next update, so the render copy lags by a few updates.
  /// Default 8000.
  std::size_t surface_visits_per_update = 8000;
  /// Once the device reports the path finished, the collision thread takes the final pose,
  /// queues no more erosion, and finishes the erosion backlog and the v_list rebuild for at
  /// most this long (s, wall clock); what is still queued then is left undone and reported
  /// (SessionStats::backlog_left_positions). Default 10 s; a plunge-and-hold at 0.0625 mm
  /// leaves drains in well under 1 s (docs/drilling.md).
  double drain_limit_s = 10.0;
};

/// A picture request of the render consumer: the boundary surface as the render consumer
/// holds it at session time @p t_s (s), as per-root v_lists (see assemble_surface).
using SurfaceSnapshotFn = std::function<void(double t_s, const std::vector<std::vector<SurfaceFace>>& v_lists)>;

/// Order statistics of a series (same unit as the series).
struct Percentiles {
  double p50 = 0.0, p99 = 0.0, p999 = 0.0, max = 0.0;
  std::size_t count = 0;
};
/// Percentiles of @p values (ido::percentile's definition); all zero for an empty series.
[[nodiscard]] Percentiles percentiles(std::vector<double> values);

/// What a running session has measured so far, readable from any thread while it runs
/// (Simulator::live_stats).
struct LiveStats {
  std::size_t collision_updates = 0;  ///< collision/erosion updates so far
  /// The updates' times (s) so far. p50, p99 and p999 are ido::percentile's (linear
  /// interpolation between order statistics) over the updates' log-spaced time bins (24 a
  /// decade from 100 ns to 100 s), each order statistic taken as its bin's geometric centre: a
  /// figure lies within a factor Simulator::kLiveBinRatio^½ (4.9 %) of what stats() gives for the
  /// same updates once the session has stopped (times outside the bins count as the end bins).
  /// max and count are exact.
  Percentiles update_time_s;
  double removed_volume_mm3 = 0.0;  ///< material removed so far
};

/// Where a session's memory goes (bytes allocated, capacities; see Simulator::memory_use).
struct SessionMemory {
  std::size_t nodes = 0;     ///< the hierarchy's node storage (TetHierarchy::node_storage_capacity_bytes)
  std::size_t v_lists = 0;   ///< face lists: the authoritative chunks and the render consumer's copy
  std::size_t hash = 0;      ///< the roots' spatial hash
  std::size_t buffers = 0;   ///< timing and statistics records, hand-off buffers and the snapshot ring
  [[nodiscard]] std::size_t total() const noexcept { return nodes + v_lists + hash + buffers; }
};

/// What a session measured.
struct SessionStats {
  std::vector<double> update_time_s;        ///< collision thread: collide + erode + v_lists, per update
  std::vector<double> haptic_period_s;      ///< time between consecutive haptic tick starts
  std::vector<double> force_compute_time_s; ///< read pose → force written, per tick
  std::size_t haptic_ticks = 0;
  std::size_t missed_deadlines = 0;         ///< ticks finishing after their period ended
  bool haptic_realtime = false;              ///< the haptic thread got its real-time priority
  bool collision_realtime = false;           ///< the collision thread got its real-time priority
  int surface_threads = 1;                   ///< v_list rebuild workers used (SimulatorOptions::surface)
  std::size_t collision_updates = 0;
  std::size_t render_snapshots = 0;          ///< snapshots consumed by the render thread
  std::size_t surface_snapshots = 0;         ///< SurfaceSnapshotFn calls
  std::vector<double> erosion_visits;        ///< erosion node visits per update
  std::size_t erosion_backlog_max = 0;       ///< most burr positions queued at once
  double removed_volume_mm3 = 0.0;
  double peak_force_n = 0.0;
  double mean_force_n = 0.0;                  ///< over ticks in contact
  std::size_t contact_ticks = 0;
  double max_force_step_n = 0.0;             ///< largest change between consecutive ticks
  /// Wall-clock time (s) from the path's end (the first pose past it) until the backlog was
  /// finished or the drain limit stopped it; 0 when the session was stopped before.
  double drain_time_s = 0.0;
  /// Burr positions not eroded when the session ended (the drain limit, or stop() before the
  /// path ended); 0 when every queued position was processed.
  std::size_t backlog_left_positions = 0;
  bool path_finished = false;  ///< the session reached the path's end
  /// Erosion passes that left a leaf coarser than asked at ErosionOptions::max_nodes.
  std::size_t node_limit_passes = 0;
  bool timed_out = false;      ///< run() stopped at its timeout, before the session ended
};

/// A drilling session on three threads (Turini et al. 2007): a haptic thread at a fixed
/// period reads the device, computes the force from the latest contact model through the
/// virtual coupling (extrapolating between collision updates) and writes it back; a
/// collision/erosion thread collides the tool, erodes, rebuilds changed v_lists and
/// publishes a new contact model; a render consumer takes snapshots of changed v_lists.
/// Hand-offs: pose and contact model through triple buffers, snapshots through an SPSC
/// ring — no locks, allocation or exceptions on the haptic path.
///
/// The simulator borrows the hierarchy and the device; both must outlive it. While running,
/// only the collision thread touches the hierarchy.
class Simulator {
 public:
  /// @throws ido::InvalidInput for a non-positive haptic period, a spin time outside
  /// [0, period), a real-time priority outside [0, 99], or invalid tool / erosion options.
  Simulator(TetHierarchy& hierarchy, HapticDevice& device, const SimulatorOptions& options = {});
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  /// Asks the render consumer to call @p fn at session times 0, period, 2·period, … up to
  /// @p end_s (s) with its copy of the v_lists; times not reached when the session stops
  /// are served at the stop with the final surface. Runs on the render thread, never on the
  /// haptic or collision path. Call before start(). @throws ido::InvalidInput for a
  /// non-positive period.
  void set_surface_snapshots(SurfaceSnapshotFn fn, double period_s, double end_s);

  /// Starts the three threads.
  void start();
  /// Stops and joins them (idempotent).
  void stop();
  /// Starts, waits until the device reports finished and the backlog is drained (or
  /// @p timeout_s passes, then SessionStats::timed_out is set), stops. @p progress (may be
  /// null) gets the path time over HapticDevice::duration_s() while the path runs, stage
  /// "drilling", then "finishing"; its cancel() stops the session (ido::Cancelled is thrown
  /// after stop()).
  void run(double timeout_s = 1e9, Progress* progress = nullptr);

  /// Measurements (call after stop()).
  [[nodiscard]] const SessionStats& stats() const noexcept { return m_stats; }
  /// The session's figures so far, from any thread, while it runs or after (since the last
  /// start()): the collision thread counts each update's time in a log-spaced bin with an
  /// atomic counter (no lock, allocation or wait on its path), and this reads the bins.
  [[nodiscard]] LiveStats live_stats() const noexcept;
  /// Ratio of the upper to the lower edge of a live_stats() time bin (10^(1/24)).
  static constexpr double kLiveBinRatio = 1.1006941712522096;
  /// The authoritative boundary surface (call after stop()).
  [[nodiscard]] const BoundarySurface& surface() const noexcept { return m_surface; }
  /// The render consumer's copy of the v_lists (call after stop(); made from its chunk
  /// lists on the first call).
  [[nodiscard]] const std::vector<std::vector<SurfaceFace>>& render_v_lists() const;
  /// Moves the render consumer's copy of the v_lists out (call after stop(); afterwards
  /// render_v_lists() is empty): lets a caller free the simulator before using the surface.
  /// Where the copy is the surface's own lists (as after a finished session, when they are
  /// shared), they are taken from the surface (BoundarySurface::take_v_lists), so the faces
  /// are never held twice; surface() is then empty.
  [[nodiscard]] std::vector<std::vector<SurfaceFace>> take_render_v_lists();
  [[nodiscard]] const Tool& tool() const noexcept { return m_tool; }
  /// The session's memory by part, as it is now (call after stop() for the final figures).
  [[nodiscard]] SessionMemory memory_use() const noexcept;

 private:
  struct PoseSample {
    std::uint64_t sequence = 0;
    double t_s = 0.0;
    ToolPose pose;
    double force_n = 0.0;
  };
  struct Snapshot {
    std::vector<ChunkId> chunks;
    std::vector<std::uint32_t> chunk_counts;  // the root's chunk count, per entry
    std::vector<std::shared_ptr<const std::vector<SurfaceFace>>> lists;  // shared with the surface (immutable)
  };

  void haptic_loop();
  void collision_loop();
  void render_loop();
  void send_pending();
  void take_surface_snapshots(bool final);
  [[nodiscard]] double now_s() const noexcept;

  TetHierarchy& m_hierarchy;
  HapticDevice& m_device;
  SimulatorOptions m_options;
  Tool m_tool;
  Eroder m_eroder;
  BoundarySurface m_surface;
  VirtualCoupling m_coupling;

  TripleBuffer<PoseSample> m_pose_buffer;
  TripleBuffer<ContactModel> m_contact_buffer;
  SpscRing<std::unique_ptr<Snapshot>, 256> m_snapshots;
  std::vector<ChunkId> m_pending;  // changed chunks not yet sent (ring full)

  // The render consumer's copy: the chunk lists it was handed, shared with the surface until
  // a rebuild replaces them there (BoundarySurface::shared_chunk), so no face is copied.
  // After stop(), render_v_lists() flattens it (freeing each chunk as it is appended).
  mutable std::vector<std::vector<std::shared_ptr<const std::vector<SurfaceFace>>>> m_render_chunks;
  mutable std::vector<std::vector<SurfaceFace>> m_render_lists;  // flattened on request, after stop()
  SurfaceSnapshotFn m_snapshot_fn;
  double m_snapshot_period_s = 0.0;
  double m_snapshot_end_s = 0.0;
  std::size_t m_next_snapshot = 0;
  std::atomic<bool> m_stop{false};
  std::atomic<bool> m_collision_done{false};
  std::atomic<bool> m_finished{false};
  std::atomic<bool> m_collision_exited{false};
  std::atomic<bool> m_path_over{false};  // the collision thread took the path's last pose
  bool m_timed_out = false;               // run() gave up at its timeout
  bool m_running = false;
  std::thread m_haptic, m_collision, m_render;
  std::int64_t m_start_ns = 0;

  SessionStats m_stats;
  std::vector<double> m_tick_period, m_tick_compute, m_tick_force;

  // live_stats(): update times in log-spaced bins (kLiveBinsPerDecade a decade from
  // kLiveMin_s), written by the collision thread only (relaxed atomics: each counter is read
  // whole; the reader sums what it read, so its ranks are consistent), reset by start().
  static constexpr int kLiveBinsPerDecade = 24;
  static constexpr int kLiveBins = 9 * kLiveBinsPerDecade;  // 100 ns .. 100 s
  static constexpr double kLiveMin_s = 1e-7;
  void record_live_update(double seconds, double removed_mm3) noexcept;
  std::array<std::atomic<std::uint64_t>, kLiveBins> m_live_bins{};
  std::atomic<double> m_live_max_s{0.0};
  std::atomic<double> m_live_removed_mm3{0.0};
};

}  // namespace ido::drill

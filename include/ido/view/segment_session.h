// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/lock_free.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"
#include "ido/segment/balloon.h"

namespace ido::view {

/// Where a balloon run of a SegmentSession is.
enum class SegmentStage {
  Idle,       ///< no seed placed
  Preparing,  ///< the Balloon is being set up (image smoothing, intensity model)
  Inflating,  ///< Balloon::step() runs
  Paused,     ///< inflation paused by the user (step_once() advances one step)
  Finishing,  ///< Balloon::run(): the edge stage and the final repair
  Done,       ///< the result is ready
  Failed,     ///< the balloon threw (message in SegmentState::error)
};

[[nodiscard]] const char* segment_stage_name(SegmentStage stage) noexcept;

/// What the render thread sees of a run: an immutable picture of the balloon.
struct SegmentState {
  std::uint64_t run = 0;          ///< which run (each start() makes a new one)
  SegmentStage stage = SegmentStage::Idle;
  std::int64_t steps = 0;         ///< Balloon::step() calls so far
  geometry::TriangleMesh surface; ///< the balloon's surface now (mm)
  std::vector<Vec3> seeds_mm;     ///< the run's seeds
  /// The options the run was started with (its stop points are options.leak.stop_points_mm).
  segment::BalloonOptions options;
  /// The finished segmentation (stage Done): exactly what segment::segment_balloon returns for
  /// the same volume, seeds and options.
  std::shared_ptr<const segment::BalloonResult> result;
  std::string error;              ///< stage Failed: what went wrong
};

/// Runs the balloon of segment::Balloon on a worker thread, one step at a time, so a window
/// can draw it as it inflates. Each start() begins a new run with its seeds (Balloon takes
/// its seeds at construction) and retires the previous one, which stops at its next step.
/// Hand-over to the render thread is a triple buffer of immutable states: latest() never
/// waits, and no lock is taken on either side. The inflation (step() until it reports done)
/// is followed by Balloon::run(), which finishes from that state, so the result equals
/// segment_balloon()'s bit for bit however the run was paused or stepped.
class SegmentSession {
 public:
  /// @p ct is shared with the caller (the workbench's scene) and with the workers, which read it.
  explicit SegmentSession(std::shared_ptr<const image::Volume<float>> ct);
  ~SegmentSession();
  SegmentSession(const SegmentSession&) = delete;
  SegmentSession& operator=(const SegmentSession&) = delete;

  /// Starts a new run from @p seeds_mm with @p options (paused if @p paused); an empty seed
  /// list just retires the current run. Does not wait for the retired run.
  void start(std::vector<Vec3> seeds_mm, const segment::BalloonOptions& options, bool paused = false);
  /// Pauses or resumes the inflation of the current run.
  void set_paused(bool paused);
  [[nodiscard]] bool paused() const;
  /// While paused: one more Balloon::step().
  void step_once();

  /// The newest state handed over (never waits). Also joins retired workers that ended.
  [[nodiscard]] std::shared_ptr<const SegmentState> latest();
  /// True while a run is being computed (not Idle, Paused, Done or Failed).
  [[nodiscard]] bool busy();

 private:
  struct Run;
  static void work(Run& run, const image::Volume<float>& ct);
  void reap();

  std::shared_ptr<const image::Volume<float>> m_ct;
  std::uint64_t m_runs = 0;
  std::unique_ptr<Run> m_current;
  std::vector<std::unique_ptr<Run>> m_retired;
  std::shared_ptr<const SegmentState> m_latest;
};

}  // namespace ido::view

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/lock_free.h"
#include "ido/drill/simulator.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::view {

/// The haptic device of a window's drilling session. Either the window moves it — the render
/// thread sets the tool pose, the haptic thread reads it at every tick — or it passes on the
/// poses of another device (a path CSV replayed, the UDP bridge of an external device) and
/// sends that device the forces. Either way it records (time, pose) of every tick with a pose —
/// the session's path — into storage fixed at construction, and hands the newest pose and force
/// to the render thread through triple buffers. No lock, allocation or exception on the haptic
/// thread.
class WindowDevice final : public drill::HapticDevice {
 public:
  /// Keeps up to @p capacity ticks of path; the session finishes by itself after
  /// @p max_duration_s (s) of session time, or when @p source (if any) finishes.
  WindowDevice(std::size_t capacity, double max_duration_s, std::unique_ptr<drill::HapticDevice> source = nullptr);

  /// Render thread: the burr centre (mm, world) from now on (ignored with a source).
  void set_position(const Vec3& position_mm) noexcept;
  /// Render thread: the tool pose (burr centre, mm; orientation, shaft along local +z) from now on
  /// (ignored with a source).
  void set_pose(const drill::ToolPose& pose) noexcept;
  /// Render thread: ends the session at the next tick.
  void finish() noexcept { m_finished.store(true, std::memory_order_release); }

  drill::ToolPose read_pose(double t_s) noexcept override;
  void write_force(const Vec3& force_n, double t_s) noexcept override;
  [[nodiscard]] bool has_pose() const noexcept override;
  [[nodiscard]] bool finished(double t_s) const noexcept override;
  [[nodiscard]] double duration_s() const noexcept override { return m_source ? m_source->duration_s() : 0.0; }

  /// The device whose poses are passed on (null when the window moves the tool).
  [[nodiscard]] const drill::HapticDevice* source() const noexcept { return m_source.get(); }
  /// Render thread: the newest force the haptic thread rendered (N) and its session time (s).
  [[nodiscard]] drill::ForceSample latest_force() noexcept { return m_force.read(); }
  /// Render thread: the newest pose the haptic thread read.
  [[nodiscard]] drill::ToolPose latest_pose() noexcept { return m_shown.read(); }
  /// Ticks recorded so far; entries below it never change (any thread).
  [[nodiscard]] std::size_t recorded() const noexcept { return m_count.load(std::memory_order_acquire); }
  /// Session time (s), burr centre (mm) and pose of recorded tick @p i < recorded().
  [[nodiscard]] double time_s(std::size_t i) const noexcept { return m_times[i]; }
  [[nodiscard]] const Vec3& position_mm(std::size_t i) const noexcept { return m_poses[i].position_mm; }
  [[nodiscard]] const drill::ToolPose& pose(std::size_t i) const noexcept { return m_poses[i]; }

 private:
  std::unique_ptr<drill::HapticDevice> m_source;
  drill::TripleBuffer<drill::ToolPose> m_pose, m_shown;
  drill::TripleBuffer<drill::ForceSample> m_force;
  std::vector<double> m_times;
  std::vector<drill::ToolPose> m_poses;
  std::atomic<std::size_t> m_count{0};
  std::atomic<bool> m_has_pose{false};
  std::atomic<bool> m_finished{false};
  double m_max_duration_s;
};

/// A drilled surface handed to the window.
struct DrillSnapshot {
  double t_s = 0.0;                ///< session time (s)
  geometry::TriangleMesh surface;  ///< the material's boundary (mm), closed
  double volume_mm3 = 0.0;         ///< the volume it encloses (mm³)
  bool final = false;              ///< the surface after the session ended and the backlog drained
};

/// What the window shows of a running session.
struct DrillFigures {
  Vec3 force_n = Vec3::Zero();  ///< the newest rendered force (N)
  bool contact = false;          ///< the force is not zero
  double session_s = 0.0;        ///< session time of the newest tick (s)
  std::size_t ticks = 0;         ///< haptic ticks so far
  drill::Percentiles haptic_period_ms;  ///< over the last 2000 ticks (ms)
  /// The collision thread's update times so far this session (ms; drill::Simulator::live_stats:
  /// within 5 % of the final figures).
  drill::Percentiles update_time_ms;
  double removed_volume_mm3 = 0.0;  ///< removed so far, as the collision thread counts it
};

/// A drilling session driven from the window: drill::Simulator's three threads as `ido drill`
/// runs them (haptic loop at its period, collision/erosion, render consumer), with the device
/// moved by the window; the render consumer hands drilled surfaces to the window through a
/// triple buffer. start() and stop() never wait: Simulator::run() (which returns once the
/// device finished and the erosion backlog is drained) runs on a thread of its own.
class DrillSession {
 public:
  /// @p mesh is the material (mm); @p options as `ido drill` sets them (drill_cli_options());
  /// @p max_duration_s bounds the session (s). Without @p source the window moves the tool
  /// (move_tool()); with one, the tool follows it (a path replayed: load_path_device(); the UDP
  /// bridge of an external device) and the session ends when it finishes.
  /// @throws as drill::TetHierarchy and drill::Simulator.
  DrillSession(const geometry::TetMesh& mesh, const drill::SimulatorOptions& options, double max_duration_s = 60.0,
               std::unique_ptr<drill::HapticDevice> source = nullptr);
  ~DrillSession();
  DrillSession(const DrillSession&) = delete;
  DrillSession& operator=(const DrillSession&) = delete;

  /// Starts the threads with the tool at @p start (without a source; with one, the source places it).
  void start(const drill::ToolPose& start);
  /// Starts the threads with the burr at @p start_mm, the tool's axis along +z.
  void start(const Vec3& start_mm) {
    drill::ToolPose pose;
    pose.position_mm = start_mm;
    start(pose);
  }
  /// Moves the burr (render thread; ignored when the session has a source).
  void move_tool(const Vec3& position_mm) { m_device.set_position(position_mm); }
  /// Moves and turns the tool (render thread; ignored when the session has a source).
  void set_tool_pose(const drill::ToolPose& pose) { m_device.set_pose(pose); }
  /// The device the tool follows (null when the window moves it).
  [[nodiscard]] const drill::HapticDevice* source() const { return m_device.source(); }
  /// The newest tool pose the haptic thread read (render thread).
  [[nodiscard]] drill::ToolPose tool_pose() { return m_device.latest_pose(); }
  /// Ends the session (the simulator drains its backlog on its own thread).
  void stop() { m_device.finish(); }
  [[nodiscard]] bool started() const { return m_thread.joinable() || m_ended.load(); }
  /// True once Simulator::run() returned; stats() and the path are final then.
  [[nodiscard]] bool ended();

  /// The newest drilled surface handed over (null before the first).
  [[nodiscard]] std::shared_ptr<const DrillSnapshot> latest_surface();
  [[nodiscard]] DrillFigures figures();
  /// Material volume before the session (mm³).
  [[nodiscard]] double initial_volume_mm3() const { return m_initial_volume_mm3; }
  /// The session's measurements (after ended()).
  [[nodiscard]] const drill::SessionStats& stats() const { return m_simulator->stats(); }
  [[nodiscard]] const drill::SimulatorOptions& options() const { return m_options; }
  /// Writes the recorded path as CSV `t,x,y,z` (s, mm; one row per haptic tick with a pose, times
  /// strictly increasing), with `qx,qy,qz,qw` added when the tool was turned, which `ido drill
  /// --path` replays. @throws ido::IoError; ido::Error before ended().
  void write_path_csv(const std::filesystem::path& path) const;
  /// Runs on the simulator's render consumer: makes and hands over a surface.
  void take_snapshot(double t_s, const std::vector<std::vector<drill::SurfaceFace>>& v_lists);

 private:
  drill::SimulatorOptions m_options;
  double m_max_duration_s;
  std::unique_ptr<drill::TetHierarchy> m_hierarchy;
  std::vector<Vec3> m_root_vertices;
  double m_initial_volume_mm3 = 0.0;
  WindowDevice m_device;
  std::unique_ptr<drill::Simulator> m_simulator;
  drill::TripleBuffer<std::shared_ptr<const DrillSnapshot>> m_surfaces;
  std::shared_ptr<const DrillSnapshot> m_latest;
  std::chrono::steady_clock::time_point m_start;
  std::thread m_thread;
  std::atomic<bool> m_ended{false};
  std::atomic<bool> m_failed{false};
};

/// The path CSV @p csv (`ido drill --path`'s format: ScriptedTrajectory::load_csv) as a device
/// replaying it, its force record sized as `ido drill` sizes it for @p options (the path's ticks
/// and the drain). @throws ido::IoError naming the file and line of a malformed path.
[[nodiscard]] std::unique_ptr<drill::ScriptedTrajectory> load_path_device(const std::filesystem::path& csv,
                                                                          const drill::SimulatorOptions& options);

/// The simulator options `ido drill` uses for a burr of @p burr_radius_mm (with a shaft of
/// @p shaft_radius_mm, 0 = none: `--tool sphere:radius=R,shaft=S`) with its default arguments:
/// force threshold 0.2 N, removal at once (rate 0), coupling 1.5 N/mm, leaves down to a quarter
/// of the burr radius.
[[nodiscard]] drill::SimulatorOptions drill_cli_options(double burr_radius_mm, double shaft_radius_mm = 0.0);

}  // namespace ido::view

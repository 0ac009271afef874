// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/tool.h"

namespace ido::drill {

/// A haptic device as the haptic thread sees it: a pose in, a force out, once per tick.
/// Both calls run on the haptic thread at ≥ 1 kHz: implementations must not lock,
/// allocate or throw.
class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  /// Tool pose at session time @p t_s (s).
  virtual ToolPose read_pose(double t_s) noexcept = 0;
  /// Force (N) to render at session time @p t_s.
  virtual void write_force(const Vec3& force_n, double t_s) noexcept = 0;
  /// False while the device has no pose yet (e.g. no packet received): the haptic thread
  /// then renders no force and does not move the tool.
  [[nodiscard]] virtual bool has_pose() const noexcept { return true; }
  /// True once the session is over (end of a script, end-of-session packet, …).
  [[nodiscard]] virtual bool finished(double t_s) const noexcept = 0;
  /// Length of the session (s) when known in advance (a script), else 0; for progress.
  [[nodiscard]] virtual double duration_s() const noexcept { return 0.0; }
};

/// Longest scripted path (s) ScriptedTrajectory accepts. A script is played in real time
/// (a session lasts as long as its path), so a last time of 1e30 — a typo, or a file in
/// other units — would run for ever; one hour is far beyond any drilling script (the
/// force record holds 2^20 samples, 17.5 min at 1 kHz).
inline constexpr double kMaxScriptDuration_s = 3600.0;

/// One recorded force sample.
struct ForceSample {
  double t_s = 0.0;
  Vec3 force_n = Vec3::Zero();
};

/// A device replaying a scripted trajectory: poses interpolated linearly in position and
/// by slerp in orientation between keyframes; it records the forces it receives (up to a
/// capacity fixed at construction, so recording never allocates).
class ScriptedTrajectory final : public HapticDevice {
 public:
  /// @p times_s strictly increasing, at most kMaxScriptDuration_s, same size as @p poses
  /// (≥ 1). @p force_capacity: samples kept. @throws ido::InvalidInput otherwise.
  ScriptedTrajectory(std::vector<double> times_s, std::vector<ToolPose> poses, std::size_t force_capacity = 1U << 20);

  /// Reads a CSV with columns t, x, y, z [, qx, qy, qz, qw] (s, mm). The first line may be a
  /// header, whose every field is a name (not a number); blank lines and lines starting with
  /// '#' are skipped. @throws ido::IoError naming the file and line for malformed content: a
  /// field that is not a finite number (also on the first line when other fields are
  /// numbers), 4 or 8 columns, times increasing strictly and at most kMaxScriptDuration_s.
  [[nodiscard]] static ScriptedTrajectory load_csv(const std::filesystem::path& path,
                                                   std::size_t force_capacity = 1U << 20);

  ToolPose read_pose(double t_s) noexcept override;
  void write_force(const Vec3& force_n, double t_s) noexcept override;
  [[nodiscard]] bool finished(double t_s) const noexcept override { return t_s > m_times.back(); }
  [[nodiscard]] double duration_s() const noexcept override { return duration(); }

  /// Pose at @p t_s without side effects.
  [[nodiscard]] ToolPose pose_at(double t_s) const noexcept;
  /// Duration of the script (s).
  [[nodiscard]] double duration() const noexcept { return m_times.back(); }
  /// Forces received so far (call after the session's threads stopped).
  [[nodiscard]] std::span<const ForceSample> forces() const noexcept { return {m_forces.data(), m_force_count}; }
  [[nodiscard]] const std::vector<double>& times() const noexcept { return m_times; }
  [[nodiscard]] const std::vector<ToolPose>& poses() const noexcept { return m_poses; }

 private:
  std::vector<double> m_times;
  std::vector<ToolPose> m_poses;
  std::vector<ForceSample> m_forces;
  std::size_t m_force_count = 0;
};

}  // namespace ido::drill

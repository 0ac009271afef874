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
};

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
  /// @p times_s strictly increasing, same size as @p poses (≥ 1). @p force_capacity:
  /// samples kept. @throws ido::InvalidInput otherwise.
  ScriptedTrajectory(std::vector<double> times_s, std::vector<ToolPose> poses, std::size_t force_capacity = 1U << 20);

  /// Reads a CSV with columns t, x, y, z [, qx, qy, qz, qw] (s, mm; a header line is
  /// allowed). @throws ido::IoError naming the file and line for malformed content.
  [[nodiscard]] static ScriptedTrajectory load_csv(const std::filesystem::path& path,
                                                   std::size_t force_capacity = 1U << 20);

  ToolPose read_pose(double t_s) noexcept override;
  void write_force(const Vec3& force_n, double t_s) noexcept override;
  [[nodiscard]] bool finished(double t_s) const noexcept override { return t_s > m_times.back(); }

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

// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/haptic_device.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include "ido/core/error.h"

namespace ido::drill {

ScriptedTrajectory::ScriptedTrajectory(std::vector<double> times_s, std::vector<ToolPose> poses,
                                       std::size_t force_capacity)
    : m_times(std::move(times_s)), m_poses(std::move(poses)), m_forces(force_capacity) {
  if (m_times.empty() || m_times.size() != m_poses.size()) {
    throw InvalidInput("trajectory: needs at least one keyframe and one pose per time");
  }
  for (std::size_t i = 0; i < m_times.size(); ++i) {
    if (!std::isfinite(m_times[i]) || !m_poses[i].position_mm.allFinite() || !m_poses[i].orientation.coeffs().allFinite()) {
      throw InvalidInput("trajectory: keyframe " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(m_times[i] > m_times[i - 1])) {
      throw InvalidInput("trajectory: times must increase strictly (keyframe " + std::to_string(i) + ")");
    }
    if (m_times[i] > kMaxScriptDuration_s) {
      throw InvalidInput(fmt::format("trajectory: time {:g} s at keyframe {} is beyond the longest script played in real time ({:g} s)",
                                     m_times[i], i, kMaxScriptDuration_s));
    }
    if (m_poses[i].orientation.norm() < 1e-12) throw InvalidInput("trajectory: zero quaternion at keyframe " + std::to_string(i));
    m_poses[i].orientation.normalize();
  }
}

ScriptedTrajectory ScriptedTrajectory::load_csv(const std::filesystem::path& path, std::size_t force_capacity) {
  std::ifstream in(path);
  if (!in) throw IoError(path.string(), "cannot open the trajectory file");
  std::vector<double> times;
  std::vector<ToolPose> poses;
  std::string line;
  std::int64_t line_no = 0;
  bool first_content = true;
  const auto at_line = [&](std::int64_t n) { return FileLocation{.line = n, .byte_offset = std::nullopt}; };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    std::vector<double> v;
    std::vector<std::string> bad;  // the fields that are not numbers
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      double d = 0.0;
      try {
        std::size_t used = 0;
        d = std::stod(cell, &used);
        if (cell.find_first_not_of(" \t", used) != std::string::npos) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        bad.push_back(cell);
        continue;
      }
      v.push_back(d);
    }
    const bool header = first_content && v.empty();  // every field a name
    first_content = false;
    if (header) continue;
    if (!bad.empty()) {
      throw IoError(path.string(), "'" + bad.front() + "' is not a number (expected t,x,y,z[,qx,qy,qz,qw]; a header line has names only)",
                    at_line(line_no));
    }
    if (v.size() != 4 && v.size() != 8) {
      throw IoError(path.string(), "expected 4 or 8 columns, found " + std::to_string(v.size()), {.line = line_no, .byte_offset = std::nullopt});
    }
    for (double d : v)
      if (!std::isfinite(d)) throw IoError(path.string(), "non-finite value", {.line = line_no, .byte_offset = std::nullopt});
    if (!times.empty() && !(v[0] > times.back())) {
      throw IoError(path.string(), "time must increase strictly", {.line = line_no, .byte_offset = std::nullopt});
    }
    if (v[0] > kMaxScriptDuration_s) {
      throw IoError(path.string(),
                    fmt::format("time {:g} s is beyond the longest path played in real time ({:g} s)", v[0], kMaxScriptDuration_s),
                    at_line(line_no));
    }
    ToolPose p;
    p.position_mm = Vec3(v[1], v[2], v[3]);
    if (v.size() == 8) {
      p.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
      if (p.orientation.norm() < 1e-9) throw IoError(path.string(), "zero quaternion", {.line = line_no, .byte_offset = std::nullopt});
      p.orientation.normalize();
    }
    times.push_back(v[0]);
    poses.push_back(p);
  }
  if (times.empty()) throw IoError(path.string(), "no trajectory rows");
  return ScriptedTrajectory(std::move(times), std::move(poses), force_capacity);
}

ToolPose ScriptedTrajectory::pose_at(double t_s) const noexcept {
  if (t_s <= m_times.front()) return m_poses.front();
  if (t_s >= m_times.back()) return m_poses.back();
  const auto it = std::upper_bound(m_times.begin(), m_times.end(), t_s);
  const auto i = static_cast<std::size_t>(it - m_times.begin());
  const double a = (t_s - m_times[i - 1]) / (m_times[i] - m_times[i - 1]);
  ToolPose p;
  p.position_mm = (1.0 - a) * m_poses[i - 1].position_mm + a * m_poses[i].position_mm;
  p.orientation = m_poses[i - 1].orientation.slerp(a, m_poses[i].orientation);
  return p;
}

ToolPose ScriptedTrajectory::read_pose(double t_s) noexcept { return pose_at(t_s); }

void ScriptedTrajectory::write_force(const Vec3& force_n, double t_s) noexcept {
  if (m_force_count < m_forces.size()) m_forces[m_force_count++] = {t_s, force_n};
}

}  // namespace ido::drill

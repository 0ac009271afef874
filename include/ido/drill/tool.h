// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "ido/core/math.h"

namespace ido::drill {

/// Shape of the drilling tool: a spherical burr and an optional cylindrical shaft along the
/// tool's local +z axis, starting at the burr centre.
struct ToolOptions {
  double burr_radius_mm = 2.0;   ///< burr radius (mm), > 0
  double shaft_radius_mm = 0.0;  ///< shaft radius (mm); 0 = no shaft; must be < burr radius
  double shaft_length_mm = 30.0; ///< shaft length from the burr centre (mm)
  int sample_count = 1000;       ///< points spread over the burr surface (≥ 20)
};

/// Pose of the tool: burr centre (mm, world) and orientation (local +z = shaft direction).
struct ToolPose {
  Vec3 position_mm = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// The tool and its surface samples (in tool coordinates: burr centre at the origin).
/// The burr surface is sampled by a Fibonacci sphere (evenly spread points, González 2010,
/// "Measurement of areas on a sphere using Fibonacci and latitude–longitude lattices");
/// the shaft by rings at the same spacing.
class Tool {
 public:
  /// @throws ido::InvalidInput for a non-positive radius, a shaft at least as thick as the
  /// burr, or fewer than 20 samples.
  explicit Tool(const ToolOptions& options = {});

  [[nodiscard]] const ToolOptions& options() const noexcept { return m_options; }
  [[nodiscard]] double burr_radius() const noexcept { return m_options.burr_radius_mm; }
  /// Burr surface samples (mm, relative to the burr centre).
  [[nodiscard]] std::span<const Vec3> burr_samples() const noexcept { return m_burr; }
  /// Shaft surface samples (mm, tool frame), ring by ring.
  [[nodiscard]] std::span<const Vec3> shaft_samples() const noexcept { return m_shaft; }
  /// Samples per shaft ring (0 without a shaft).
  [[nodiscard]] int shaft_ring_size() const noexcept { return m_ring; }

 private:
  ToolOptions m_options;
  std::vector<Vec3> m_burr;
  std::vector<Vec3> m_shaft;
  int m_ring = 0;
};

/// @p n unit vectors spread evenly over the sphere (Fibonacci lattice). n ≥ 1.
[[nodiscard]] std::vector<Vec3> fibonacci_sphere(int n);

/// Parses "sphere:radius=MM[,shaft=MM][,samples=N]" (shaft = shaft radius).
/// @throws ido::InvalidInput naming the text and what is wrong.
[[nodiscard]] ToolOptions parse_tool(std::string_view spec);

}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>

#include "ido/core/math.h"
#include "ido/viz/camera.h"

namespace ido::view {

/// The 3-D view's camera: it orbits a target at a distance, turned by a mouse drag (azimuth
/// about world +z, elevation towards +z), moved by a pan and brought closer or farther by the
/// wheel. Angles in degrees, lengths in mm; the same conventions as viz::Camera::orbit.
class OrbitCamera {
 public:
  /// Frames the box [@p lo, @p hi] (mm) at the given angles: viz::Camera::orbit's framing for a
  /// square picture, 1.3 times farther, so views down to 3:4 (width:height) show it whole.
  void frame(const Vec3& lo, const Vec3& hi, double azimuth_deg = 30.0, double elevation_deg = 20.0);
  /// Turns by a drag of (@p dx_px, @p dy_px) pixels: 0.4° per pixel, elevation kept within ±89°.
  void rotate(double dx_px, double dy_px);
  /// Moves the target so the scene follows a drag of (@p dx_px, @p dy_px) pixels in a view
  /// @p view_height_px tall.
  void pan(double dx_px, double dy_px, double view_height_px);
  /// Scales the distance by 0.9^notches (positive notches bring the eye closer), at least 1 mm.
  void zoom(double notches);

  /// The camera for a view of width/height @p aspect (perspective, 30° vertical field of view,
  /// near and far planes around the framed box).
  [[nodiscard]] viz::Camera camera() const;
  /// The ray (origin, unit direction; mm) through pixel (@p x_px, @p y_px) of a
  /// @p width_px × @p height_px view, (0, 0) its top-left corner.
  [[nodiscard]] std::array<Vec3, 2> pick_ray(double x_px, double y_px, double width_px, double height_px) const;

  [[nodiscard]] double azimuth_deg() const { return m_azimuth_deg; }
  [[nodiscard]] double elevation_deg() const { return m_elevation_deg; }
  [[nodiscard]] double distance_mm() const { return m_distance_mm; }
  [[nodiscard]] const Vec3& target() const { return m_target; }

 private:
  Vec3 m_target = Vec3::Zero();
  double m_azimuth_deg = 30.0, m_elevation_deg = 20.0;
  double m_distance_mm = 100.0;
  double m_radius_mm = 50.0;  // half the framed box's diagonal: sets near / far
};

}  // namespace ido::view

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>

#include "ido/core/math.h"

namespace ido::viz {

/// How the camera projects the scene.
enum class Projection {
  Orthographic,  ///< parallel rays; sizes in the picture do not depend on depth
  Perspective,   ///< pinhole camera with a vertical field of view
};

/// A look-at camera in world space (mm). The eye sits at target + distance_mm · direction
/// and looks at the target; `up` is projected to the picture's vertical.
struct Camera {
  Vec3 target = Vec3::Zero();        ///< point looked at (mm)
  Vec3 direction = Vec3(0, -1, 0);   ///< unit vector from the target towards the eye
  Vec3 up = Vec3(0, 0, 1);           ///< world direction shown upwards (not parallel to direction)
  double distance_mm = 100.0;        ///< eye–target distance (mm), > 0
  Projection projection = Projection::Orthographic;
  double half_height_mm = 50.0;      ///< orthographic: half the visible height at the target (mm)
  double fov_y_deg = 30.0;           ///< perspective: vertical field of view (degrees)
  double near_mm = 1.0;              ///< near clipping distance from the eye (mm), > 0
  double far_mm = 1000.0;            ///< far clipping distance from the eye (mm), > near_mm

  /// The eye position (mm).
  [[nodiscard]] Vec3 eye() const { return target + distance_mm * direction; }

  /// World → eye transform (OpenGL convention: the eye looks down −z, y is up).
  [[nodiscard]] Mat4 view_matrix() const;

  /// Eye → clip transform for a picture of width/height @p aspect (OpenGL convention).
  [[nodiscard]] Mat4 projection_matrix(double aspect) const;

  /// A camera orbiting the centre of the box [lo, hi] (mm) that shows the whole box in a
  /// picture of width/height @p aspect. Azimuth turns around the world z axis (0° looks from
  /// −y, i.e. from the front in LPS, 90° from +x); elevation lifts the eye towards +z
  /// (90° looks straight down). Up is +z (or +y when looking along z).
  [[nodiscard]] static Camera orbit(const Vec3& lo, const Vec3& hi, double azimuth_deg,
                                    double elevation_deg, Projection projection, double aspect);
};

}  // namespace ido::viz

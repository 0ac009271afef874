// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/core/math.h"

namespace ido::geometry {

/// The point of the closed triangle (a, b, c) closest to @p p (mm), found by locating p in
/// the Voronoi regions of the triangle's vertices, edges and face (the method of Ericson,
/// Real-Time Collision Detection, 2005, §5.1.5; implemented for this project). Degenerate
/// triangles are handled: the result is then the closest point of the segment or point.
[[nodiscard]] Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                             const Vec3& c);

/// Euclidean distance (mm) from @p p to the closed triangle (a, b, c).
[[nodiscard]] double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b,
                                             const Vec3& c);

/// The point of the closed segment [a, b] closest to @p p (mm); a when a = b.
[[nodiscard]] Vec3 closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b);

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <limits>
#include <span>

#include "ido/core/math.h"

namespace ido::geometry {

/// An axis-aligned bounding box in world coordinates (mm). Closed: a box contains the points
/// of its faces. A default-constructed box is empty (min = +inf, max = −inf) and grows with
/// extend().
struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  /// The box of a single point.
  [[nodiscard]] static Aabb of_point(const Vec3& p) { return {p, p}; }
  /// The box of @p points (empty for none).
  [[nodiscard]] static Aabb of(std::span<const Vec3> points) {
    Aabb b;
    for (const Vec3& p : points) b.extend(p);
    return b;
  }
  /// The box of three points (a triangle).
  [[nodiscard]] static Aabb of_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    return {a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)};
  }

  /// True when no point was ever added.
  [[nodiscard]] bool empty() const {
    return min.x() > max.x() || min.y() > max.y() || min.z() > max.z();
  }
  /// Grows the box to contain @p p.
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  /// Grows the box to contain @p other.
  void extend(const Aabb& other) {
    min = min.cwiseMin(other.min);
    max = max.cwiseMax(other.max);
  }
  /// True when the two closed boxes share at least one point (touching counts).
  [[nodiscard]] bool overlaps(const Aabb& o) const {
    return min.x() <= o.max.x() && o.min.x() <= max.x() && min.y() <= o.max.y() &&
           o.min.y() <= max.y() && min.z() <= o.max.z() && o.min.z() <= max.z();
  }
  /// True when @p p lies in the closed box.
  [[nodiscard]] bool contains(const Vec3& p) const {
    return p.x() >= min.x() && p.x() <= max.x() && p.y() >= min.y() && p.y() <= max.y() &&
           p.z() >= min.z() && p.z() <= max.z();
  }
  /// True when @p o lies entirely in this box.
  [[nodiscard]] bool contains(const Aabb& o) const { return contains(o.min) && contains(o.max); }
  /// max − min (mm); zero vector for an empty box.
  [[nodiscard]] Vec3 extent() const { return empty() ? Vec3::Zero() : Vec3(max - min); }
  /// Length of the diagonal (mm); 0 for an empty box.
  [[nodiscard]] double diagonal() const { return extent().norm(); }
  /// Centre of the box (mm). Undefined for an empty box.
  [[nodiscard]] Vec3 centre() const { return 0.5 * (min + max); }
  /// Index (0, 1, 2) of the longest side.
  [[nodiscard]] int longest_axis() const {
    const Vec3 e = extent();
    return e.x() >= e.y() ? (e.x() >= e.z() ? 0 : 2) : (e.y() >= e.z() ? 1 : 2);
  }
  /// The box grown by @p margin_mm on every side.
  [[nodiscard]] Aabb inflated(double margin_mm) const {
    return {min.array() - margin_mm, max.array() + margin_mm};
  }
  /// Squared distance (mm²) from @p p to the closed box; 0 inside.
  [[nodiscard]] double squared_distance(const Vec3& p) const {
    const Vec3 d = (min - p).cwiseMax(p - max).cwiseMax(Vec3::Zero());
    return d.squaredNorm();
  }
};

}  // namespace ido::geometry

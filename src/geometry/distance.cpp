// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/distance.h"

#include <algorithm>

namespace ido::geometry {

Vec3 closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a;
  const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return a + t * ab;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const Vec3 n = ab.cross(ac);
  if (n.squaredNorm() <= 1e-30 * std::max(ab.squaredNorm(), ac.squaredNorm()) *
                             std::max(ab.squaredNorm(), ac.squaredNorm()) ||
      n.squaredNorm() == 0.0) {
    // Degenerate: the closest of the three edge candidates.
    const Vec3 c1 = closest_point_on_segment(p, a, b);
    const Vec3 c2 = closest_point_on_segment(p, b, c);
    const Vec3 c3 = closest_point_on_segment(p, c, a);
    const double d1 = (p - c1).squaredNorm(), d2 = (p - c2).squaredNorm(), d3 = (p - c3).squaredNorm();
    return d1 <= d2 ? (d1 <= d3 ? c1 : c3) : (d2 <= d3 ? c2 : c3);
  }
  // Vertex region of a.
  const Vec3 ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  // Vertex region of b.
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  // Edge region of ab.
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
  // Vertex region of c.
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  // Edge region of ac.
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
  // Edge region of bc.
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  // Face region: barycentric coordinates (1 − v − w, v, w).
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom;
  const double w = vc * denom;
  return a + v * ab + w * ac;
}

double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  return (p - closest_point_on_triangle(p, a, b, c)).norm();
}

}  // namespace ido::geometry

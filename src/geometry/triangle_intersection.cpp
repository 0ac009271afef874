// SPDX-License-Identifier: Apache-2.0
// Exact triangle–triangle intersection built on orient3d / orient2d (this project's own
// formulation; the orientation-based case analysis is in the spirit of Guigue & Devillers,
// "Fast and robust triangle-triangle overlap test using orientation predicates", JGT 2003).
#include "ido/geometry/triangle_intersection.h"

#include <algorithm>
#include <cmath>

#include "ido/geometry/predicates.h"

namespace ido::geometry {
namespace {

Vec2 project(const Vec3& p, int drop) { return {p[(drop + 1) % 3], p[(drop + 2) % 3]}; }

int sgn3(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return sign_of(orient3d(a, b, c, d));
}

/// An axis whose removal keeps the triangle non-degenerate, or −1 if it is collinear.
int proper_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).cwiseAbs();
  const int first = n.x() >= n.y() ? (n.x() >= n.z() ? 0 : 2) : (n.y() >= n.z() ? 1 : 2);
  if (orient2d_projected(a, b, c, first) != 0.0) return first;
  for (int k = 0; k < 3; ++k) {
    if (k != first && orient2d_projected(a, b, c, k) != 0.0) return k;
  }
  return -1;
}

bool in_box_2d(const Vec2& p, const Vec2& q, const Vec2& r) {
  return r.x() >= std::min(p.x(), q.x()) && r.x() <= std::max(p.x(), q.x()) &&
         r.y() >= std::min(p.y(), q.y()) && r.y() <= std::max(p.y(), q.y());
}

/// Closed segments [p, q] and [r, s] share a point (degenerate segments allowed).
bool segments_intersect_2d(const Vec2& p, const Vec2& q, const Vec2& r, const Vec2& s) {
  const int o1 = sign_of(orient2d(p, q, r));
  const int o2 = sign_of(orient2d(p, q, s));
  const int o3 = sign_of(orient2d(r, s, p));
  const int o4 = sign_of(orient2d(r, s, q));
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  if (o1 == 0 && in_box_2d(p, q, r)) return true;
  if (o2 == 0 && in_box_2d(p, q, s)) return true;
  if (o3 == 0 && in_box_2d(r, s, p)) return true;
  if (o4 == 0 && in_box_2d(r, s, q)) return true;
  return false;
}

/// p lies in the closed hull of a, b, c (which may be collinear).
bool point_in_hull_2d(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c) {
  const int o = sign_of(orient2d(a, b, c));
  if (o != 0) {
    return sign_of(orient2d(a, b, p)) * o >= 0 && sign_of(orient2d(b, c, p)) * o >= 0 &&
           sign_of(orient2d(c, a, p)) * o >= 0;
  }
  auto on = [&](const Vec2& u, const Vec2& v) { return orient2d(u, v, p) == 0.0 && in_box_2d(u, v, p); };
  return on(a, b) || on(b, c) || on(a, c);
}

bool hulls_intersect_2d(const std::array<Vec2, 3>& a, const std::array<Vec2, 3>& b) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (segments_intersect_2d(a[static_cast<std::size_t>(i)], a[static_cast<std::size_t>((i + 1) % 3)],
                                b[static_cast<std::size_t>(j)], b[static_cast<std::size_t>((j + 1) % 3)])) {
        return true;
      }
    }
  }
  return point_in_hull_2d(a[0], b[0], b[1], b[2]) || point_in_hull_2d(b[0], a[0], a[1], a[2]);
}

std::array<Vec2, 3> project3(const Triangle3& t, int drop) {
  return {project(t[0], drop), project(t[1], drop), project(t[2], drop)};
}

/// [p, q] against a non-degenerate triangle whose plane sides of p and q are known.
bool segment_triangle_signs(const Vec3& p, const Vec3& q, int op, int oq, const Triangle3& t,
                            int t_axis) {
  if (op * oq > 0) return false;
  if (op == 0 && oq == 0) {
    const Vec2 p2 = project(p, t_axis);
    const Vec2 q2 = project(q, t_axis);
    const auto t2 = project3(t, t_axis);
    return segments_intersect_2d(p2, q2, t2[0], t2[1]) ||
           segments_intersect_2d(p2, q2, t2[1], t2[2]) ||
           segments_intersect_2d(p2, q2, t2[2], t2[0]) || point_in_hull_2d(p2, t2[0], t2[1], t2[2]);
  }
  // The segment crosses or touches the plane at one point; the line passes through the
  // closed triangle iff it is on the same side of (or on) all three edge lines.
  const int s1 = sgn3(p, q, t[0], t[1]);
  const int s2 = sgn3(p, q, t[1], t[2]);
  const int s3 = sgn3(p, q, t[2], t[0]);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

bool segment_triangle_proper(const Vec3& p, const Vec3& q, const Triangle3& t, int t_axis) {
  return segment_triangle_signs(p, q, sgn3(t[0], t[1], t[2], p), sgn3(t[0], t[1], t[2], q), t,
                                t_axis);
}

/// Drop axis for a set of coplanar points: injective on their plane (or line).
int injective_axis(const std::array<const Vec3*, 6>& pts, int n) {
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      for (int k = j + 1; k < n; ++k) {
        const int ax = proper_axis(*pts[static_cast<std::size_t>(i)], *pts[static_cast<std::size_t>(j)],
                                   *pts[static_cast<std::size_t>(k)]);
        if (ax >= 0) return ax;
      }
    }
  }
  // All collinear: keep the coordinate along which the points spread most.
  Vec3 lo = *pts[0];
  Vec3 hi = *pts[0];
  for (int i = 1; i < n; ++i) {
    lo = lo.cwiseMin(*pts[static_cast<std::size_t>(i)]);
    hi = hi.cwiseMax(*pts[static_cast<std::size_t>(i)]);
  }
  const Vec3 e = hi - lo;
  // Drop the axis of least spread: the largest spread is then kept.
  return e.x() <= e.y() ? (e.x() <= e.z() ? 0 : 2) : (e.y() <= e.z() ? 1 : 2);
}

/// General closed-hull test used when a triangle is degenerate.
bool hulls_intersect_3d(const Triangle3& a, int a_axis, const Triangle3& b, int b_axis) {
  const std::array<const Vec3*, 6> pts{&a[0], &a[1], &a[2], &b[0], &b[1], &b[2]};
  // Find a plane through three of the points; all coplanar → 2D test.
  int base = -1;
  std::array<int, 3> tri{};
  for (int i = 0; i < 6 && base < 0; ++i) {
    for (int j = i + 1; j < 6 && base < 0; ++j) {
      for (int k = j + 1; k < 6 && base < 0; ++k) {
        if (!collinear3d(*pts[static_cast<std::size_t>(i)], *pts[static_cast<std::size_t>(j)],
                         *pts[static_cast<std::size_t>(k)])) {
          base = 0;
          tri = {i, j, k};
        }
      }
    }
  }
  bool coplanar = true;
  if (base == 0) {
    for (int m = 0; m < 6 && coplanar; ++m) {
      coplanar = orient3d(*pts[static_cast<std::size_t>(tri[0])], *pts[static_cast<std::size_t>(tri[1])],
                          *pts[static_cast<std::size_t>(tri[2])], *pts[static_cast<std::size_t>(m)]) == 0.0;
    }
  }
  if (coplanar) {
    const int ax = injective_axis(pts, 6);
    return hulls_intersect_2d(project3(a, ax), project3(b, ax));
  }
  if (a_axis >= 0) {
    for (int i = 0; i < 3; ++i) {
      if (segment_triangle_proper(b[static_cast<std::size_t>(i)], b[static_cast<std::size_t>((i + 1) % 3)], a, a_axis)) return true;
    }
  }
  if (b_axis >= 0) {
    for (int i = 0; i < 3; ++i) {
      if (segment_triangle_proper(a[static_cast<std::size_t>(i)], a[static_cast<std::size_t>((i + 1) % 3)], b, b_axis)) return true;
    }
  }
  return false;  // two non-coplanar segments/points: no common point
}

bool boxes_disjoint(const Triangle3& a, const Triangle3& b) {
  for (int k = 0; k < 3; ++k) {
    const double amin = std::min({a[0][k], a[1][k], a[2][k]});
    const double amax = std::max({a[0][k], a[1][k], a[2][k]});
    const double bmin = std::min({b[0][k], b[1][k], b[2][k]});
    const double bmax = std::max({b[0][k], b[1][k], b[2][k]});
    if (amax < bmin || bmax < amin) return true;
  }
  return false;
}

/// Whether v + ε (x − v) lies in the closed triangle t = (v, t1, t2) for some ε > 0.
bool in_tangent_cone(const Vec3& v, const Vec3& x, const Vec3& t1, const Vec3& t2, int t_axis) {
  if (x == v) return false;
  if (t_axis >= 0) {
    if (orient3d(v, t1, t2, x) != 0.0) return false;
    const int s = sign_of(orient2d_projected(v, t1, t2, t_axis));
    return sign_of(orient2d_projected(v, t1, x, t_axis)) * s >= 0 &&
           sign_of(orient2d_projected(v, x, t2, t_axis)) * s >= 0;
  }
  // Degenerate t: a segment (or point) through v; its directions from v are towards t1, t2.
  for (const Vec3* t : {&t1, &t2}) {
    if (*t == v || !collinear3d(v, *t, x)) continue;
    const Vec3 d = (*t - v).cwiseAbs();
    const int m = d.x() >= d.y() ? (d.x() >= d.z() ? 0 : 2) : (d.y() >= d.z() ? 1 : 2);
    if (((*t)[m] > v[m]) == (x[m] > v[m]) && x[m] != v[m]) return true;
  }
  return false;
}

}  // namespace

bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Triangle3& t) {
  const Triangle3 seg{p, q, q};
  if (boxes_disjoint(seg, t)) return false;
  const int ax = proper_axis(t[0], t[1], t[2]);
  if (ax >= 0) return segment_triangle_proper(p, q, t, ax);
  return hulls_intersect_3d(seg, -1, t, -1);
}

bool triangles_intersect(const Triangle3& a, const Triangle3& b) {
  if (boxes_disjoint(a, b)) return false;
  // Separating planes first: non-zero signs imply the plane's triangle is non-degenerate.
  const std::array<int, 3> db{sgn3(a[0], a[1], a[2], b[0]), sgn3(a[0], a[1], a[2], b[1]),
                              sgn3(a[0], a[1], a[2], b[2])};
  if ((db[0] > 0 && db[1] > 0 && db[2] > 0) || (db[0] < 0 && db[1] < 0 && db[2] < 0)) return false;
  const std::array<int, 3> da{sgn3(b[0], b[1], b[2], a[0]), sgn3(b[0], b[1], b[2], a[1]),
                              sgn3(b[0], b[1], b[2], a[2])};
  if ((da[0] > 0 && da[1] > 0 && da[2] > 0) || (da[0] < 0 && da[1] < 0 && da[2] < 0)) return false;
  const int a_axis = proper_axis(a[0], a[1], a[2]);
  const int b_axis = proper_axis(b[0], b[1], b[2]);
  if (a_axis < 0 || b_axis < 0) return hulls_intersect_3d(a, a_axis, b, b_axis);
  if (db[0] == 0 && db[1] == 0 && db[2] == 0) {
    return hulls_intersect_2d(project3(a, a_axis), project3(b, a_axis));
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t j = (i + 1) % 3;
    if (segment_triangle_signs(a[i], a[j], da[i], da[j], b, b_axis)) return true;
    if (segment_triangle_signs(b[i], b[j], db[i], db[j], a, a_axis)) return true;
  }
  return false;
}

bool adjacent_triangles_intersect(const Triangle3& a, const Triangle3& b, int shared) {
  if (shared >= 3) return true;
  if (shared == 2) {
    const Vec3& u = a[0];
    const Vec3& v = a[1];
    if (orient3d(u, v, a[2], b[2]) != 0.0) return false;
    const int a_axis = proper_axis(a[0], a[1], a[2]);
    const int b_axis = proper_axis(b[0], b[1], b[2]);
    int ax = a_axis >= 0 ? a_axis : b_axis;
    if (ax >= 0) {
      return sign_of(orient2d_projected(u, v, a[2], ax)) * sign_of(orient2d_projected(u, v, b[2], ax)) > 0;
    }
    // Both degenerate along the line uv: overlap beyond [u, v] on the same side.
    const Vec3 d = (v - u).cwiseAbs();
    const int m = d.x() >= d.y() ? (d.x() >= d.z() ? 0 : 2) : (d.y() >= d.z() ? 1 : 2);
    const double lo = std::min(u[m], v[m]);
    const double hi = std::max(u[m], v[m]);
    return (a[2][m] < lo && b[2][m] < lo) || (a[2][m] > hi && b[2][m] > hi);
  }
  if (shared == 1) {
    const Vec3& v = a[0];
    // If both free corners of one triangle lie strictly on one side of the other's plane,
    // that triangle meets the plane only at v: nothing else can be shared. (Non-zero signs
    // also prove the plane's triangle non-degenerate.)
    if (sgn3(b[0], b[1], b[2], a[1]) * sgn3(b[0], b[1], b[2], a[2]) > 0) return false;
    if (sgn3(a[0], a[1], a[2], b[1]) * sgn3(a[0], a[1], a[2], b[2]) > 0) return false;
    const int a_axis = proper_axis(a[0], a[1], a[2]);
    const int b_axis = proper_axis(b[0], b[1], b[2]);
    if (a_axis >= 0) {  // opposite edge of a against b (it cannot contain v)
      if (b_axis >= 0 ? segment_triangle_proper(a[1], a[2], b, b_axis)
                      : segment_intersects_triangle(a[1], a[2], b)) {
        return true;
      }
    }
    if (b_axis >= 0) {
      if (a_axis >= 0 ? segment_triangle_proper(b[1], b[2], a, a_axis)
                      : segment_intersects_triangle(b[1], b[2], a)) {
        return true;
      }
    }
    return in_tangent_cone(v, a[1], b[1], b[2], b_axis) ||
           in_tangent_cone(v, a[2], b[1], b[2], b_axis) ||
           in_tangent_cone(v, b[1], a[1], a[2], a_axis) ||
           in_tangent_cone(v, b[2], a[1], a[2], a_axis);
  }
  return triangles_intersect(a, b);
}

}  // namespace ido::geometry

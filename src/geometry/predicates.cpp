// SPDX-License-Identifier: Apache-2.0
// Exact-sign orientation predicates. The floating-point filter and the exact fallback through
// expansion arithmetic follow the idea of J. R. Shewchuk, "Adaptive Precision Floating-Point
// Arithmetic and Fast Robust Geometric Predicates", Discrete Comput. Geom. 18 (1997). The
// code is written for this project: a non-adaptive exact stage built only from the
// error-free transformations two_sum / two_product (the latter through fma) and
// "grow expansion", with zero elimination.
#include "ido/geometry/predicates.h"

#include <array>
#include <cmath>
#include <cstdlib>

namespace ido::geometry {
namespace {

constexpr double kEpsilon = 0x1p-53;  // unit roundoff of double
// Forward error bounds of the plain floating-point evaluations below (slightly above the
// (3 + 16ε)ε and (7 + 56ε)ε bounds derived in Shewchuk 1997, section 4).
constexpr double kOrient2dBound = 4.0 * kEpsilon;
constexpr double kOrient3dBound = 8.0 * kEpsilon;

/// A floating-point expansion: the exact value is the sum of the components, stored
/// non-overlapping and in increasing magnitude, without zeros. Capacity covers the orient3d
/// determinant (at most 192 components).
struct Expansion {
  static constexpr int kCapacity = 256;
  std::array<double, kCapacity> c{};
  int n = 0;
};

inline void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a;
  const double av = s - bv;
  e = (a - av) + (b - bv);
}

inline void two_product(double a, double b, double& p, double& e) {
  p = a * b;
  e = std::fma(a, b, -p);
}

/// e ← e + b, exactly (grow-expansion), dropping zero components.
void grow(Expansion& e, double b) {
  if (b == 0.0) return;
  double q = b;
  int out = 0;
  for (int i = 0; i < e.n; ++i) {
    double s = 0.0;
    double h = 0.0;
    two_sum(q, e.c[static_cast<std::size_t>(i)], s, h);
    if (h != 0.0) e.c[static_cast<std::size_t>(out++)] = h;
    q = s;
  }
  if (q != 0.0) e.c[static_cast<std::size_t>(out++)] = q;
  e.n = out;
}

Expansion from_difference(double a, double b) {
  Expansion e;
  double s = 0.0;
  double err = 0.0;
  two_sum(a, -b, s, err);
  grow(e, err);
  grow(e, s);
  return e;
}

Expansion sum(const Expansion& a, const Expansion& b) {
  Expansion r = a;
  for (int i = 0; i < b.n; ++i) grow(r, b.c[static_cast<std::size_t>(i)]);
  return r;
}

Expansion negate(Expansion a) {
  for (int i = 0; i < a.n; ++i) a.c[static_cast<std::size_t>(i)] = -a.c[static_cast<std::size_t>(i)];
  return a;
}

Expansion product(const Expansion& a, const Expansion& b) {
  Expansion r;
  for (int j = 0; j < b.n; ++j) {
    for (int i = 0; i < a.n; ++i) {
      double p = 0.0;
      double err = 0.0;
      two_product(a.c[static_cast<std::size_t>(i)], b.c[static_cast<std::size_t>(j)], p, err);
      grow(r, err);
      grow(r, p);
    }
  }
  return r;
}

/// A value with the exact sign of the expansion: its largest component.
double leading(const Expansion& e) { return e.n == 0 ? 0.0 : e.c[static_cast<std::size_t>(e.n - 1)]; }

double orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
  const Expansion bax = from_difference(bx, ax);
  const Expansion bay = from_difference(by, ay);
  const Expansion cax = from_difference(cx, ax);
  const Expansion cay = from_difference(cy, ay);
  return leading(sum(product(bax, cay), negate(product(bay, cax))));
}

double orient2d_raw(double ax, double ay, double bx, double by, double cx, double cy) {
  const double left = (bx - ax) * (cy - ay);
  const double right = (by - ay) * (cx - ax);
  const double det = left - right;
  const double bound = kOrient2dBound * (std::abs(left) + std::abs(right));
  if (det > bound || -det > bound) return det;
  return orient2d_exact(ax, ay, bx, by, cx, cy);
}

}  // namespace

double orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  return orient2d_raw(a.x(), a.y(), b.x(), b.y(), c.x(), c.y());
}

double orient2d_projected(const Vec3& a, const Vec3& b, const Vec3& c, int drop_axis) {
  const int i = (drop_axis + 1) % 3;
  const int j = (drop_axis + 2) % 3;
  return orient2d_raw(a[i], a[j], b[i], b[j], c[i], c[j]);
}

bool collinear3d(const Vec3& a, const Vec3& b, const Vec3& c) {
  return orient2d_projected(a, b, c, 0) == 0.0 && orient2d_projected(a, b, c, 1) == 0.0 &&
         orient2d_projected(a, b, c, 2) == 0.0;
}

double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double bax = b.x() - a.x(), bay = b.y() - a.y(), baz = b.z() - a.z();
  const double cax = c.x() - a.x(), cay = c.y() - a.y(), caz = c.z() - a.z();
  const double dax = d.x() - a.x(), day = d.y() - a.y(), daz = d.z() - a.z();
  const double m1 = cay * daz, m2 = caz * day;
  const double m3 = caz * dax, m4 = cax * daz;
  const double m5 = cax * day, m6 = cay * dax;
  const double det = bax * (m1 - m2) + bay * (m3 - m4) + baz * (m5 - m6);
  const double permanent = std::abs(bax) * (std::abs(m1) + std::abs(m2)) +
                           std::abs(bay) * (std::abs(m3) + std::abs(m4)) +
                           std::abs(baz) * (std::abs(m5) + std::abs(m6));
  const double bound = kOrient3dBound * permanent;
  if (det > bound || -det > bound) return det;

  // Exact: every difference is a two-component expansion, every product exact.
  const Expansion ebx = from_difference(b.x(), a.x()), eby = from_difference(b.y(), a.y()),
                  ebz = from_difference(b.z(), a.z());
  const Expansion ecx = from_difference(c.x(), a.x()), ecy = from_difference(c.y(), a.y()),
                  ecz = from_difference(c.z(), a.z());
  const Expansion edx = from_difference(d.x(), a.x()), edy = from_difference(d.y(), a.y()),
                  edz = from_difference(d.z(), a.z());
  const Expansion t1 = product(ebx, sum(product(ecy, edz), negate(product(ecz, edy))));
  const Expansion t2 = product(eby, sum(product(ecz, edx), negate(product(ecx, edz))));
  const Expansion t3 = product(ebz, sum(product(ecx, edy), negate(product(ecy, edx))));
  return leading(sum(sum(t1, t2), t3));
}

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/core/math.h"

namespace ido::geometry {

/// Orientation of four points in space with an exact sign.
///
/// Returns a value whose SIGN is exactly that of det[b − a; c − a; d − a] evaluated in real
/// arithmetic on the given doubles (the magnitude is only an approximation of that
/// determinant). Positive when d lies on the side of the plane (a, b, c) into which
/// (b − a) × (c − a) points, i.e. when a, b, c appear counter-clockwise seen from d; the value
/// approximates 6 × tet_signed_volume(a, b, c, d), so a positively oriented TetMesh
/// tetrahedron has orient3d > 0. Zero exactly when the four points are coplanar.
///
/// Algorithm: a floating-point evaluation with a forward error bound, and, when the bound
/// cannot certify the sign, an exact evaluation with floating-point expansion arithmetic
/// (the idea of Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast robust
/// geometric predicates"; the implementation is this project's own and is not adaptive in
/// stages: it goes straight to the exact expansion). Inputs must be finite and their
/// products must not overflow or underflow (any coordinates in ±1e100 with spacing above
/// 1e-100 are safe).
[[nodiscard]] double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Orientation of three points in the plane with an exact sign: the sign of
/// (b − a) × (c − a) = (b−a).x·(c−a).y − (b−a).y·(c−a).x. Positive when a, b, c turn
/// counter-clockwise, zero exactly when collinear. Same filter and exact fallback as
/// orient3d.
[[nodiscard]] double orient2d(const Vec2& a, const Vec2& b, const Vec2& c);

/// orient2d of the projections of a, b, c onto the plane that drops coordinate
/// @p drop_axis (0, 1 or 2); the two kept coordinates keep their cyclic order
/// (drop x → (y, z), drop y → (z, x), drop z → (x, y)), so the result has the sign of the
/// @p drop_axis component of (b − a) × (c − a).
[[nodiscard]] double orient2d_projected(const Vec3& a, const Vec3& b, const Vec3& c,
                                        int drop_axis);

/// True when the three points are exactly collinear (including coincident points).
[[nodiscard]] bool collinear3d(const Vec3& a, const Vec3& b, const Vec3& c);

/// Returns the sign (−1, 0, +1) of a value.
[[nodiscard]] inline int sign_of(double v) { return (v > 0.0) - (v < 0.0); }

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>

#include "ido/core/math.h"

namespace ido::geometry {

/// The three corners of a triangle (mm).
using Triangle3 = std::array<Vec3, 3>;

/// Exact intersection test of two closed triangles: true when they share at least one point
/// (touching at a vertex or along an edge counts; coplanar overlap counts). Decided with the
/// exact-sign predicates of predicates.h only, so the answer is exact for the given doubles.
/// Degenerate triangles (collinear or coincident corners) are handled as the segment or
/// point they span.
///
/// Method: separating-plane rejection with orient3d, then for non-coplanar triangles the
/// fact that two triangles meet iff an edge of one meets the other (each edge test: the
/// segment straddles the plane, and the line passes inside all three edges by orient3d
/// signs); coplanar configurations are projected to the coordinate plane on which the
/// projection is injective and tested with orient2d (edge–edge crossings and containment).
[[nodiscard]] bool triangles_intersect(const Triangle3& t1, const Triangle3& t2);

/// Exact test whether the closed segment [p, q] meets the closed triangle @p t (same rules).
[[nodiscard]] bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Triangle3& t);

/// Exact test for two triangles of one mesh that share exactly the vertices listed: whether
/// they meet anywhere other than the shared element. @p shared is 1 or 2: the first @p shared
/// corners of t1 and t2 are the same points, in the same order (t1[0] = t2[0], and
/// t1[1] = t2[1] when shared = 2). Non-coplanar triangles sharing an edge meet only along it;
/// coplanar ones overlap when their third corners lie on the same side of the edge (a fold).
/// Triangles sharing a vertex meet elsewhere when the opposite edge of one meets the other,
/// or when an edge leaving the shared vertex runs into the other triangle.
[[nodiscard]] bool adjacent_triangles_intersect(const Triangle3& t1, const Triangle3& t2,
                                                int shared);

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// A geodesic sphere: an icosahedron whose triangles are split into 4 @p subdivisions times,
/// new vertices pushed onto the sphere. Closed, manifold, counter-clockwise seen from outside;
/// 20·4ˢ triangles, 10·4ˢ + 2 vertices, all at exactly-computed distance radius_mm (to
/// rounding) from centre_mm. @throws ido::InvalidInput if radius_mm ≤ 0 or not finite, or
/// subdivisions is outside [0, 10].
[[nodiscard]] TriangleMesh icosphere(const Vec3& centre_mm, double radius_mm, int subdivisions);

/// The closed surface of the box [min_mm, max_mm]: 8 vertices, 12 triangles, outward
/// counter-clockwise. @throws ido::InvalidInput unless min < max in every coordinate.
[[nodiscard]] TriangleMesh box_surface(const Vec3& min_mm, const Vec3& max_mm);

/// A torus around the z axis through @p centre_mm: tube centre-line radius @p major_mm,
/// tube radius @p minor_mm, @p nu segments around the z axis and @p nv around the tube.
/// Closed, manifold, genus 1, outward counter-clockwise; nu·nv vertices, 2·nu·nv triangles.
/// @throws ido::InvalidInput unless 0 < minor_mm < major_mm and nu, nv ≥ 3.
[[nodiscard]] TriangleMesh torus_surface(const Vec3& centre_mm, double major_mm, double minor_mm,
                                         int nu, int nv);

/// A closed cylinder from @p base_mm to @p top_mm of radius @p radius_mm: @p segments
/// vertices around each rim, @p rings ≥ 1 rows of side quads, and a fan-triangulated cap at
/// each end around a centre vertex. Outward counter-clockwise.
/// @throws ido::InvalidInput if radius ≤ 0, the ends coincide, segments < 3 or rings < 1.
[[nodiscard]] TriangleMesh uv_cylinder(const Vec3& base_mm, const Vec3& top_mm, double radius_mm,
                                       int segments, int rings = 1);

/// The box [min_mm, max_mm] filled with positively oriented tetrahedra: n × n × n cubes, each
/// split into 6 tetrahedra around its main diagonal (Kuhn subdivision), which match across
/// cube faces. (n+1)³ vertices, 6n³ tetrahedra. @throws ido::InvalidInput unless
/// min < max and 1 ≤ n ≤ 200.
[[nodiscard]] TetMesh box_tets(const Vec3& min_mm, const Vec3& max_mm, int n);

}  // namespace ido::geometry

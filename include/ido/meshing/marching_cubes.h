// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>

#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"

/// Topologically consistent marching cubes.
///
/// Conventions (both extractors):
/// - A voxel is *inside* when its value is strictly below the iso level; a value equal to
///   the level, or NaN, counts as outside. Vertices lie on grid edges whose two voxels
///   differ, by linear interpolation clamped to [0.001, 0.999] of the edge, so no two
///   vertices coincide and no triangle is degenerate even when values equal the level.
/// - The grid is conceptually padded by one layer of outside voxels (think +∞) on every
///   side: a surface that reaches the border is capped there, with the cap's vertices
///   half a voxel beyond the last voxel centre. The output is therefore always closed.
/// - Ambiguous cube faces are resolved by one fixed rule, "inside corners are separated"
///   (inside is 6-connected, outside 18-connected), which depends only on the face's four
///   corners; neighbouring cubes agree, so the surface has no cracks. The case table is
///   generated at start-up by walking the face segments of each of the 256 cases into
///   closed polygons (the approach of Bloomenthal, "An implicit surface polygonizer",
///   Graphics Gems IV, 1994), and each polygon is triangulated without a diagonal lying
///   in a cube face. Together with vertices welded by grid-edge id this makes the output a
///   closed, oriented 2-manifold by construction (each mesh edge has exactly two
///   triangles, each vertex a single fan).
/// - Triangles are counter-clockwise seen from outside (normals point towards increasing
///   values), also for direction matrices with negative determinant.
/// - Output is deterministic and identical with and without threads: vertices are ordered
///   by their grid edge (k, j, i, axis), triangles by their cube.
namespace ido::meshing {

/// Tunables of marching_cubes.
struct MarchingCubesOptions {
  float iso_value = 0.0f;  ///< level to extract, in the volume's own units
  bool threaded = true;    ///< run the passes with oneTBB
};

/// Extracts the iso-surface of @p field (values below iso_value inside) as a closed,
/// 2-manifold, outward-oriented triangle mesh in world coordinates (mm).
/// An empty field or a field with no inside voxel gives an empty mesh.
[[nodiscard]] geometry::TriangleMesh marching_cubes(const image::Volume<float>& field,
                                                    const MarchingCubesOptions& options = {});

/// Surface of a binary mask: voxels ≠ 0 are inside (iso 0.5 on the mask seen as a float
/// field, every vertex at an edge midpoint). Closed, 2-manifold, outward-oriented.
[[nodiscard]] geometry::TriangleMesh marching_cubes_mask(const image::Volume<std::uint8_t>& mask,
                                                         bool threaded = true);

/// Number of triangles marching cubes emits per cube configuration (bit c of @p cube_case
/// set = corner c inside, corner c at offset (c&1, (c>>1)&1, (c>>2)&1)). For tests and
/// diagnostics.
[[nodiscard]] int marching_cubes_case_triangle_count(int cube_case);

}  // namespace ido::meshing

// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"

namespace ido::segment {

/// Pairs (i < j) of triangles of @p mesh that intersect other than along the edge or at the
/// vertex they share. Broad phase: a uniform grid over triangle boxes; narrow phase: edge
/// against triangle crossings with orientation determinants (floating point, so two
/// triangles that only graze within ~1e-12 of their size may go either way). Triangles
/// sharing an edge count as intersecting only when folded flat onto each other; triangles
/// sharing a vertex when the edge opposite the shared vertex of one crosses the other.
/// Exactly coplanar overlapping triangles that share nothing are not reported. Written by
/// hand for the balloon; geometry::self_intersections is the exact general-purpose check.
[[nodiscard]] std::vector<std::pair<std::int32_t, std::int32_t>> find_self_intersections(
    const geometry::TriangleMesh& mesh, bool threaded = true);

/// Combinatorial and metric facts about a triangle surface.
struct SurfaceCheck {
  bool closed = false;           ///< every edge has exactly two triangles
  bool edge_manifold = false;    ///< no edge has more than two triangles
  bool vertex_manifold = false;  ///< every vertex's triangles form one fan
  bool oriented = false;         ///< each edge is used once in each direction
  std::int64_t vertices = 0, edges = 0, triangles = 0;
  std::int64_t euler_characteristic = 0;  ///< V − E + F
  std::int64_t components = 0;            ///< connected components (by shared vertices)
  double volume_mm3 = 0;                  ///< signed enclosed volume (divergence theorem)
  double area_mm2 = 0;                    ///< total triangle area
};

/// Checks @p mesh (unreferenced vertices count in V).
[[nodiscard]] SurfaceCheck check_surface(const geometry::TriangleMesh& mesh);

/// The zero level of @p field (values < 0 inside) as a closed, 2-manifold, outward-oriented
/// triangle mesh in world coordinates: marching tetrahedra over the Kuhn (Freudenthal)
/// subdivision of each voxel cell into six tetrahedra, which is consistent between
/// neighbouring cells, so the piecewise-linear level set is a closed 2-manifold by
/// construction (no ambiguous cases). Values ≥ 0 count as outside; the outermost layer of
/// the grid is treated as outside so the surface closes. Vertices are kept at least 1e-3 of
/// an edge from grid points, so no triangle collapses to a point. Written by hand.
[[nodiscard]] geometry::TriangleMesh extract_zero_level(const image::Volume<float>& field,
                                                        bool threaded = true);

/// Tunables of repair_topology().
struct TopologyRepairOptions {
  double grid_spacing_mm = 1.0;  ///< spacing of the signed distance grid (isotropic), > 0
  double target_edge_mm = 1.0;   ///< edge length of the remeshed result, > 0
  /// Components whose enclosed volume is below this (mm³) are dropped (specks left where
  /// the winding number is ambiguous).
  double min_component_volume_mm3 = 0.0;
  bool remesh = true;  ///< remesh the extracted level to target_edge_mm
  bool threaded = true;
};

/// Rebuilds a self-intersecting closed surface as a non-self-intersecting one with the
/// topology of the region it encloses (the paper's repair step): a signed distance map on an
/// isotropic world-aligned grid around the surface, distances from the triangles not listed
/// in @p intersecting_pairs, inside by generalised winding number > 0.5 from all triangles;
/// its zero level by extract_zero_level(); optionally remeshed. Overlapping parts merge, so
/// a balloon that met itself around a hole becomes a torus.
/// @throws ido::InvalidInput on an empty mesh or non-positive spacings.
[[nodiscard]] geometry::TriangleMesh repair_topology(
    const geometry::TriangleMesh& mesh,
    const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const TopologyRepairOptions& options);

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"

namespace ido::segment {

/// Tunables of repair_topology().
struct TopologyRepairOptions {
  double grid_spacing_mm = 1.0;  ///< spacing of the signed distance grid (isotropic), > 0
  double target_edge_mm = 1.0;   ///< edge length of the remeshed result, > 0
  /// Components whose enclosed volume is below this (mm³) are dropped (specks left where
  /// the winding number is ambiguous).
  double min_component_volume_mm3 = 0.0;
  /// Points the result must hold (the balloon's seeds): when some component encloses one of
  /// them, the components that enclose none are dropped — pieces the repair pinched off the
  /// balloon. Empty = keep every component (above the volume floor).
  std::vector<Vec3> keep_points_mm;
  bool remesh = true;  ///< remesh the extracted level to target_edge_mm
  bool threaded = true;
};

/// The components of the closed surface @p mesh worth keeping: those enclosing at least
/// @p min_volume_mm3 (signed volume, so inner cavities go too), and, when some such component
/// encloses a point of @p keep_points_mm (winding number > ½), only the components enclosing
/// a point. Vertices are renumbered in order of first use; unused ones go.
[[nodiscard]] geometry::TriangleMesh keep_components(const geometry::TriangleMesh& mesh, double min_volume_mm3,
                                                     const std::vector<Vec3>& keep_points_mm = {});

/// Rebuilds a self-intersecting closed surface as a non-self-intersecting one with the
/// topology of the region it encloses (the paper's repair step): a signed distance map on an
/// isotropic world-aligned grid around the surface, distances from the triangles not listed
/// in @p intersecting_pairs, inside by generalised winding number > 0.5 from all triangles;
/// its zero level by meshing::marching_cubes() (topologically consistent, closed and
/// 2-manifold by construction); optionally remeshed. Overlapping parts merge, so a balloon
/// that met itself around a hole becomes a torus. The pairs come from
/// geometry::self_intersections() (exact); check the result with geometry::check_mesh().
/// @throws ido::InvalidInput on an empty mesh or non-positive spacings.
[[nodiscard]] geometry::TriangleMesh repair_topology(
    const geometry::TriangleMesh& mesh,
    const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const TopologyRepairOptions& options);

/// Tunables of untangle_folds().
struct FoldRepairOptions {
  int rings = 2;   ///< a pair is a fold when its triangles lie at most this many edges apart
  int rounds = 6;  ///< smoothing rounds, the region growing by one ring after each
  bool threaded = true;  ///< oneTBB for the intersection test of the region
};

/// Local repair of folds: self-intersections between triangles at most options.rings edges
/// apart on the surface (a vertex pushed through its neighbours, as where a deforming front
/// crumples at a crease), not two distant sheets meeting. When every pair of
/// @p intersecting_pairs is such a fold, the corners of the intersecting triangles and their
/// one-ring are moved halfway to their neighbours' centroid (two Laplacian passes per round,
/// which flattens a fold), the region growing by a ring after each round, until none of the
/// region's triangles meets any other triangle of the mesh (exact test,
/// geometry::self_intersections_touching); vertices flagged in
/// @p fixed (empty or one per vertex) and every vertex outside the region keep their
/// positions bit for bit, and the connectivity is unchanged. Returns the moved region's
/// vertices; std::nullopt, with @p mesh unchanged, when a pair is not a fold or the fold did
/// not open within options.rounds (then rebuild with repair_topology()). The pairs must be all
/// those of geometry::self_intersections(mesh) for the result to be free of intersections.
/// Preconditions: a closed, manifold mesh with valid indices.
[[nodiscard]] std::optional<std::vector<std::int32_t>> untangle_folds(
    geometry::TriangleMesh& mesh, const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const std::vector<std::uint8_t>& fixed, const FoldRepairOptions& options = {});

}  // namespace ido::segment

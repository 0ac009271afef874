// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"

namespace ido::meshing {

/// How signed_distance() decides inside from outside.
enum class SignMethod {
  /// Crossing parity when the surface is closed and consistently oriented (every directed
  /// edge appears once and its reverse exactly once; self-intersections allowed), the
  /// generalised winding number otherwise.
  automatic,
  /// Always the hierarchical generalised winding number (geometry::WindingNumber).
  winding_number,
};

/// Tunables of signed_distance().
struct SignedDistanceOptions {
  /// Half-width (mm) of the band around the surface where distances are exact; outside it
  /// the field is ±band_mm. 0 chooses twice the grid's largest spacing (the least that keeps
  /// the sign of every grid point correct, see signed_distance()).
  double band_mm = 0.0;
  /// Triangles that count for the distance (one flag per triangle, 1 = use); empty = all.
  /// The sign always uses every triangle. The balloon's topology repair excludes the
  /// triangles that intersect others.
  std::vector<std::uint8_t> distance_triangles;
  /// Accuracy of the hierarchical winding number (geometry::WindingNumberOptions::beta): a
  /// cluster is replaced by its far-field expansion when the query is farther than
  /// beta × the cluster's radius (Barill et al. 2018 use 2).
  double winding_beta = 2.0;
  SignMethod sign = SignMethod::automatic;  ///< see SignMethod
  bool threaded = true;  ///< use oneTBB
};

/// Signed distance (mm) from a closed triangle surface, sampled on the grid of @p grid
/// (its size, spacing, origin and direction; its voxel values are ignored): negative inside,
/// where inside means winding number > 0.5, so self-intersecting surfaces (overlaps count
/// twice) and slightly open ones still get a sensible inside. On a closed, consistently
/// oriented surface the winding number is an integer off the surface and is computed exactly
/// by counting signed crossings along each grid row (the exact orient2d sign with a
/// symbolic perturbation of the row, so rows through an edge or a vertex count once); a
/// grid point lying exactly on the surface takes the side just before it along the row.
/// Other surfaces use the generalised winding number (geometry::WindingNumber, see
/// options.sign). Within
/// options.band_mm of the surface the magnitude is the exact Euclidean distance to the
/// nearest counted triangle (an inside point lying on a triangle gets −FLT_MIN, never 0:
/// inside values are strictly negative); beyond it, the value is ±band_mm. The generalised
/// winding number is evaluated only at grid points within about the grid's largest spacing
/// of the surface (or of an uncounted triangle); every other grid point takes the sign of one
/// evaluation per connected component of such points, which is exact because a grid step from a point
/// farther than a spacing from every triangle cannot cross the surface (it needs band_mm
/// above the largest spacing). Runs in O(triangles × band voxels + grid voxels).
/// A marching-cubes extraction of the zero level reads only values at the ends of grid edges
/// the level crosses, which lie within one spacing of a counted triangle when the crossing
/// is theirs: a band a little above the largest spacing gives the same level.
/// @throws ido::InvalidInput if the grid is empty, the mesh has no triangles, an index is
/// out of range, or distance_triangles has the wrong size.
/// The isotropic, world-aligned grid a surface's signed distance is sampled on (its voxel
/// values are zero): spacing @p spacing_mm, covering the vertices' bounding box with
/// @p margin_cells whole cells beyond it on every side. The balloon's topology repair and its
/// edge stage's reach use it. @throws ido::InvalidInput on a mesh without vertices, a
/// non-positive spacing or a negative margin.
[[nodiscard]] image::Volume<float> distance_grid(const geometry::TriangleMesh& surface, double spacing_mm,
                                                 int margin_cells);

[[nodiscard]] image::Volume<float> signed_distance(const geometry::TriangleMesh& surface,
                                                   const image::Volume<float>& grid,
                                                   const SignedDistanceOptions& options = {});

/// Closest point (mm) to @p p on the triangle (a, b, c) (Ericson, Real-Time Collision
/// Detection, 2005, §5.1.5).
[[nodiscard]] Vec3 closest_point_on_triangle_mm(const Vec3& p, const Vec3& a, const Vec3& b,
                                                const Vec3& c);

}  // namespace ido::meshing

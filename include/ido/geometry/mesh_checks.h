// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Everything check_mesh() measures on a triangle mesh.
///
/// Counting conventions: `vertices` counts vertices used by at least one triangle (unused
/// vertices are ignored by every check); `edges` counts unique undirected edges.
struct MeshCheckReport {
  std::size_t vertices = 0;   ///< referenced vertices
  std::size_t edges = 0;      ///< unique undirected edges
  std::size_t triangles = 0;  ///< triangles
  /// No boundary edge (no edge used by exactly one triangle) and at least one triangle.
  bool closed = false;
  /// Every edge is used by at most two triangles.
  bool edge_manifold = false;
  /// Around every vertex the incident triangles form a single fan (connected through edges
  /// at that vertex), so the neighbourhood is a disc or a half-disc.
  bool vertex_manifold = false;
  /// The mesh is edge-manifold and every edge used by two triangles is traversed once in
  /// each direction (neighbouring triangles agree on the orientation).
  bool oriented = false;
  /// V − E + F with the counts above.
  std::int64_t euler_characteristic = 0;
  /// Connected components (triangles sharing a vertex are connected).
  int components = 0;
  /// Sum over components of (2 − χᵢ) / 2; only when the mesh is closed, edge- and
  /// vertex-manifold and oriented (a closed orientable surface).
  std::optional<int> genus;
  std::size_t boundary_edges = 0;         ///< edges used by exactly one triangle
  std::size_t non_manifold_edges = 0;     ///< edges used by three or more triangles
  std::size_t non_manifold_vertices = 0;  ///< vertices whose incident triangles form 2+ fans
  /// Triangles with exactly collinear corners (including repeated indices), decided with
  /// exact predicates.
  std::size_t degenerate_triangles = 0;
  double area_mm2 = 0.0;           ///< total surface area
  double signed_volume_mm3 = 0.0;  ///< see signed_volume()
  Vec3 bounds_min = Vec3::Zero();  ///< lower corner of the referenced vertices' box (mm)
  Vec3 bounds_max = Vec3::Zero();  ///< upper corner (mm)
};

/// Runs every check of MeshCheckReport in O(T log T). Self-intersections are not part of it
/// (see self_intersection.h). @throws ido::InvalidInput for an index out of range or a
/// non-finite coordinate.
[[nodiscard]] MeshCheckReport check_mesh(const TriangleMesh& mesh);

/// True when no edge is used by exactly one triangle and there is at least one triangle.
[[nodiscard]] bool is_closed(const TriangleMesh& mesh);

/// V − E + F counting referenced vertices and unique edges.
[[nodiscard]] std::int64_t euler_characteristic(const TriangleMesh& mesh);

/// Signed enclosed volume (mm³) by the divergence theorem: Σ (a · (b × c)) / 6 over the
/// triangles, evaluated relative to the centre of the bounding box for accuracy. Positive for
/// a closed surface whose triangles are counter-clockwise seen from outside; meaningful only
/// for closed meshes.
[[nodiscard]] double signed_volume(const TriangleMesh& mesh);

/// Total area of the triangles (mm²).
[[nodiscard]] double surface_area(const TriangleMesh& mesh);

/// True when the corners of the triangle are exactly collinear (or repeated).
[[nodiscard]] bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace ido::geometry

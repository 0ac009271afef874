// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstddef>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Signed volume (mm³) of the tetrahedron (a, b, c, d): (b − a) · ((c − a) × (d − a)) / 6.
/// Positive for the TetMesh orientation convention; its sign agrees with orient3d(a, b, c, d)
/// whenever the floating-point value is not within rounding of zero (use orient3d for an
/// exact sign).
[[nodiscard]] double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c,
                                       const Vec3& d);

/// The six interior dihedral angles (degrees, in [0, 180]) at the edges, in the order
/// ab, ac, ad, bc, bd, cd. The angle at edge (p, q) is the angle between the two faces that
/// share it, measured inside the tetrahedron; orientation does not matter. A regular
/// tetrahedron gives acos(1/3) = 70.5288° everywhere. An edge of zero length, or a face
/// collapsed onto that edge, gives 0 for that edge.
[[nodiscard]] std::array<double, 6> dihedral_angles_deg(const Vec3& a, const Vec3& b,
                                                        const Vec3& c, const Vec3& d);

/// Mean ratio quality η = 12 (3|V|)^{2/3} / Σ lᵢⱼ² (Liu & Joe 1994), carrying the sign of
/// the volume V: 1 for a regular tetrahedron, 0 for a degenerate one, negative for an
/// inverted one, |η| ≤ 1 always. Scale invariant. 0 when all points coincide.
[[nodiscard]] double mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Everything check_tet_mesh() measures on a tetrahedral mesh.
struct TetMeshReport {
  std::size_t vertices = 0;    ///< vertex array size
  std::size_t tets = 0;        ///< tetrahedra
  std::size_t inverted = 0;    ///< tetrahedra with exactly negative orientation (orient3d < 0)
  std::size_t degenerate = 0;  ///< tetrahedra with exactly coplanar corners (orient3d = 0)
  double volume_mm3 = 0.0;     ///< sum of signed volumes
  double min_dihedral_deg = 0.0;   ///< smallest dihedral angle over all tetrahedra
  double max_dihedral_deg = 0.0;   ///< largest dihedral angle over all tetrahedra
  double min_mean_ratio = 0.0;     ///< smallest (signed) mean ratio
  double mean_mean_ratio = 0.0;    ///< average (signed) mean ratio
  std::size_t boundary_faces = 0;  ///< faces used by exactly one tetrahedron
  /// The boundary surface (tet_boundary) is closed, i.e. has no boundary edge.
  bool boundary_closed = false;
  /// Every face is shared by at most two tetrahedra and the boundary surface is edge- and
  /// vertex-manifold.
  bool boundary_manifold = false;
};

/// Measures orientation, volume, quality and boundary of @p mesh. All-zero report for an
/// empty mesh. @throws ido::InvalidInput for an index out of range or a non-finite coordinate.
[[nodiscard]] TetMeshReport check_tet_mesh(const TetMesh& mesh);

/// The faces used by exactly one tetrahedron, oriented outward for positively oriented
/// tetrahedra (counter-clockwise seen from outside). The returned mesh keeps the tet mesh's
/// whole vertex array and indices (so boundary vertex i is tet vertex i; unused vertices
/// remain — call remove_unused_vertices to compact); point fields are copied, cell fields are
/// not. Faces are ordered by (tetrahedron, local face). @throws ido::InvalidInput for an
/// index out of range.
[[nodiscard]] TriangleMesh tet_boundary(const TetMesh& mesh);

}  // namespace ido::geometry

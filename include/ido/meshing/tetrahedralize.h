// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/core/error.h"
#include "ido/core/progress.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"

namespace ido::meshing {

/// The lattice spacing (edge_mm) is too small for the input: the lattice would have more
/// vertices or cells than the mesher indexes. An InvalidInput of its own type, so a caller can
/// name its own option (the CLI's --edge) without reading the message.
class EdgeTooSmall : public InvalidInput {
 public:
  using InvalidInput::InvalidInput;
};

/// Tunables of tetrahedralize.
struct TetrahedralizeOptions {
  /// Lattice spacing h (mm): the length of the body-centred cubic lattice's axis-parallel
  /// edges (the cube size). 0 = twice the geometric mean of the field's voxel spacing.
  double edge_mm = 0;
  /// Octree-graded lattice: spacing edge_mm near the surface, cubes up to 64 × edge_mm
  /// deeper inside (each level twice the previous), so far fewer tetrahedra for the same
  /// boundary. Same boundary and same dihedral bounds as the uniform lattice (see
  /// kGradedStuffingMinDihedralDeg).
  bool graded = false;
  /// Evaluate the field and fill the lattice in parallel (oneTBB). The output is identical
  /// either way.
  bool threaded = true;
};

/// The warping thresholds of isosurface stuffing (Labelle & Shewchuk 2007, table 1): a
/// lattice vertex is snapped to a cut point on one of its edges when the cut point lies
/// within alpha × (edge length) of it. These values give the paper's proven dihedral-angle
/// bounds for the one-level lattice: every output angle lies in [10.7829°, 164.8266°].
inline constexpr double kStuffingAlphaLong = 0.24999;   ///< for the axis-parallel edges (length h)
inline constexpr double kStuffingAlphaShort = 0.41189;  ///< for the diagonal edges (length h·√3/2)
/// The proven dihedral-angle bounds (degrees) of one-level isosurface stuffing.
inline constexpr double kStuffingMinDihedralDeg = 10.7829;
inline constexpr double kStuffingMaxDihedralDeg = 164.8266;

/// The dihedral-angle bounds (degrees) of graded stuffing (options.graded). The octree is
/// refined until every lattice tetrahedron that stuffing cuts or warps is a body-centred
/// cubic tetrahedron between two finest cubes, treated exactly as by one-level stuffing, so
/// those keep the one-level bounds; every other output tetrahedron is an unchanged tetrahedron
/// of the graded lattice (BCC, bisected BCC, or joining the centres of cubes of two sizes),
/// whose angles lie in [kGradedLatticeMinDihedralDeg, kGradedLatticeMaxDihedralDeg]. The
/// caveat of the one-level bounds on non-distance fields (see tetrahedralize()) applies.
inline constexpr double kGradedStuffingMinDihedralDeg = kStuffingMinDihedralDeg;
inline constexpr double kGradedStuffingMaxDihedralDeg = kStuffingMaxDihedralDeg;
/// The dihedral angles (degrees) of the graded lattice's own tetrahedra range over exactly
/// [30°, 135°] (the tetrahedron joining a cube's centre to the centre of a neighbour twice
/// its size over an inner edge of the big face reaches both).
inline constexpr double kGradedLatticeMinDihedralDeg = 30.0;
inline constexpr double kGradedLatticeMaxDihedralDeg = 135.0;

/// Fills the region where @p signed_distance_mm < 0 with positively oriented tetrahedra by
/// one-level isosurface stuffing on a body-centred cubic lattice (F. Labelle and J. R.
/// Shewchuk, "Isosurface stuffing: fast tetrahedral meshes with good dihedral angles", ACM
/// Transactions on Graphics 26(3), SIGGRAPH 2007): the field is evaluated at the lattice
/// vertices, each lattice edge whose ends have opposite signs gets a cut point at the
/// field's zero (found on the trilinear field), lattice vertices too close to a cut point
/// are warped onto it, and every lattice tetrahedron is replaced by the stencil of its sign
/// pattern, quadrilaterals being split by the paper's rules (fixed by the long edge, or by
/// a parity rule that depends only on the face). A lattice tetrahedron whose four vertices
/// were all warped onto the surface is left out. The paper proves every dihedral angle lies
/// within [kStuffingMinDihedralDeg, kStuffingMaxDihedralDeg]; on smooth fields that is what
/// is measured, but on white-noise fields this implementation was measured down to 10.64°
/// (a configuration with two warped vertices and a cut point exactly at alpha_long), and on
/// a smooth field that is not a distance (0.3 × a bumpy sphere's) down to 10.38°, so the
/// bound is not guaranteed here for arbitrary fields. Boundary vertices lie on the zero level
/// of the (trilinear) field; the boundary is closed.
///
/// With options.graded the lattice is an octree-graded BCC lattice (Labelle & Shewchuk 2007,
/// section 5's construction; our refinement rule instead of their graded thresholds, see
/// kGradedStuffingMinDihedralDeg): finest cubes of size edge_mm wherever stuffing changes the
/// lattice, cubes up to 64 × edge_mm inside and outside, 2:1 balanced across faces and edges,
/// conforming (no hanging vertices); the boundary is built by the same rules as the uniform
/// lattice's.
///
/// The field is read by trilinear interpolation in world space; outside the volume's grid
/// it is intersected with the grid's box, so a region touching the border is closed there.
/// Output vertices are in world coordinates (mm).
/// @param signed_distance_mm signed distance (mm), negative inside; any orientation/spacing.
/// @throws ido::InvalidInput if the field is empty or has fewer than 2 voxels along an axis,
///         or if edge_mm is negative or not finite; EdgeTooSmall if the lattice would
///         exceed 2^31 vertices.
/// @throws ido::Cancelled if @p progress is cancelled.
[[nodiscard]] geometry::TetMesh tetrahedralize(const image::Volume<float>& signed_distance_mm,
                                               const TetrahedralizeOptions& options = {},
                                               Progress* progress = nullptr);

/// Fills the inside of a closed triangle surface (mm) with tetrahedra: its signed distance
/// (meshing::signed_distance; inside = generalised winding number > ½, so small defects are
/// tolerated) is sampled on an axis-aligned grid of spacing h/2 covering the surface's
/// bounds plus 2h, exact within 2h of the surface, then stuffed as tetrahedralize() does.
/// edge_mm = 0 takes h = the surface's mean edge length.
/// @throws ido::InvalidInput for a surface without triangles, an index out of range, a
///         negative or non-finite edge_mm; EdgeTooSmall for a grid that would exceed 2^31
///         voxels; as tetrahedralize() otherwise.
[[nodiscard]] geometry::TetMesh tetrahedralize_surface(const geometry::TriangleMesh& surface,
                                                       const TetrahedralizeOptions& options = {},
                                                       Progress* progress = nullptr);

/// The lattice spacing (mm) tetrahedralize uses for @p field with @p options.
[[nodiscard]] double stuffing_lattice_spacing(const image::Volume<float>& field,
                                              const TetrahedralizeOptions& options = {});

}  // namespace ido::meshing

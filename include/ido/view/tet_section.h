// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/viz/renderer.h"

namespace ido::view {

/// Where a plane cuts a tetrahedral mesh.
struct TetSection {
  /// The section faces (mm): for every tetrahedron with corners on both sides of the plane, the
  /// polygon where the plane cuts it — a triangle, or a quadrilateral as two triangles — facing
  /// along the plane's normal (out of the kept side, where (x − point) · normal ≤ 0).
  geometry::TriangleMesh faces;
  /// The polygons' edges (pairs of points, mm), so the cut tetrahedra can be told apart.
  std::vector<std::array<Vec3, 2>> edges;
  std::size_t cut_tets = 0;  ///< tetrahedra the plane cuts
};

/// The section of @p mesh by @p plane (a real cut through the tetrahedra, not along whole cells).
/// Corners exactly on the plane count as on the kept side. @throws ido::InvalidInput for an
/// index out of range or a zero normal.
[[nodiscard]] TetSection tet_section(const geometry::TetMesh& mesh, const viz::ClipPlane& plane);

/// Counts of the dihedral angles (degrees) of every tetrahedron (6 each) in @p bins equal bins
/// over [0°, 180°]. @throws ido::InvalidInput unless 1 ≤ bins ≤ 3600, or for an index out of range.
[[nodiscard]] std::vector<std::size_t> dihedral_histogram(const geometry::TetMesh& mesh, int bins);

}  // namespace ido::view

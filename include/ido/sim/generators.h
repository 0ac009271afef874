// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"

namespace ido::sim {

/// How a hexahedral cell is split into tetrahedra.
enum class HexSplit {
  Six,    ///< 6 tetrahedra around the main diagonal (Kuhn / Freudenthal): conforming always
  Five,   ///< 5 tetrahedra, alternating by cell parity so that faces match
};

/// An axis-aligned box [origin, origin + size] divided into cells.x × cells.y × cells.z hex
/// cells, each split into tetrahedra, all positively oriented. Vertex (i, j, k) has index
/// i + (cells.x + 1)(j + (cells.y + 1) k). @throws ido::InvalidInput for a cell count < 1
/// or a non-positive size.
[[nodiscard]] geometry::TetMesh make_beam(const Vec3& size_mm, const Vec3i& cells,
                                          const Vec3& origin_mm = Vec3::Zero(),
                                          HexSplit split = HexSplit::Six);

/// A cube of edge @p edge_mm with @p cells per side, centred at @p centre_mm.
[[nodiscard]] geometry::TetMesh make_cube(double edge_mm, int cells,
                                          const Vec3& centre_mm = Vec3::Zero(),
                                          HexSplit split = HexSplit::Six);

/// A voxel-style sphere: the cells of a (2·cells_per_radius)³ grid whose centres lie inside
/// the sphere, split into tetrahedra (a staircase approximation of the ball).
[[nodiscard]] geometry::TetMesh make_sphere(double radius_mm, int cells_per_radius,
                                            const Vec3& centre_mm = Vec3::Zero());

}  // namespace ido::sim

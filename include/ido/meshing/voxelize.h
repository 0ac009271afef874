// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstdint>

#include "ido/geometry/triangle_mesh.h"
#include "ido/image/resample.h"
#include "ido/image/volume.h"

namespace ido::meshing {

/// Tunables of voxelize().
struct VoxelizeOptions {
  bool threaded = true;  ///< rows in parallel (oneTBB)
};

/// Mesh → mask, ido's one inside rule: a voxel is 1 when its centre is inside the closed,
/// oriented surface @p closed_mesh, that is when its winding number, counted by signed
/// crossings along the voxel row, is positive (an inverted pocket, winding ≤ 0, is outside;
/// meshing::signed_distance takes its sign from here). Orientation tests are exact, with a symbolic perturbation, so a centre lying
/// exactly on a triangle edge or vertex is counted once. Every mask ido derives from a surface
/// (`ido segment --mask`, `ido compare --mesh`, the pipeline, calcification) comes from here.
/// @throws ido::InvalidInput for a non-finite vertex or an out-of-range triangle index.
[[nodiscard]] image::Volume<std::uint8_t> voxelize(const geometry::TriangleMesh& closed_mesh,
                                                   const image::GridGeometry& grid,
                                                   const VoxelizeOptions& options = {});

/// voxelize() onto the grid of @p grid_like (any voxel type).
template <class T>
[[nodiscard]] image::Volume<std::uint8_t> voxelize(const geometry::TriangleMesh& closed_mesh,
                                                   const image::Volume<T>& grid_like,
                                                   const VoxelizeOptions& options = {}) {
  return voxelize(closed_mesh, image::GridGeometry::of(grid_like), options);
}

}  // namespace ido::meshing

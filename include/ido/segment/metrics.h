// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>

#include "ido/geometry/triangle_mesh.h"
#include "ido/image/resample.h"
#include "ido/image/volume.h"

/// Accuracy metrics of a segmentation against a ground truth. Definitions: docs/metrics.md.
namespace ido::segment {

/// Voxel neighbourhood used for connected components.
enum class Connectivity {
  Six = 6,          ///< face neighbours (matches marching cubes' inside connectivity)
  TwentySix = 26,   ///< face, edge and corner neighbours
};

/// Scores of a mask against a truth (see docs/metrics.md for the exact definitions).
struct SegmentationScores {
  double dice = 0.0;        ///< 2|A∩B| / (|A|+|B|); 1 when both are empty
  double hd95_mm = 0.0;     ///< max of the two directed 95th-percentile surface distances (mm)
  double assd_mm = 0.0;     ///< average symmetric surface distance (mm)
  double hd_mm = 0.0;       ///< Hausdorff distance between the surface voxel sets (mm)
  double volume_ratio = 0.0;  ///< |A| / |B| (∞ if the truth is empty and the mask is not)
  int components_mask = 0;    ///< 6-connected components of the mask
  int components_truth = 0;   ///< 6-connected components of the truth
  std::size_t voxels_mask = 0;   ///< mask voxels (on the truth's grid)
  std::size_t voxels_truth = 0;  ///< truth voxels
  double volume_mask_mm3 = 0.0;   ///< voxels_mask × voxel volume
  double volume_truth_mm3 = 0.0;  ///< voxels_truth × voxel volume
  bool resampled = false;  ///< the mask was resampled onto the truth's grid
};

/// Compares @p mask with @p truth (voxels ≠ 0 are inside). When the grids differ the mask
/// is resampled onto the truth's grid by nearest neighbour in physical space. Surface
/// distances are spacing-aware: the surface of a mask is its inside voxels with a
/// 6-neighbour outside (or on the grid border); each surface voxel's distance to the other
/// surface is exact (Euclidean distance transform, Felzenszwalb & Huttenlocher 2012), in
/// both directions. When either surface is empty the distances are +∞.
/// @throws ido::InvalidInput if either volume is empty.
[[nodiscard]] SegmentationScores compare_masks(const image::Volume<std::uint8_t>& mask,
                                               const image::Volume<std::uint8_t>& truth);

/// Scores a closed surface against a truth mask: the mesh is rasterised onto the truth's
/// grid, then compare_masks. @throws ido::InvalidInput for an empty truth, a bad mesh, or a
/// surface that is not closed (boundary edges: it has no inside).
[[nodiscard]] SegmentationScores compare_mesh_to_mask(const geometry::TriangleMesh& closed_mesh,
                                                      const image::Volume<std::uint8_t>& truth);

/// Number of connected components of the voxels ≠ 0.
[[nodiscard]] int count_components(const image::Volume<std::uint8_t>& mask,
                                   Connectivity connectivity = Connectivity::Six);

/// Euler characteristic of the boundary surface of the voxels ≠ 0 taken as a 6-connected
/// set, exactly as marching_cubes_mask would triangulate it (Σ over components of 2 − 2g):
/// 2·(V − E + F − C + H) where V, E, F, C count inside voxels, 6-adjacent pairs, 2×2 squares
/// and 2×2×2 blocks, and H counts 2×2×2 blocks whose only outside voxels are two opposite
/// corners (marching cubes fills that loop; the (6,26) cubical complex does not).
[[nodiscard]] std::int64_t mask_euler_characteristic(const image::Volume<std::uint8_t>& mask);

}  // namespace ido::segment

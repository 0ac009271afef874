// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>

#include "ido/image/volume.h"

namespace ido::meshing {

/// Tunables of signed_distance_from_mask.
struct DistanceFieldOptions {
  bool threaded = true;  ///< run the per-line passes in parallel (oneTBB)
};

/// Exact Euclidean distance transform of a binary mask, spacing-aware (mm): for each voxel,
/// the distance (mm) from its centre to the nearest voxel centre whose mask value is
/// nonzero; 0 on the mask. Voxels with no mask voxel anywhere get +infinity.
/// Algorithm: separable lower envelope of parabolas (Felzenszwalb & Huttenlocher, "Distance
/// transforms of sampled functions", Theory of Computing 8, 2012), one pass per axis with
/// that axis's spacing; written here by hand.
/// @throws ido::InvalidInput if the mask is empty.
[[nodiscard]] image::Volume<float> distance_to_mask(const image::Volume<std::uint8_t>& mask,
                                                    const DistanceFieldOptions& options = {});

/// Signed distance field (mm) of a binary mask on the mask's own grid, negative inside:
/// for a voxel outside the mask, the distance to the nearest mask voxel centre; for a voxel
/// inside, minus the distance to the nearest non-mask voxel centre. Neighbouring voxels of
/// opposite label therefore hold values of opposite sign and equal magnitude (the voxel
/// spacing along their axis), so the zero level lies half-way between their centres.
/// A mask with no voxel set is +infinity everywhere; a mask with every voxel set is
/// -infinity everywhere.
/// @throws ido::InvalidInput if the mask is empty.
[[nodiscard]] image::Volume<float> signed_distance_from_mask(
    const image::Volume<std::uint8_t>& mask, const DistanceFieldOptions& options = {});

}  // namespace ido::meshing

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>

#include "ido/core/math.h"
#include "ido/image/volume.h"

/// Resampling a volume onto another grid in physical (world) space.
namespace ido::image {

/// The placement of a voxel grid in world space (mm), without voxels.
struct GridGeometry {
  Index3 size{0, 0, 0};
  Vec3 spacing_mm = Vec3::Ones();
  Vec3 origin_mm = Vec3::Zero();
  Mat3 direction = Mat3::Identity();

  /// The grid of an existing volume.
  template <class T>
  [[nodiscard]] static GridGeometry of(const Volume<T>& v) {
    return {v.size(), v.spacing(), v.origin(), v.direction()};
  }
};

/// Tunables of the resamplers.
struct ResampleOptions {
  double outside_value = 0.0;  ///< value where the target voxel centre is outside the source
  bool threaded = true;        ///< run with oneTBB
};

/// Resamples @p src onto @p grid by trilinear interpolation at each target voxel centre's
/// world position. A target centre within half a voxel of the source's voxel-centre hull
/// takes the border value; farther out it gets options.outside_value.
/// Same grid → exact copy; a field linear in world coordinates is reproduced exactly
/// wherever the target centre lies inside the source hull.
/// @throws ido::InvalidInput if @p src is empty.
[[nodiscard]] Volume<float> resample_linear(const Volume<float>& src, const GridGeometry& grid,
                                            const ResampleOptions& options = {});

/// Resamples a label/mask volume onto @p grid by nearest neighbour in world space (the
/// source voxel whose cell contains the target centre; ties round half up). Outside the
/// source: options.outside_value (cast to uint8).
/// @throws ido::InvalidInput if @p src is empty.
[[nodiscard]] Volume<std::uint8_t> resample_nearest(const Volume<std::uint8_t>& src,
                                                    const GridGeometry& grid,
                                                    const ResampleOptions& options = {});

/// resample_linear onto the grid of @p grid_like (any voxel type).
template <class G>
[[nodiscard]] Volume<float> resample_linear(const Volume<float>& src, const Volume<G>& grid_like,
                                            const ResampleOptions& options = {}) {
  return resample_linear(src, GridGeometry::of(grid_like), options);
}

/// resample_nearest onto the grid of @p grid_like (any voxel type).
template <class G>
[[nodiscard]] Volume<std::uint8_t> resample_nearest(const Volume<std::uint8_t>& src,
                                                    const Volume<G>& grid_like,
                                                    const ResampleOptions& options = {}) {
  return resample_nearest(src, GridGeometry::of(grid_like), options);
}

}  // namespace ido::image

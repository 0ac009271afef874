// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstdint>

#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"
#include "ido/segment/balloon.h"

namespace ido::segment {

/// Tunables of add_calcification().
struct CalcificationOptions {
  /// Voxels brighter than this (image units, e.g. HU) that touch the lumen, or
  /// touch such a voxel, are plaque. Choose it above the lumen's accepted band
  /// (reference + tolerance) so that contrast alone does not count; required (>
  /// −∞).
  double threshold = 0.0;
  /// Plaque may lie at most this far (mm) from the nearest lumen voxel it grew
  /// from, so a bright neighbour the plaque happens to touch (bone) is cut off
  /// there. > 0.
  double max_reach_mm = 4.0;
  /// Plaque pieces smaller than this many voxels are left out (noise above the
  /// threshold).
  std::int64_t min_voxels = 2;
  bool threaded = true;
};

/// What add_calcification() added.
struct CalcificationResult {
  geometry::TriangleMesh surface;  ///< lumen ∪ plaque: closed, 2-manifold
                                   ///< (marching cubes), remeshed
  std::int64_t plaque_voxels = 0;  ///< voxels of the image counted as plaque
  double plaque_volume_mm3 = 0.0;  ///< their volume
};

/// Calcified plaque for vessel segmentations whose reference is the whole
/// vessel, not only its lumen (an intensity-driven balloon stops at the lumen;
/// calcium in the wall is far brighter than the band). From the voxels inside
/// @p lumen (a closed surface, e.g. the balloon's) a breadth-first growth over
/// face neighbours takes every voxel brighter than options.threshold within
/// options.max_reach_mm of the lumen voxel it came from. The output surface is
/// the zero level of min(signed distance to the lumen, (threshold − I_plaque)
/// scaled to mm), where I_plaque is the image with every voxel that is not
/// plaque clamped below the threshold (so a bright structure that is not
/// connected, or beyond the reach, adds nothing), extracted by
/// meshing::marching_cubes on an isotropic grid of the smallest spacing and
/// remeshed to that edge length. With no plaque found the lumen surface is
/// returned unchanged. Written for ido (no packaged library does this).
/// @throws ido::InvalidInput on an empty image or surface, a non-finite
/// threshold, or a reach ≤ 0.
[[nodiscard]] CalcificationResult add_calcification(const geometry::TriangleMesh &lumen, const image::Volume<float> &ct,
                                                    const CalcificationOptions &options);

/// add_calcification() on a balloon's result: result.surface becomes lumen ∪ plaque and
/// result.report's surface figures (volume, V/E/F, Euler characteristic, flags,
/// self-intersections) are recounted for it. Returns the plaque figures; the returned
/// surface is empty (it is in result.surface).
/// @throws ido::InvalidInput when options.threshold lies inside the lumen's accepted band
/// (at or below reference + tolerance of result.report.model, unless it accepts anything
/// brighter): contrast would count as plaque; as add_calcification() otherwise.
CalcificationResult add_calcification(BalloonResult &result, const image::Volume<float> &ct,
                                      const CalcificationOptions &options);

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"
#include "ido/io/report_json.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"

namespace ido::view {

/// Where the workbench saves a segmentation; an empty path is not written.
struct SegmentOutputs {
  std::filesystem::path surface;  ///< .stl, .ply, .obj or .vtp
  std::filesystem::path mask;     ///< a volume file (.nii, .nii.gz, .nrrd, .mha): 1 inside
  std::filesystem::path report;   ///< JSON, the keys `ido segment --report` writes
};

using segment::SegmentRequest;

/// Checks the output paths before any work, as `ido segment` does (surface extension, mask
/// a volume file). @throws ido::InvalidInput naming the path and the problem.
void check_segment_outputs(const SegmentOutputs& outputs);

/// Writes the surface (io::write_triangle_mesh), the mask (segment::surface_to_mask on
/// @p ct's grid) and the report (io::segment_report), each atomically; the ones with an empty path are skipped.
/// @throws ido::IoError when a file cannot be written.
void save_segmentation(const SegmentOutputs& outputs, const image::Volume<float>& ct, const SegmentRequest& request,
                       const segment::BalloonResult& result);

}  // namespace ido::view

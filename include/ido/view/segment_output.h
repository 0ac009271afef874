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

/// How a segmentation was asked for, as its report records it.
struct SegmentRequest {
  std::string input;               ///< the CT's file name as given
  std::vector<Vec3> seeds_mm;      ///< world positions (mm)
  segment::Organ organ = segment::Organ::Generic;
  segment::BalloonOptions options; ///< the options the balloon ran with
};

/// Checks the output paths before any work, as `ido segment` does (surface extension, mask
/// a volume file). @throws ido::InvalidInput naming the path and the problem.
void check_segment_outputs(const SegmentOutputs& outputs);

/// The segmentation report for @p result ("surface" and "mask" name @p outputs): the request
/// (input, seeds, organ, options, stop points, region of interest `roi_mm` [[min], [max]] and
/// `leak_control.max_radius_mm`, each null when not set) and io::to_json of the balloon's report; the
/// document `ido segment --report` writes (which adds its calcification and snapshot keys) and
/// the workbench saves. Keys: docs/reports.md.
[[nodiscard]] io::Json segment_report_json(const SegmentRequest& request, const segment::BalloonResult& result,
                                           const SegmentOutputs& outputs);

/// Writes the surface (io::write_triangle_mesh), the mask (segment::surface_to_mask on
/// @p ct's grid) and the report, each atomically; the ones with an empty path are skipped.
/// @throws ido::IoError when a file cannot be written.
void save_segmentation(const SegmentOutputs& outputs, const image::Volume<float>& ct, const SegmentRequest& request,
                       const segment::BalloonResult& result);

}  // namespace ido::view

// SPDX-License-Identifier: Apache-2.0
#include "ido/view/segment_output.h"

#include <cmath>

#include <fmt/format.h>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "ido/io/report_json.h"
#include "ido/io/volume_io.h"

namespace ido::view {

void check_segment_outputs(const SegmentOutputs& o) {
  if (!o.surface.empty()) {
    if (!io::is_triangle_mesh_path(o.surface))
      throw InvalidInput(fmt::format("{}: the surface output must be .stl, .ply, .obj or .vtp", o.surface.string()));
  }
  if (!o.mask.empty() && !io::looks_like_volume(o.mask))
    throw InvalidInput(
        fmt::format("{}: the mask output must be a volume file (.nii, .nii.gz, .nrrd, .mha)", o.mask.string()));
}

void save_segmentation(const SegmentOutputs& outputs, const image::Volume<float>& ct, const SegmentRequest& request,
                       const segment::BalloonResult& result) {
  if (!outputs.surface.empty()) io::write_triangle_mesh(outputs.surface, result.surface);
  if (!outputs.mask.empty()) io::write_volume(outputs.mask, segment::surface_to_mask(result.surface, ct));
  if (!outputs.report.empty()) {
    const std::string text = io::segment_report(request, result, outputs.surface, outputs.mask).dump(2) + "\n";
    write_file_atomically(outputs.report, [&](std::ostream& out) { out << text; }, false);
  }
}

}  // namespace ido::view

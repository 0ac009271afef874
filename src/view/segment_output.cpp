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
    const std::string ext = o.surface.extension().string();
    if (ext != ".stl" && ext != ".ply" && ext != ".obj" && ext != ".vtp")
      throw InvalidInput(fmt::format("{}: the surface output must be .stl, .ply, .obj or .vtp", o.surface.string()));
  }
  if (!o.mask.empty() && !io::looks_like_volume(o.mask))
    throw InvalidInput(
        fmt::format("{}: the mask output must be a volume file (.nii, .nii.gz, .nrrd, .mha)", o.mask.string()));
}

io::Json segment_report_json(const SegmentRequest& request, const segment::BalloonResult& result,
                             const SegmentOutputs& outputs) {
  const segment::BalloonOptions& bo = request.options;
  const auto points = [](const std::vector<Vec3>& ps) {
    io::Json out = io::Json::array();
    for (const Vec3& p : ps) out.push_back(io::Json::array({p.x(), p.y(), p.z()}));
    return out;
  };
  io::Json j = {{"input", request.input},
                {"seeds_mm", points(request.seeds_mm)},
                {"organ", segment::organ_name(request.organ)},
                {"edge_reach_voxels", bo.edge_reach_voxels},
                {"outside_level", bo.outside_level ? io::Json(*bo.outside_level) : io::Json(nullptr)}};
  j.update(io::to_json(result.report));  // the balloon's figures, as every report writes them
  // The region of interest (null: none); the stop points and radius bound are the balloon's.
  j["roi_mm"] = bo.roi_mm ? points({bo.roi_mm->min, bo.roi_mm->max}) : io::Json(nullptr);
  j["surface"] = outputs.surface.empty() ? io::Json(nullptr) : io::Json(outputs.surface.string());
  j["mask"] = outputs.mask.empty() ? io::Json(nullptr) : io::Json(outputs.mask.string());
  return j;
}

void save_segmentation(const SegmentOutputs& outputs, const image::Volume<float>& ct, const SegmentRequest& request,
                       const segment::BalloonResult& result) {
  if (!outputs.surface.empty()) io::write_triangle_mesh(outputs.surface, result.surface);
  if (!outputs.mask.empty()) io::write_volume(outputs.mask, segment::surface_to_mask(result.surface, ct));
  if (!outputs.report.empty()) {
    const std::string text = segment_report_json(request, result, outputs).dump(2) + "\n";
    write_file_atomically(outputs.report, [&](std::ostream& out) { out << text; }, false);
  }
}

}  // namespace ido::view

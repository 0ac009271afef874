// SPDX-License-Identifier: Apache-2.0
#include "ido/view/segment_output.h"

#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
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

nlohmann::json segment_report_json(const SegmentRequest& request, const segment::BalloonResult& result,
                                   const SegmentOutputs& outputs) {
  const segment::BalloonReport& rep = result.report;
  const segment::BalloonOptions& bo = request.options;
  nlohmann::json seeds = nlohmann::json::array();
  for (const Vec3& s : request.seeds_mm) seeds.push_back({s.x(), s.y(), s.z()});
  nlohmann::json events = nlohmann::json::array(), markers = nlohmann::json::array();
  for (const segment::LeakEvent& e : rep.leaks)
    events.push_back({{"cause", segment::leak_cause_name(e.cause)},
                      {"position_mm", {e.position_mm.x(), e.position_mm.y(), e.position_mm.z()}},
                      {"iteration", e.iteration},
                      {"neck_area_mm2", e.neck_area_mm2},
                      {"neck_radius_mm", e.neck_radius_mm}});
  for (const Vec3& m : rep.neighbour_markers_mm) markers.push_back({m.x(), m.y(), m.z()});
  const nlohmann::json leak = {
      {"seed_radius_mm", rep.seed_radius_mm},
      {"chamber_radius_mm",
       std::isfinite(rep.chamber_radius_mm) ? nlohmann::json(rep.chamber_radius_mm) : nlohmann::json(nullptr)},
      {"neighbour_markers_mm", markers},
      {"events", events}};
  return {
      {"input", request.input},
      {"seeds_mm", seeds},
      {"reference", rep.model.reference},
      {"tolerance", rep.model.tolerance},
      {"accept_brighter", rep.model.accept_brighter},
      {"iterations", rep.iterations},
      {"organ", segment::organ_name(request.organ)},
      {"edge_reach_voxels", bo.edge_reach_voxels},
      {"outside_level", bo.outside_level ? nlohmann::json(*bo.outside_level) : nlohmann::json(nullptr)},
      {"leak_control", leak},
      {"seconds", rep.seconds},
      {"phase_seconds",
       {{"setup", rep.phase_seconds.setup},
        {"move", rep.phase_seconds.move},
        {"remesh", rep.phase_seconds.remesh},
        {"intersections", rep.phase_seconds.intersections},
        {"repair", rep.phase_seconds.repair}}},
      {"volume_mm3", rep.volume_mm3},
      {"area_mm2", rep.area_mm2},
      {"vertices", rep.vertices},
      {"edges", rep.edges},
      {"triangles", rep.triangles},
      {"euler_characteristic", rep.euler_characteristic},
      {"components", rep.components},
      {"closed", rep.closed},
      {"manifold", rep.manifold},
      {"oriented", rep.oriented},
      {"self_intersections", rep.self_intersections},
      {"repairs", rep.repairs},
      {"local_repairs", rep.local_repairs},
      {"inflation_vertex_steps", rep.inflation_vertex_steps},
      {"slept_vertex_steps", rep.slept_vertex_steps},
      {"frozen_vertices", rep.frozen_vertices},
      {"converged", rep.converged},
      {"stop_reason", rep.stop_reason},
      {"leak_warning", rep.leak_warning},
      {"surface", outputs.surface.empty() ? nlohmann::json(nullptr) : nlohmann::json(outputs.surface.string())},
      {"mask", outputs.mask.empty() ? nlohmann::json(nullptr) : nlohmann::json(outputs.mask.string())}};
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

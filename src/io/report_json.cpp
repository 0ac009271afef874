// SPDX-License-Identifier: Apache-2.0
#include "ido/io/report_json.h"

#include <cmath>
#include <optional>
#include <vector>

namespace ido::io {
namespace {

using json = Json;

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

/// A list of points as [[x, y, z], ...].
json vecs(const std::vector<Vec3>& points) {
  json out = json::array();
  for (const Vec3& p : points) out.push_back(vec(p));
  return out;
}

/// An optional figure: the value, or null when unset.
template <class T>
json value_or_null(const std::optional<T>& v) {
  return v ? json(*v) : json(nullptr);
}

}  // namespace

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json to_json(const geometry::MeshCheckReport& r) {
  return {{"vertices", r.vertices},
          {"edges", r.edges},
          {"triangles", r.triangles},
          {"closed", r.closed},
          {"edge_manifold", r.edge_manifold},
          {"vertex_manifold", r.vertex_manifold},
          {"oriented", r.oriented},
          {"euler_characteristic", r.euler_characteristic},
          {"components", r.components},
          {"genus", value_or_null(r.genus)},
          {"boundary_edges", r.boundary_edges},
          {"non_manifold_edges", r.non_manifold_edges},
          {"non_manifold_vertices", r.non_manifold_vertices},
          {"degenerate_triangles", r.degenerate_triangles},
          {"area_mm2", r.area_mm2},
          {"volume_mm3", r.signed_volume_mm3},
          {"bounds_min_mm", vec(r.bounds_min)},
          {"bounds_max_mm", vec(r.bounds_max)}};
}

json to_json(const geometry::TetMeshReport& r) {
  return {{"vertices", r.vertices},
          {"tets", r.tets},
          {"inverted", r.inverted},
          {"degenerate", r.degenerate},
          {"volume_mm3", r.volume_mm3},
          {"min_dihedral_deg", finite_or_null(r.min_dihedral_deg)},
          {"max_dihedral_deg", finite_or_null(r.max_dihedral_deg)},
          {"min_mean_ratio", r.min_mean_ratio},
          {"mean_mean_ratio", r.mean_mean_ratio},
          {"boundary_faces", r.boundary_faces},
          {"boundary_closed", r.boundary_closed},
          {"boundary_manifold", r.boundary_manifold}};
}

json to_json(const segment::SegmentationScores& s) {
  return {{"dice", s.dice},
          {"hd95_mm", finite_or_null(s.hd95_mm)},
          {"assd_mm", finite_or_null(s.assd_mm)},
          {"hausdorff_mm", finite_or_null(s.hd_mm)},
          {"volume_ratio", finite_or_null(s.volume_ratio)},
          {"volume_mask_mm3", s.volume_mask_mm3},
          {"volume_truth_mm3", s.volume_truth_mm3},
          {"voxels_mask", s.voxels_mask},
          {"voxels_truth", s.voxels_truth},
          {"components_mask", s.components_mask},
          {"components_truth", s.components_truth},
          {"resampled_to_truth_grid", s.resampled}};
}

json to_json(const segment::BalloonReport& r) {
  json events = json::array();
  for (const segment::LeakEvent& e : r.leaks)
    events.push_back(json{{"cause", segment::leak_cause_name(e.cause)},
                      {"position_mm", vec(e.position_mm)},
                      {"iteration", e.iteration},
                      {"neck_area_mm2", e.neck_area_mm2},
                      {"neck_radius_mm", e.neck_radius_mm}});
  return {{"reference", r.model.reference},
          {"tolerance", r.model.tolerance},
          {"accept_brighter", r.model.accept_brighter},
          {"outside_level_used", value_or_null(r.outside_level)},
          {"iterations", r.iterations},
          {"leak_control",
           {{"seed_radius_mm", r.seed_radius_mm},
            {"chamber_radius_mm", finite_or_null(r.chamber_radius_mm)},
            {"neighbour_markers_mm", vecs(r.neighbour_markers_mm)},
            {"events", events},
            {"stop_points_mm", vecs(r.stop_points_mm)},
            {"max_radius_mm", finite_or_null(r.max_radius_mm)}}},
          {"seconds", r.seconds},
          {"phase_seconds",
           {{"setup", r.phase_seconds.setup},
            {"move", r.phase_seconds.move},
            {"remesh", r.phase_seconds.remesh},
            {"intersections", r.phase_seconds.intersections},
            {"repair", r.phase_seconds.repair}}},
          {"volume_mm3", r.volume_mm3},
          {"area_mm2", r.area_mm2},
          {"vertices", r.vertices},
          {"edges", r.edges},
          {"triangles", r.triangles},
          {"euler_characteristic", r.euler_characteristic},
          {"components", r.components},
          {"closed", r.closed},
          {"manifold", r.manifold},
          {"oriented", r.oriented},
          {"self_intersections", r.self_intersections},
          {"repairs", r.repairs},
          {"local_repairs", r.local_repairs},
          {"inflation_vertex_steps", r.inflation_vertex_steps},
          {"slept_vertex_steps", r.slept_vertex_steps},
          {"frozen_vertices", r.frozen_vertices},
          {"edge_profile_searches", r.edge_profile_searches},
          {"edge_profile_reuses", r.edge_profile_reuses},
          {"converged", r.converged},
          {"stop_reason", r.stop_reason},
          {"leak_warning", r.leak_warning}};
}

json to_json(const sim::EnergyReport& e) {
  json per_model = json::array();
  for (std::size_t m = 0; m < e.elastic_mj.size(); ++m)
    per_model.push_back(json{{"model", m < e.model_kinds.size() ? e.model_kinds[m] : std::string()},
                         {"elastic_mj", e.elastic_mj[m]}});
  return {{"kinetic_mj", e.kinetic_mj},
          {"gravitational_mj", e.gravitational_mj},
          {"elastic_mj", e.elastic_total_mj()},
          {"total_mj", e.total_mj()},
          {"per_model", per_model}};
}

json segment_report(const segment::SegmentRequest& request, const segment::BalloonResult& result,
                    const std::filesystem::path& surface, const std::filesystem::path& mask) {
  const segment::BalloonOptions& bo = request.options;
  json j = {{"input", request.input},
            {"seeds_mm", vecs(request.seeds_mm)},
            {"organ", segment::organ_name(request.organ)},
            {"edge_reach_voxels", bo.edge_reach_voxels},
            {"outside_level", value_or_null(bo.outside_level)}};
  j.update(to_json(result.report));  // the balloon's figures, as every report writes them
  // The region of interest (null: none); the stop points and radius bound are the balloon's.
  j["roi_mm"] = bo.roi_mm ? vecs({bo.roi_mm->min, bo.roi_mm->max}) : json(nullptr);
  j["surface"] = surface.empty() ? json(nullptr) : json(surface.string());
  j["mask"] = mask.empty() ? json(nullptr) : json(mask.string());
  return j;
}

}  // namespace ido::io

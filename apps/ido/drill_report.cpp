// SPDX-License-Identifier: Apache-2.0
#include "drill_report.h"

namespace ido::cli {
namespace {
nlohmann::json times_ms(const drill::Percentiles& p) {
  return {{"p50", p.p50 * 1e3}, {"p99", p.p99 * 1e3}, {"p99_9", p.p999 * 1e3}, {"max", p.max * 1e3}, {"count", p.count}};
}
}  // namespace

nlohmann::json drill_session_json(const drill::TetHierarchy& hierarchy, const drill::Simulator& sim,
                                  const drill::SimulatorOptions& options, double volume_before_mm3) {
  const auto& st = sim.stats();
  const double after = hierarchy.material_volume();
  nlohmann::json r;
  r["roots"] = hierarchy.root_count();
  r["tool"] = {{"burr_radius_mm", options.tool.burr_radius_mm}, {"shaft_radius_mm", options.tool.shaft_radius_mm},
               {"samples", options.tool.sample_count}};
  r["removed_volume_mm3"] = volume_before_mm3 - after;
  r["remaining_volume_mm3"] = after;
  r["node_count"] = hierarchy.node_count();
  r["bytes_per_node"] = hierarchy.bytes_per_node();
  r["storage_bytes_per_node_incl_free_list"] = hierarchy.storage_bytes_per_node();
  r["update_time_ms"] = times_ms(drill::percentiles(st.update_time_s));
  r["haptic_period_ms"] = times_ms(drill::percentiles(st.haptic_period_s));
  r["force_compute_ms"] = times_ms(drill::percentiles(st.force_compute_time_s));
  r["haptic_ticks"] = st.haptic_ticks;
  r["missed_1ms_deadlines"] = st.missed_deadlines;
  r["haptic_realtime"] = st.haptic_realtime;
  r["surface_threads"] = st.surface_threads;
  r["collision_updates"] = st.collision_updates;
  r["render_snapshots"] = st.render_snapshots;
  // How the session ended: at the path's end, with the erosion backlog finished within the
  // drain limit (or how many burr positions it left undone).
  r["session_end"] = {{"path_finished", st.path_finished},
                      {"drain_time_s", st.drain_time_s},
                      {"drain_limit_s", options.drain_limit_s},
                      {"backlog_left_positions", st.backlog_left_positions},
                      {"timed_out", st.timed_out},
                      {"node_limit", options.erosion.max_nodes},
                      {"node_limit_passes", st.node_limit_passes}};
  r["force"] = {{"peak_n", st.peak_force_n}, {"mean_in_contact_n", st.mean_force_n},
                {"max_step_between_ticks_n", st.max_force_step_n}, {"ticks_in_contact", st.contact_ticks}};
  return r;
}

}  // namespace ido::cli

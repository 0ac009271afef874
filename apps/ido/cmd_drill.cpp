// SPDX-License-Identifier: Apache-2.0
// `ido drill MESH --tool sphere:radius=MM[,shaft=MM] --path PATH.csv -o OUT.vtu ...
//  [--snapshots DIR [--snapshot-every SECONDS] [--snapshot-size WxH]]`: runs a scripted tool
// trajectory through the same three threads as an interactive session, which ends when the
// path ends (the erosion backlog is finished within SimulatorOptions::drain_limit_s, or the
// report and a warning say what was left); pictures of the
// drilled surface come from the render consumer's copies of the v_lists, rendered after the
// session (the drill library knows nothing of viz).
#include <fmt/format.h>

#include <sys/resource.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "command.h"
#include "snapshots.h"
#include "drill_report.h"
#include "ido/core/error.h"
#include "ido/core/log.h"
#include "ido/drill/assembled_surface.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/embedding.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/simulator.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/drill/tool.h"
#include "ido/io/leaf_mesh_io.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "ido/viz/renderer.h"

namespace ido::cli {
namespace {

struct DrillOptions {
  std::string mesh;
  std::string tool;
  std::string path;
  std::string output;
  std::string surface;
  std::string report;
  double min_size_mm = 0.0;         // 0: not given
  std::optional<int> max_depth;     // absent with min_size_mm 0: leaves down to burr radius / 4
  std::string density_from;
  double force_threshold_n = 0.2;
  double removal_rate = 0.0;
  double stiffness = 1.5;
  std::int64_t visit_budget = -1;  // -1: the library default
  int haptic_priority = drill::SimulatorOptions{}.haptic_realtime_priority;
  int surface_threads = 0;  // 0: the hardware threads less one
  std::string snapshots;
  double snapshot_every_s = 0.5;
  std::string snapshot_size = "640x480";
};

/// The most pictures one run may ask for.
constexpr double kMaxSnapshots = 2000;

// The whole process's peak resident memory (bytes), getrusage's ru_maxrss.
std::size_t peak_rss_bytes() {
  rusage u{};
  if (::getrusage(RUSAGE_SELF, &u) != 0) return 0;
  return static_cast<std::size_t>(u.ru_maxrss) * 1024U;  // KiB on Linux
}

// Returns the heap's freed memory to the system (glibc; elsewhere nothing to do).
void trim_heap() {
#if defined(__GLIBC__)
  ::malloc_trim(0);
#endif
}

// The smallest leaf size the hierarchy can reach on @p hierarchy's largest root (mm), and
// the refinement depth @p min_size_mm implies there.
void check_min_size(const drill::TetHierarchy& hierarchy, double min_size_mm) {
  double largest = 0.0;
  for (std::size_t r = 0; r < hierarchy.root_count(); ++r) largest = std::max(largest, hierarchy.root_diameter(r));
  if (!(largest > 0.0)) return;
  const double implied = std::ceil(std::log2(largest / min_size_mm) - 1e-12);
  if (implied > drill::kMaxDepth) {
    throw InvalidInput(fmt::format(
        "--min-size {:g} mm needs refinement depth {:g} on the largest tetrahedron ({:.3g} mm across); the hierarchy "
        "allows {} levels, so --min-size must be at least {:.3g} mm on this mesh",
        min_size_mm, implied, largest, drill::kMaxDepth, largest / std::ldexp(1.0, drill::kMaxDepth)));
  }
}

void run(const DrillOptions& o, const GlobalOptions& g) {
  if (!io::is_tet_mesh_path(o.output)) throw InvalidInput(fmt::format("{}: -o must be a .vtu (or .msh, .node) file", o.output));
  if (!o.surface.empty() && !io::is_triangle_mesh_path(o.surface)) {
    throw InvalidInput(fmt::format("{}: --surface must be .stl, .ply, .obj or .vtp", o.surface));
  }
  if (!(o.min_size_mm >= 0.0) || !std::isfinite(o.min_size_mm)) throw InvalidInput("--min-size must be a positive number of mm");
  if (o.max_depth && (*o.max_depth < 0 || *o.max_depth > drill::kMaxDepth)) {
    throw InvalidInput(fmt::format("--max-depth must be between 0 and {}", drill::kMaxDepth));
  }
  drill::SimulatorOptions so;
  so.tool = drill::parse_tool(o.tool);
  so.erosion.force_threshold_n = o.force_threshold_n;
  so.erosion.removal_rate_mm3_per_s = o.removal_rate;
  if (o.max_depth) so.erosion.max_depth = *o.max_depth;
  so.erosion.min_size_mm = o.min_size_mm;
  // Neither given: leaves a quarter of the burr radius across, fine enough for a smooth cut
  // and independent of how coarse the input mesh is (a fixed depth is not).
  if (!o.max_depth && o.min_size_mm == 0.0) so.erosion.min_size_mm = so.tool.burr_radius_mm / 4.0;
  so.coupling.stiffness_n_per_mm = o.stiffness;
  if (o.visit_budget >= 0) so.erosion.max_node_visits = static_cast<std::size_t>(o.visit_budget);
  if (o.haptic_priority < 0 || o.haptic_priority > 99) {
    throw InvalidInput(fmt::format("--haptic-priority must be between 0 and 99, got {}", o.haptic_priority));
  }
  so.haptic_realtime_priority = o.haptic_priority;
  if (o.surface_threads < 0) {
    throw InvalidInput(fmt::format("--surface-threads must be 0 (automatic) or a positive count, got {}", o.surface_threads));
  }
  so.surface.threads = o.surface_threads;
  SnapshotOptions picture;  // one camera for every picture, looking down at 50°
  picture.azimuth_deg = 30.0;
  picture.elevation_deg = 50.0;
  if (!o.snapshots.empty()) {
    if (!(o.snapshot_every_s > 0.0) || !std::isfinite(o.snapshot_every_s)) {
      throw InvalidInput(fmt::format("--snapshot-every must be a positive number of seconds, got {}", o.snapshot_every_s));
    }
    const auto [w, h] = parse_picture_size(o.snapshot_size, "--snapshot-size");
    picture.width_px = w;
    picture.height_px = h;
  }
  // Every output is checked before the work starts, and written all or none at the end.
  OutputBatch outputs;
  const std::string output_tmp = outputs.stage(o.output, "-o");
  const std::string surface_tmp = o.surface.empty() ? std::string() : outputs.stage(o.surface, "--surface");
  const std::string report_tmp = o.report.empty() ? std::string() : outputs.stage(o.report, "--report");

  // The recording buffers hold the path's ticks (1 kHz) and the drain, not a fixed 2^20.
  const auto peek = drill::ScriptedTrajectory::load_csv(o.path, 1);
  const auto ticks = static_cast<std::size_t>((peek.duration() + so.drain_limit_s + 1.0) / so.haptic_period_s) + 1024;
  so.max_haptic_ticks = std::min<std::size_t>(ticks, so.max_haptic_ticks);
  auto device = drill::ScriptedTrajectory(peek.times(), peek.poses(), so.max_haptic_ticks);
  if (!o.snapshots.empty() && device.duration() / o.snapshot_every_s > kMaxSnapshots) {
    throw InvalidInput(fmt::format("--snapshot-every {} s gives more than {} pictures over the {} s path", o.snapshot_every_s,
                                   kMaxSnapshots, device.duration()));
  }
  const auto mesh = io::read_tet_mesh(o.mesh);
  drill::TetHierarchy hierarchy(mesh);
  if (o.min_size_mm > 0.0) check_min_size(hierarchy, o.min_size_mm);
  if (!o.density_from.empty()) drill::assign_density_from_ct(hierarchy, io::read_volume(o.density_from));
  const double before = hierarchy.material_volume();
  std::optional<SnapshotWriter> writer;
  if (!o.snapshots.empty()) writer.emplace(o.snapshots, picture);

  // The session, and what is kept of it: the surface, the report's figures and the summary's.
  // The simulator (its v_lists and the render copy) is gone before the outputs are made.
  std::vector<std::pair<double, std::vector<std::vector<drill::SurfaceFace>>>> shots;
  std::vector<std::vector<drill::SurfaceFace>> lists;
  nlohmann::json r;
  drill::SessionMemory mem;
  drill::SessionStats st;
  std::size_t session_peak = 0;
  {
    drill::Simulator sim(hierarchy, device, so);
    // The render consumer hands over copies of its v_lists at the picture times; they are
    // rendered once the session is over, so rendering never competes with the session.
    if (!o.snapshots.empty()) {
      sim.set_surface_snapshots([&shots](double t, const auto& shown) { shots.emplace_back(t, shown); },
                                o.snapshot_every_s, device.duration());
    }
    {
      const auto progress = make_progress(g.quiet);
      // A safety net only: the session ends at the path's end plus at most the drain limit.
      sim.run(device.duration() + so.drain_limit_s + 30.0, progress.get());
    }
    session_peak = peak_rss_bytes();  // the drilling alone, before any output is made
    mem = sim.memory_use();
    if (!o.report.empty()) r = drill_session_json(hierarchy, sim, so, before);
    st = sim.stats();
    lists = sim.take_render_v_lists();
  }
  // The outputs one at a time, each freed before the next is made: the surface (assembled
  // from the v_lists taken over, which it frees root by root), then the leaf mesh. Between
  // them the freed memory goes back to the system: ido's heap policy keeps freed memory
  // (ido/core/memory.h), and blocks above 32 MiB are mapped afresh, so the next output would
  // come on top of it (docs/drilling.md, "Session end and memory").
  trim_heap();
  std::size_t surface_triangles = 0, surface_bytes = 0, leaf_bytes = 0;
  if (!o.surface.empty() || !o.report.empty()) {
    // Held compactly (point keys, triangles in blocks) and, as a .vtp, streamed to the file.
    const drill::AssembledSurface surface(std::move(lists), hierarchy.vertices());
    surface_triangles = surface.triangle_count();
    surface_bytes = surface.memory_bytes();
    if (!o.surface.empty()) io::write_drilled_surface(surface_tmp, surface);
  }
  lists = {};
  const std::size_t surface_peak = peak_rss_bytes();  // the session and the surface
  trim_heap();
  // The leaf mesh goes to the file as the hierarchy is walked (a .vtu holds no mesh).
  leaf_bytes = io::write_leaf_mesh(output_tmp, hierarchy).memory_bytes;
  trim_heap();
  if (writer) {
    // The camera is fixed by the first picture (the intact mesh) and kept for the rest.
    for (const auto& shot : shots) {
      viz::Renderer ren(picture.width_px, picture.height_px);
      ren.add_surface(drill::assemble_surface(shot.second, hierarchy.vertices()), Vec3(0.9, 0.85, 0.7),
                      {.shading = viz::Shading::Flat});
      (void)writer->write(ren);
    }
  }
  const std::size_t force_record = device.forces().size() * sizeof(drill::ForceSample);
  const std::size_t peak = peak_rss_bytes();
  if (!o.report.empty()) {
    r["mesh"] = o.mesh;
    r["surface_triangles"] = surface_triangles;
    r["memory"] = {{"peak_rss_bytes", peak},
                   {"session_peak_rss_bytes", session_peak},
                   {"surface_peak_rss_bytes", surface_peak},
                   {"nodes_bytes", mem.nodes},
                   {"v_lists_bytes", mem.v_lists},
                   {"hash_bytes", mem.hash},
                   {"buffers_bytes", mem.buffers + force_record},
                   {"other_bytes", peak > mem.total() + force_record ? peak - mem.total() - force_record : 0},
                   {"surface_mesh_bytes", surface_bytes},
                   {"leaf_mesh_bytes", leaf_bytes}};
    if (!o.snapshots.empty()) {
      r["snapshots"] = writer->files_json();
      r["snapshot_period_s"] = o.snapshot_every_s;
      nlohmann::json times = nlohmann::json::array();
      for (const auto& s : shots) times.push_back(s.first);
      r["snapshot_times_s"] = times;
    }
    write_text_file(report_tmp, r.dump(2) + "\n");
  }
  outputs.commit();
  if (!g.quiet) {
    std::vector<double> force;
    force.reserve(device.forces().size());
    for (const auto& f : device.forces()) force.push_back(f.force_n.norm());
    std::printf("drilled %.3g mm3 in %.1f s (+%.2f s finishing), update p99 %.3g ms, force p99.9 %.3g N, %zu nodes, peak memory %.0f MiB%s\n",
                before - hierarchy.material_volume(), device.duration(), st.drain_time_s,
                drill::percentiles(st.update_time_s).p99 * 1e3, drill::percentiles(force).p999, hierarchy.node_count(),
                static_cast<double>(peak) / (1024.0 * 1024.0),
                st.backlog_left_positions > 0
                    ? fmt::format("; {} burr positions left undone after the {:g} s drain limit", st.backlog_left_positions,
                                  so.drain_limit_s).c_str()
                    : "");
  }
  if (st.backlog_left_positions > 0 || st.timed_out)
    logger().warn("drill: the session ended with {} burr positions not eroded (drain limit {:g} s{})",
                  st.backlog_left_positions, so.drain_limit_s, st.timed_out ? ", run timed out" : "");
  if (st.node_limit_passes > 0)
    logger().warn("drill: the node limit ({} nodes) left some leaves coarser than asked", so.erosion.max_nodes);
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand("drill", "Drill a tetrahedral mesh along a scripted tool path (haptic-rate threads)");
  auto opts = std::make_shared<DrillOptions>();
  sub->add_option("MESH", opts->mesh, "Tetrahedral mesh (.vtu, .msh, .node)")->required();
  sub->add_option("--tool", opts->tool, "sphere:radius=MM[,shaft=MM][,samples=N]")->required();
  sub->add_option("--path", opts->path,
                  "Trajectory CSV: t,x,y,z[,qx,qy,qz,qw] (s, mm), times increasing up to 3600 s, played in real time; "
                  "an optional first line of names")
      ->required();
  sub->add_option("-o,--output", opts->output, "Drilled mesh (.vtu): remaining leaf tetrahedra, depth and density")->required();
  sub->add_option("--surface", opts->surface, "Boundary surface (.stl, .ply, .vtp)");
  sub->add_option("--report", opts->report, "JSON report");
  auto* min_size = sub->add_option("--min-size", opts->min_size_mm, "Finest leaf size (mm; default a quarter of the burr radius)");
  auto* depth = sub->add_option("--max-depth", opts->max_depth, "Finest refinement level (default: leaves down to a quarter of the burr radius)");
  min_size->excludes(depth);
  sub->add_option("--density-from", opts->density_from, "CT volume (HU) giving each root's density");
  sub->add_option("--force-threshold", opts->force_threshold_n, "Pressing force (N) above which the burr cuts (default 0.2)");
  sub->add_option("--removal-rate", opts->removal_rate, "Removal rate (mm^3/s at density 1); 0 = unlimited (default)");
  sub->add_option("--stiffness", opts->stiffness, "Coupling stiffness (N/mm, default 1.5)");
  sub->add_option("--visit-budget", opts->visit_budget,
                  "Erosion work per collision update (node visits; 0 = unlimited; default 6000), the rest carries over");
  sub->add_option("--haptic-priority", opts->haptic_priority,
                  "SCHED_FIFO priority asked for the haptic thread (1-99; 0 = ordinary scheduling; default 80; "
                  "refused without CAP_SYS_NICE, see haptic_realtime in the report)");
  sub->add_option("--surface-threads", opts->surface_threads,
                  "Worker threads of the surface (v_list) rebuild; 0 = the hardware threads less one for the haptic "
                  "thread (default), 1 = serial");
  sub->add_option("--snapshots", opts->snapshots, "Folder for pictures of the drilled surface: snapshot_0000.png, ...");
  sub->add_option("--snapshot-every", opts->snapshot_every_s, "Seconds of the path between pictures (default 0.5)");
  sub->add_option("--snapshot-size", opts->snapshot_size, "Picture size WIDTHxHEIGHT in pixels (default 640x480)");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"drill", 45, setup});

}  // namespace
}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
// `ido view [FILE...] [--script EVENTS.json --screenshots DIR] [--record EVENTS.json] [--frames N]
//  [--size WxH] [--organ NAME] [--seed-voxel I,J,K] [--stop-voxel I,J,K] [--surface S.stl] [--mask M.nii.gz]
//  [--report R.json] [--tet-output M.vtu] [--tet-edge MM] [--burr-radius MM] [--shaft-radius MM] [--drill-max S]
//  [--drill-path P.csv] [--drill-report R.json] [--drill-replay P.csv] [--drill-udp PORT] [--deform-log LOG.json]
//  [--roi x0,y0,z0,x1,y1,z1] [--max-radius MM] [--snapshot OUT.png]`:
//  the interactive workbench. Presentation only: the workbench is ido::view::run_workbench.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_util.h"
#include "command.h"
#include "ido/core/error.h"
#include "ido/view/workbench.h"
#include "snapshots.h"

namespace ido::cli {
namespace {

struct ViewCliOptions {
  std::vector<std::string> files;
  std::string script, screenshots, record;
  std::int64_t frames = 0;
  std::string size = "1280x800";
  std::string organ = "generic";
  std::vector<std::string> seed_voxels, stop_voxels;
  std::string surface, mask, report;
  std::string tet_output;
  double tet_edge_mm = 0.0;
  double burr_radius_mm = 2.0;
  double shaft_radius_mm = 0.0;
  double drill_max_s = 60.0;
  std::string drill_path, drill_report, drill_replay;
  int drill_udp_port = 0;
  std::string deform_log;
  std::string roi;
  std::optional<double> max_radius_mm;
  std::string snapshot;
};

void run(const ViewCliOptions& o, const GlobalOptions& g) {
  view::WorkbenchOptions w;
  for (const auto& f : o.files) w.files.emplace_back(f);
  w.script = o.script;
  w.screenshots = o.screenshots;
  w.record = o.record;
  if (o.frames < 0) throw InvalidInput(fmt::format("--frames must be 0 (no limit) or more, got {}", o.frames));
  w.max_frames = o.frames;
  const auto [width, height] = parse_picture_size(o.size, "--size");
  w.width_px = width;
  w.height_px = height;
  w.organ = parse_organ_option(o.organ, "--organ");
  for (const auto& s : o.seed_voxels) w.seed_voxels.push_back(parse_index3(s, "--seed-voxel"));
  for (const auto& s : o.stop_voxels) w.stop_voxels.push_back(parse_index3(s, "--stop-voxel"));
  w.segment_outputs = {o.surface, o.mask, o.report};
  for (const auto& [path, option] : {std::pair{o.surface, "--surface"}, {o.mask, "--mask"}, {o.report, "--report"}})
    if (!path.empty()) check_output_file(path, option);
  if (!o.record.empty()) check_output_file(o.record, "--record");
  w.tet_output = o.tet_output;
  if (!o.tet_output.empty()) check_output_file(o.tet_output, "--tet-output");
  w.tet_edge_mm = o.tet_edge_mm;
  w.burr_radius_mm = o.burr_radius_mm;
  w.shaft_radius_mm = o.shaft_radius_mm;
  w.drill_max_s = o.drill_max_s;
  w.drill_path = o.drill_path;
  w.drill_report = o.drill_report;
  w.drill_replay = o.drill_replay;
  w.drill_udp_port = o.drill_udp_port;
  if (!o.drill_path.empty()) check_output_file(o.drill_path, "--drill-path");
  if (!o.drill_report.empty()) check_output_file(o.drill_report, "--drill-report");
  w.deform_log = o.deform_log;
  if (!o.deform_log.empty()) check_output_file(o.deform_log, "--deform-log");
  if (!o.roi.empty()) w.roi_mm = parse_roi(o.roi);
  w.max_radius_mm = o.max_radius_mm;
  w.snapshot = o.snapshot;
  if (!o.snapshot.empty()) {
    if (std::filesystem::path(o.snapshot).extension() != ".png")
      throw InvalidInput(fmt::format("--snapshot {}: the picture is written as PNG: name a .png file", o.snapshot));
    check_output_file(o.snapshot, "--snapshot");
    if (!o.script.empty() || !o.record.empty())
      throw InvalidInput("--snapshot renders one picture without a window: it does not take --script or --record");
  }
  w.quiet = g.quiet;
  (void)view::run_workbench(w);
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand("view", "Interactive workbench: segment a CT live, tetrahedralise and clip, drill by hand, look at surfaces and scenes");
  auto opts = std::make_shared<ViewCliOptions>();
  sub->add_option("FILE", opts->files,
                  "files to open: a CT volume (.nii .nii.gz .mha .nrrd ...), surfaces (.stl .ply .obj .vtp), "
                  "tetrahedral meshes (.vtu .msh .node), scenes (.json)");
  sub->add_option("--script", opts->script,
                  "replay the input events of EVENTS.json (docs/viewer.md), then close the window");
  sub->add_option("--screenshots", opts->screenshots, "folder for the script's screenshots (PNG)");
  sub->add_option("--record", opts->record, "write the session's input events to EVENTS.json when the window closes");
  sub->add_option("--frames", opts->frames, "close after this many frames (0: no limit)");
  sub->add_option("--size", opts->size, "window size WIDTHxHEIGHT in pixels; default 1280x800 (a script's own size wins)");
  sub->add_option("--organ", opts->organ, "first organ choice of the Segment workspace: generic, artery, vein, vertebra");
  sub->add_option("--seed-voxel", opts->seed_voxels, "seed voxel I,J,K placed at start; repeatable");
  sub->add_option("--stop-voxel", opts->stop_voxels,
                  "stop point voxel I,J,K placed at start (the balloon's front does not pass it); repeatable");
  sub->add_option("--surface", opts->surface, "where Save (ctrl+s) writes the segmented surface (.stl .ply .obj .vtp)");
  sub->add_option("--mask", opts->mask, "where Save writes the mask (a volume file)");
  sub->add_option("--report", opts->report, "where Save writes the report (JSON, as ido segment --report)");
  sub->add_option("--tet-output", opts->tet_output,
                  "where Save (ctrl+s) in the Mesh workspace writes the tetrahedra (.vtu .msh .node)");
  sub->add_option("--tet-edge", opts->tet_edge_mm,
                  "the Mesh workspace's lattice spacing (mm); 0 (default) = the surface's mean edge, as ido tetmesh");
  sub->add_option("--burr-radius", opts->burr_radius_mm, "the Drill workspace's spherical burr radius (mm); default 2");
  sub->add_option("--shaft-radius", opts->shaft_radius_mm,
                  "the burr's shaft radius (mm; 0, the default: none), as ido drill --tool sphere:radius=R,shaft=S");
  sub->add_option("--drill-max", opts->drill_max_s, "longest drilling session (s); default 60");
  sub->add_option("--drill-path", opts->drill_path,
                  "write each drilling session's path here when it ends (CSV t,x,y,z that ido drill --path replays)");
  sub->add_option("--drill-report", opts->drill_report,
                  "write each drilling session's figures here when it ends (JSON: removed volume, timing percentiles)");
  sub->add_option("--drill-replay", opts->drill_replay,
                  "a path CSV (t,x,y,z as ido drill --path reads) the Drill workspace replays with p");
  sub->add_option("--drill-udp", opts->drill_udp_port,
                  "UDP port on 127.0.0.1 where the Drill workspace's device bridge listens (u); 0 (default) = any free port");
  sub->add_option("--deform-log", opts->deform_log,
                  "write the pulled particle's positions, time and momentum per shown step to this JSON on exit");
  sub->add_option("--roi", opts->roi,
                  "the Segment workspace's first region of interest x0,y0,z0,x1,y1,z1 (world mm), as ido segment --roi; "
                  "ctrl+drag on a slice draws one");
  sub->add_option("--max-radius", opts->max_radius_mm,
                  "the Segment workspace's first bound on the organ's local radius (mm): where a wider ball fits, the "
                  "front does not go");
  sub->add_option("--snapshot", opts->snapshot,
                  "no window: render one picture of what was opened (seeds grown first) off-screen, without a display, "
                  "to this PNG and exit");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"view", 95, setup});

}  // namespace
}  // namespace ido::cli

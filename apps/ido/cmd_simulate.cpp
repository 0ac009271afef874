// SPDX-License-Identifier: Apache-2.0
// `ido simulate SCENE.json -o OUTDIR [--snapshots DIR [--snapshot-every FRAMES]
//  [--snapshot-field von_mises|displacement] [--snapshot-size WxH]]`: runs a JSON scene
// (docs/scene.md) and writes VTU frames with a .pvd index, energy.csv, energy.png,
// report.json and, on request, pictures of the deforming bodies, drawn from the frames the run
// hands over in memory.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "command.h"
#include "energy_plot.h"
#include "ido/core/error.h"
#include "ido/geometry/aabb.h"
#include "ido/io/scene.h"
#include "ido/viz/renderer.h"
#include "snapshots.h"

namespace ido::cli {
namespace {

struct Options {
  std::string scene;
  std::string out_dir;
  std::string snapshots;
  int snapshot_every = 1;
  std::string snapshot_field = "von_mises";
  std::string snapshot_size = "800x600";
};

/// The per-tetrahedron value pictured: von Mises stress (Pa) as run_scene writes it, or the
/// mean displacement magnitude (mm) of the tetrahedron's four vertices.
std::vector<double> picture_values(const geometry::TetMesh& frame, const std::string& field) {
  if (field == "von_mises") {
    const auto it = frame.cell_fields.find("von_mises_pa");
    if (it == frame.cell_fields.end() || it->second.count() != frame.tet_count())
      throw Error("snapshots: the frame has no von_mises_pa cell field of one value per tetrahedron");
    std::vector<double> out(frame.tet_count());
    for (std::size_t t = 0; t < out.size(); ++t)
      out[t] = it->second.values[t * static_cast<std::size_t>(it->second.components)];
    return out;
  }
  const auto it = frame.point_fields.find("displacement_mm");
  if (it == frame.point_fields.end() || it->second.components != 3 || it->second.count() != frame.vertex_count())
    throw Error("snapshots: the frame has no displacement_mm point field of 3 values per vertex");
  const auto& d = it->second.values;
  std::vector<double> out(frame.tet_count(), 0.0);
  for (std::size_t t = 0; t < out.size(); ++t) {
    for (const auto v : frame.tets[t]) {
      const std::size_t i = 3 * static_cast<std::size_t>(v);
      out[t] += 0.25 * std::sqrt(d[i] * d[i] + d[i + 1] * d[i + 1] + d[i + 2] * d[i + 2]);
    }
  }
  return out;
}

/// The frames to picture, kept in memory as run_scene hands them over (io::SceneFrameListener):
/// frame indices 0, every, 2·every, … and the last (which is known only when the run ends, so
/// the latest frame is always kept).
class SnapshotFrames {
 public:
  explicit SnapshotFrames(const Options& o) : m_every(o.snapshot_every), m_field(o.snapshot_field) {}

  void add(std::int64_t index, const geometry::TetMesh& mesh) {
    if (m_tets.empty()) m_tets = mesh.tets;
    Kept k{index, mesh.vertices, picture_values(mesh, m_field)};
    if (index % m_every == 0) m_picked.push_back(std::move(k));
    else m_latest = std::move(k);
  }

  /// The pictured frames in order, once the run has ended.
  struct Kept {
    std::int64_t index = 0;
    std::vector<Vec3> vertices;   ///< mm
    std::vector<double> values;   ///< one per tetrahedron
  };
  [[nodiscard]] std::vector<Kept> finish() {
    std::vector<Kept> out = std::move(m_picked);
    if (m_latest && (out.empty() || m_latest->index > out.back().index)) out.push_back(std::move(*m_latest));
    return out;
  }
  [[nodiscard]] const std::vector<Tet>& tets() const { return m_tets; }

 private:
  std::int64_t m_every;
  std::string m_field;
  std::vector<Tet> m_tets;
  std::vector<Kept> m_picked;
  std::optional<Kept> m_latest;
};

/// Pictures of the kept frames. The camera frames the union of all pictured frames' bounding
/// boxes and the colour range is the min..max of the value over all of them, so the pictures
/// compare.
nlohmann::json write_snapshots(const Options& o, SnapshotFrames& frames, Progress* progress) {
  const auto [w, h] = parse_picture_size(o.snapshot_size, "--snapshot-size");
  SnapshotWriter writer(o.snapshots, {.width_px = w, .height_px = h, .azimuth_deg = 20.0, .elevation_deg = 15.0});
  const auto picked = frames.finish();
  // Pass 1: bounds and value range over the whole run.
  geometry::Aabb box;
  double vmin = std::numeric_limits<double>::infinity(), vmax = -vmin;
  for (const auto& f : picked) {
    for (const Vec3& p : f.vertices) box.extend(p);
    for (const double v : f.values) {
      vmin = std::min(vmin, v);
      vmax = std::max(vmax, v);
    }
  }
  const Vec3 &lo = box.min, &hi = box.max;
  if (box.empty()) throw Error("snapshots: the scene's frames have no vertices");
  if (!(vmax > vmin)) vmax = vmin + std::max(1e-12, std::abs(vmin) * 1e-6);
  writer.frame(lo, hi);
  // Pass 2: the pictures.
  const std::string cell_name = "snapshot_value";
  for (std::size_t k = 0; k < picked.size(); ++k) {
    check_cancel(progress);
    geometry::TetMesh mesh;
    mesh.vertices = picked[k].vertices;
    mesh.tets = frames.tets();
    mesh.cell_fields[cell_name] = geometry::Field{1, picked[k].values};
    viz::Renderer ren(w, h);
    viz::ClipPlane keep_all;  // a plane beyond the union box clips nothing
    keep_all.normal = Vec3(1, 0, 0);
    keep_all.point = Vec3(hi.x() + 1.0, 0, 0);
    ren.add_tet_mesh_clipped(mesh, keep_all, cell_name,
                             {.colormap = viz::Colormap::Viridis, .range_min = vmin, .range_max = vmax});
    writer.write(ren);
    report(progress, double(k + 1) / double(picked.size()), "snapshots");
  }
  nlohmann::json frames_json = nlohmann::json::array();
  for (const auto& f : picked) frames_json.push_back(f.index);
  return {{"snapshots", writer.files_json()},
          {"snapshot_frames", frames_json},
          {"snapshot_field", o.snapshot_field == "von_mises" ? "von_mises_pa" : "displacement_magnitude_mm"},
          {"snapshot_range", {vmin, vmax}}};
}

void run(const Options& o, const GlobalOptions& g) {
  if (!o.snapshots.empty()) {
    // Check the picture options before the (long) run.
    if (o.snapshot_every < 1) throw InvalidInput(fmt::format("--snapshot-every must be >= 1, got {}", o.snapshot_every));
    if (o.snapshot_field != "von_mises" && o.snapshot_field != "displacement")
      throw InvalidInput(fmt::format("--snapshot-field must be von_mises or displacement, got '{}'", o.snapshot_field));
    (void)parse_picture_size(o.snapshot_size, "--snapshot-size");
    SnapshotWriter check(o.snapshots);  // folder usable (throws naming --snapshots)
  }
  auto scene = io::load_scene(o.scene);
  auto progress = make_progress(g.quiet);
  // Every output of the run (frames, index, energies, plot, report) is written, or none.
  const std::filesystem::path out_dir(o.out_dir);
  std::error_code ec;
  const bool made_folder = !std::filesystem::exists(out_dir, ec);
  FileBatch outputs;
  std::size_t pictures = 0;
  io::SceneRunResult result;
  try {
    // The pictures are drawn from the frames as the run hands them over, not read back.
    SnapshotFrames frames(o);
    io::SceneFrameListener keep;
    if (!o.snapshots.empty()) keep = [&frames](std::int64_t index, const geometry::TetMesh& mesh) { frames.add(index, mesh); };
    result = io::run_scene(scene, out_dir, progress.get(), &outputs, {}, keep);
    write_energy_plot(outputs.stage(out_dir / "energy.png"), result);
    if (!o.snapshots.empty()) {
      const nlohmann::json snap = write_snapshots(o, frames, progress.get());
      pictures = snap["snapshots"].size();
      // run_scene staged report.json: stage it again with the pictures added.
      nlohmann::json report_json = io::scene_report(scene, result);
      report_json.update(snap);
      write_text_file(outputs.staged(out_dir / "report.json").string(), report_json.dump(2) + "\n");
    }
    outputs.commit();
  } catch (...) {
    outputs.discard();
    if (made_folder) std::filesystem::remove(out_dir, ec);  // only if empty
    throw;
  }
  if (!g.quiet) {
    std::printf("simulated %lld steps in %.3f s, %lld frames written to %s\n",
                static_cast<long long>(scene.steps), result.wall_time_s,
                static_cast<long long>(result.frames), o.out_dir.c_str());
    if (pictures > 0) std::printf("%zu snapshots written to %s\n", pictures, o.snapshots.c_str());
  }
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand("simulate", "Run a deformable-body scene (JSON) and write VTU frames, energies and a report");
  auto opts = std::make_shared<Options>();
  sub->add_option("SCENE", opts->scene, "Scene file (.json), see docs/scene.md")->required();
  sub->add_option("-o,--output", opts->out_dir, "Output folder (created if missing)")->required();
  sub->add_option("--snapshots", opts->snapshots,
                  "Folder for pictures of the deforming bodies (snapshot_NNNN.png, one fixed camera and "
                  "colour range for the whole run); earlier snapshot_NNNN.png files there are replaced");
  sub->add_option("--snapshot-every", opts->snapshot_every, "Picture every this many output frames (and the last); default 1");
  sub->add_option("--snapshot-field", opts->snapshot_field,
                  "Colour by von_mises (stress, Pa) or displacement (magnitude, mm); default von_mises");
  sub->add_option("--snapshot-size", opts->snapshot_size, "Picture size WIDTHxHEIGHT in pixels; default 800x600");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"simulate", 50, setup});

}  // namespace
}  // namespace ido::cli

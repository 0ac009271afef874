// SPDX-License-Identifier: Apache-2.0
// `ido simulate SCENE.json -o OUTDIR`: runs a JSON scene (docs/scene.md) and writes VTU
// frames with a .pvd index, energy.csv, energy.png and report.json.
#include <cstdio>
#include <memory>
#include <string>

#include "cli_util.h"
#include "command.h"
#include "ido/io/scene.h"
#include "ido/viz/plot.h"

namespace ido::cli {
namespace {

struct Options {
  std::string scene;
  std::string out_dir;
};

void run(const Options& o, const GlobalOptions& g) {
  auto scene = io::load_scene(o.scene);
  auto progress = make_progress(g.quiet);
  const auto result = io::run_scene(scene, o.out_dir, progress.get());
  const std::vector<viz::PlotSeries> series = {
      {"kinetic", result.time_s, result.kinetic_mj, {}},
      {"elastic", result.time_s, result.elastic_mj, {}},
      {"gravitational", result.time_s, result.gravitational_mj, {}},
      {"total", result.time_s, result.total_mj, {}},
  };
  viz::write_line_plot(std::filesystem::path(o.out_dir) / "energy.png", series,
                       {.width_px = 900, .height_px = 540, .title = "Energy",
                        .x_label = "time (s)", .y_label = "energy (mJ)"});
  if (!g.quiet)
    std::printf("simulated %lld steps in %.3f s, %lld frames written to %s\n",
                static_cast<long long>(scene.steps), result.wall_time_s,
                static_cast<long long>(result.frames), o.out_dir.c_str());
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand("simulate", "Run a deformable-body scene (JSON) and write VTU frames, energies and a report");
  auto opts = std::make_shared<Options>();
  sub->add_option("SCENE", opts->scene, "Scene file (.json), see docs/scene.md")->required();
  sub->add_option("-o,--output", opts->out_dir, "Output folder (created if missing)")->required();
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"simulate", 50, setup});

}  // namespace
}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
#include "energy_plot.h"

#include <vector>

#include "ido/viz/plot.h"

namespace ido::cli {

namespace {

std::vector<double> change_since_start(const std::vector<double>& v) {
  std::vector<double> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = v[i] - v.front();
  return out;
}

}  // namespace

void write_energy_plot(const std::filesystem::path& path, const io::SceneRunResult& result) {
  const std::vector<viz::PlotSeries> series = {
      {"kinetic", result.time_s, result.kinetic_mj, {}},
      {"elastic", result.time_s, result.elastic_mj, {}},
      {"gravitational change", result.time_s, change_since_start(result.gravitational_mj), {}},
      {"total change", result.time_s, change_since_start(result.total_mj), {}},
  };
  viz::write_line_plot(path, series,
                       {.width_px = 900, .height_px = 540, .title = "Energy",
                        .x_label = "time (s)", .y_label = "energy (mJ)"});
}

}  // namespace ido::cli

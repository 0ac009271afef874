// SPDX-License-Identifier: Apache-2.0
// `ido phantom KIND -o CT.nii.gz [--labels TRUTH.nii.gz] ...`: writes a synthetic CT volume
// (HU) and its ground-truth labels, and prints the seed(s) to start `ido segment` from.
// Presentation only: the phantom comes from ido::segment::make_phantom.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <new>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "command.h"
#include "ido/core/error.h"
#include "ido/io/memory_budget.h"
#include "ido/io/volume_io.h"
#include "ido/segment/phantom.h"

namespace ido::cli {
namespace {

struct PhantomCliOptions {
  std::string kind;
  std::string output;
  std::string labels;
  double noise_hu = 0.0;
  double noise_fraction = -1.0;
  double blur_voxels = 0.0;
  std::string spacing = "1,1,1";
  std::uint64_t seed = 1;
  bool json_seeds = false;
  std::string drill_path;
  double drill_speed_mm_s = 4.0;
};

/// Refuses a --spacing whose grid would not fit the memory budget (ido --memory-limit) before
/// anything is allocated. The kind's extent is read off a probe build at 2-mm voxels (one
/// sample each, no noise: at most about 130 000 voxels, a few milliseconds), whose grid has
/// max(2, round(extent / 2 mm)) voxels along an axis; the grid at @p spacing_mm is counted
/// from the smallest extent that allows, so a phantom that fits is never refused. A spacing
/// make_phantom refuses anyway (not in (0, 10] mm) is left to it.
void check_phantom_grid(segment::PhantomKind kind, const Vec3& spacing_mm, const std::string& spacing_text) {
  constexpr double kProbeMm = 2.0, kMaxSpacingMm = 10.0;
  if (!((spacing_mm.array() > 0.0).all() && (spacing_mm.array() <= kMaxSpacingMm).all())) return;
  segment::PhantomOptions probe_options;
  probe_options.spacing_mm = Vec3::Constant(kProbeMm);
  probe_options.supersampling = 1;
  probe_options.threaded = false;
  const segment::Phantom probe = segment::make_phantom(kind, probe_options);
  std::array<std::uint64_t, 3> n{};
  for (int a = 0; a < 3; ++a) {
    const double probe_voxels = static_cast<double>(probe.ct_hu.size(a));
    const double extent_mm = probe_voxels > 2 ? kProbeMm * (probe_voxels - 0.5) : 0.0;
    const double count = std::max(2.0, std::round(extent_mm / spacing_mm[a]));
    n[static_cast<std::size_t>(a)] = count >= 1e18 ? std::uint64_t(1e18) : static_cast<std::uint64_t>(count);
  }
  // The CT (float) and label (byte) volumes.
  const std::uint64_t bytes = io::saturating_product({n[0], n[1], n[2], sizeof(float) + sizeof(std::uint8_t)});
  if (bytes > io::memory_limit_bytes())
    throw InvalidInput(fmt::format("--spacing {}: the {} phantom's grid of at least {} x {} x {} voxels needs {}, over "
                                   "the memory limit of {} (ido --memory-limit)",
                                   spacing_text, segment::phantom_kind_name(kind), n[0], n[1], n[2],
                                   io::format_bytes(bytes), io::format_bytes(io::memory_limit_bytes())));
}

void run(const PhantomCliOptions& o) {
  const auto kind = segment::parse_phantom_kind(o.kind);
  if (!io::looks_like_volume(o.output) || std::filesystem::is_directory(o.output))
    throw InvalidInput(fmt::format("{}: the CT output must be a volume file (.nii, .nii.gz, .nrrd, .mha)", o.output));
  if (!o.labels.empty() && !io::looks_like_volume(o.labels))
    throw InvalidInput(fmt::format("{}: the labels output must be a volume file (.nii, .nii.gz, .nrrd, .mha)", o.labels));
  if (o.noise_fraction >= 0.0 && o.noise_hu > 0.0)
    throw InvalidInput("give either --noise or --noise-fraction, not both");
  // The outputs are checked before the work and written all or none.
  OutputBatch outputs;
  const std::string ct_file = outputs.stage(o.output, "-o");
  const std::string labels_file = o.labels.empty() ? std::string() : outputs.stage(o.labels, "--labels");
  const std::string path_file = o.drill_path.empty() ? std::string() : outputs.stage(o.drill_path, "--drill-path");
  segment::PhantomOptions po;
  po.spacing_mm = parse_vec3(o.spacing, "--spacing");
  check_phantom_grid(kind, po.spacing_mm, o.spacing);
  po.blur_voxels = o.blur_voxels;
  po.seed = o.seed;
  po.noise_hu = o.noise_hu;
  if (o.noise_fraction >= 0.0) {
    // The contrast is known only once the kind's intensities are chosen: build noise-free
    // first to read it (cheap), then with the requested noise.
    po.noise_hu = 0.0;
    po.noise_hu = o.noise_fraction * segment::make_phantom(kind, po).contrast_hu;
  }
  if (!o.drill_path.empty() && !(o.drill_speed_mm_s > 0.0))
    throw InvalidInput("--drill-speed must be positive");
  const segment::Phantom ph = [&] {
    try {
      return segment::make_phantom(kind, po);
    } catch (const std::bad_alloc&) {
      // A grid just under the budget that still did not fit beside the rest of the process.
      throw InvalidInput(fmt::format("--spacing {}: the {} phantom's grid does not fit in memory", o.spacing,
                                     segment::phantom_kind_name(kind)));
    }
  }();
  if (!o.drill_path.empty() && ph.drill_path_mm.empty())
    throw InvalidInput(fmt::format("--drill-path: the {} phantom has no bone to drill", o.kind));
  io::write_volume(ct_file, ph.ct_hu);
  if (!o.labels.empty()) io::write_volume(labels_file, ph.labels);
  if (!o.drill_path.empty()) {
    // A scripted tool trajectory (ido drill's CSV: t, x, y, z) along the phantom's drill
    // polyline at a constant speed.
    std::string csv = "t_s,x_mm,y_mm,z_mm\n";
    double t = 0.0;
    for (std::size_t i = 0; i < ph.drill_path_mm.size(); ++i) {
      if (i > 0) t += (ph.drill_path_mm[i] - ph.drill_path_mm[i - 1]).norm() / o.drill_speed_mm_s;
      const Vec3& p = ph.drill_path_mm[i];
      csv += fmt::format("{:.6f},{:.6f},{:.6f},{:.6f}\n", t, p.x(), p.y(), p.z());
    }
    write_text_file(path_file, csv);
  }
  outputs.commit();

  if (o.json_seeds) {
    nlohmann::json seeds = nlohmann::json::array();
    for (std::size_t s = 0; s < ph.seeds_mm.size(); ++s)
      seeds.push_back({{"label", ph.seed_labels[s]},
                       {"world_mm", {ph.seeds_mm[s].x(), ph.seeds_mm[s].y(), ph.seeds_mm[s].z()}},
                       {"voxel", {ph.seeds_voxel[s][0], ph.seeds_voxel[s][1], ph.seeds_voxel[s][2]}}});
    const nlohmann::json j = {{"kind", std::string(segment::phantom_kind_name(kind))},
                              {"description", ph.description},
                              {"ct", o.output},
                              {"labels", o.labels.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.labels)},
                              {"size", {ph.ct_hu.size(0), ph.ct_hu.size(1), ph.ct_hu.size(2)}},
                              {"spacing_mm", {po.spacing_mm.x(), po.spacing_mm.y(), po.spacing_mm.z()}},
                              {"noise_hu", po.noise_hu},
                              {"blur_voxels", po.blur_voxels},
                              {"seed", po.seed},
                              {"object_hu", ph.object_hu},
                              {"background_hu", ph.background_hu},
                              {"contrast_hu", ph.contrast_hu},
                              {"truth_euler_characteristic", ph.truth_euler_characteristic},
                              {"seeds", seeds}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("%s\n", ph.description.c_str());
  std::printf("grid %lld x %lld x %lld, spacing %g,%g,%g mm, noise %g HU, blur %g voxels, contrast %g HU\n",
              static_cast<long long>(ph.ct_hu.size(0)), static_cast<long long>(ph.ct_hu.size(1)),
              static_cast<long long>(ph.ct_hu.size(2)), po.spacing_mm.x(), po.spacing_mm.y(), po.spacing_mm.z(),
              po.noise_hu, po.blur_voxels, ph.contrast_hu);
  std::printf("truth Euler characteristic %d\n", ph.truth_euler_characteristic);
  for (std::size_t s = 0; s < ph.seeds_mm.size(); ++s)
    std::printf("seed %zu (label %d): --seed %g,%g,%g  (or --seed-voxel %lld,%lld,%lld)\n", s + 1, ph.seed_labels[s], ph.seeds_mm[s].x(), ph.seeds_mm[s].y(), ph.seeds_mm[s].z(), static_cast<long long>(ph.seeds_voxel[s][0]),
                static_cast<long long>(ph.seeds_voxel[s][1]), static_cast<long long>(ph.seeds_voxel[s][2]));
}

void setup(CLI::App& app, const GlobalOptions& /*g*/) {
  auto* sub = app.add_subcommand("phantom", "Write a synthetic CT volume (HU) with ground-truth labels");
  auto opts = std::make_shared<PhantomCliOptions>();
  sub->add_option("KIND", opts->kind,
                  "sphere, torus, y-bifurcation, u-tube, vessel-near-bone, vessel-tree, vertebra, spine-aorta, calcified-vessel; "
                  "leak phantoms (label 1 = the intended organ only): valve-chamber (vessel into a chamber of the same "
                  "grey level), vein-in-parenchyma (vein in a liver 15 HU darker), vertebra-stack (middle of three "
                  "touching vertebrae), lung-seed (airway into air-filled lung)")
      ->required();
  sub->add_option("-o,--output", opts->output, "CT volume to write (.nii.gz, .nrrd, .mha)")->required();
  sub->add_option("--labels", opts->labels, "Ground-truth label volume to write (1 = object; spine-aorta: 1 aorta, 2 vertebra; calcified-vessel: 1 vessel with plaque, 2 bone; vertebra-stack: 1 the middle vertebra)");
  sub->add_option("--noise", opts->noise_hu, "Gaussian noise sigma (HU)");
  sub->add_option("--noise-fraction", opts->noise_fraction, "Noise sigma as a fraction of the contrast (e.g. 0.2)");
  sub->add_option("--blur", opts->blur_voxels, "Gaussian blur sigma (voxels)");
  sub->add_option("--spacing", opts->spacing, "Voxel size SX,SY,SZ in mm (default 1,1,1)");
  sub->add_option("--seed", opts->seed, "Noise seed (same seed, same volume)");
  sub->add_option("--drill-path", opts->drill_path, "Also write the phantom's drill trajectory (CSV t,x,y,z) here");
  sub->add_option("--drill-speed", opts->drill_speed_mm_s, "Tool speed along the drill path (mm/s, default 4)");
  sub->add_flag("--json-seeds", opts->json_seeds, "Print the seeds and phantom facts as JSON");
  sub->callback([opts] { run(*opts); });
}

const bool kRegistered = register_command({"phantom", 30, setup});

}  // namespace
}  // namespace ido::cli

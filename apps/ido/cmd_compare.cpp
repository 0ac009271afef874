// SPDX-License-Identifier: Apache-2.0
// `ido compare --mask A --truth B [--json]` and `ido compare --mesh S --truth B`: Dice,
// HD95, ASSD, volume ratio and components (definitions in docs/metrics.md). Presentation
// only: the scores come from ido::segment.
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include <fmt/format.h>
#include "command.h"
#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "ido/io/report_json.h"
#include "ido/io/volume_io.h"
#include "ido/segment/metrics.h"

namespace ido::cli {
namespace {

struct CompareOptions {
  std::string mask;
  std::string mesh;
  std::string truth;
  int label = -1;
  std::optional<double> truth_below;  // truth is a level set: inside where value < this
  bool json = false;
};

/// Reads a volume as a mask: voxels whose value passes @p inside are 1.
template <class Inside>
image::Volume<std::uint8_t> read_mask_where(const std::string& path, Inside inside) {
  const auto v = io::read_volume(path);
  auto m = v.like<std::uint8_t>(0);
  for (std::size_t n = 0; n < v.data().size(); ++n) m.data()[n] = inside(v.data()[n]);
  return m;
}

/// Reads a label volume: voxels equal to @p label (or ≠ 0 when label < 0) are inside.
image::Volume<std::uint8_t> read_mask(const std::string& path, int label) {
  return read_mask_where(path, [label](float x) { return label < 0 ? x != 0.f : x == float(label); });
}

/// Reads a level-set or distance volume: voxels with a value below @p level are inside.
image::Volume<std::uint8_t> read_level_set_mask(const std::string& path, double level) {
  return read_mask_where(path, [level](float x) { return static_cast<double>(x) < level; });
}


void run(const CompareOptions& o) {
  if (o.mask.empty() == o.mesh.empty()) throw InvalidInput("give exactly one of --mask and --mesh");
  if (o.truth_below && !std::isfinite(*o.truth_below))
    throw InvalidInput(fmt::format("--truth-below must be a finite number, got {}", *o.truth_below));
  const auto truth = o.truth_below ? read_level_set_mask(o.truth, *o.truth_below) : read_mask(o.truth, o.label);
  // The mesh's own problems (an open surface) are named with its file.
  auto mesh_scores = [&] {
    const geometry::TriangleMesh mesh = io::read_triangle_mesh(o.mesh);
    try {
      return segment::compare_mesh_to_mask(mesh, truth);
    } catch (const InvalidInput& e) {
      throw InvalidInput(fmt::format("{}: {}", o.mesh, e.what()));
    }
  };
  const segment::SegmentationScores s =
      o.mask.empty() ? mesh_scores() : segment::compare_masks(read_mask(o.mask, o.label), truth);
  if (o.json) {
    io::Json j = {{"mask", o.mask.empty() ? io::Json(nullptr) : io::Json(o.mask)},
                  {"mesh", o.mesh.empty() ? io::Json(nullptr) : io::Json(o.mesh)},
                  {"truth", o.truth}};
    j.update(io::to_json(s));
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("Dice            %.4f\n", s.dice);
  std::printf("HD95            %.3f mm\n", s.hd95_mm);
  std::printf("ASSD            %.3f mm\n", s.assd_mm);
  std::printf("Hausdorff       %.3f mm\n", s.hd_mm);
  std::printf("volume ratio    %.4f  (%.1f / %.1f mm^3)\n", s.volume_ratio, s.volume_mask_mm3, s.volume_truth_mm3);
  std::printf("components      %d (%s), %d (truth)\n", s.components_mask, o.mask.empty() ? "mesh" : "mask",
              s.components_truth);
  if (s.resampled) std::printf("note: the mask was resampled onto the truth's grid (nearest neighbour)\n");
}

void setup(CLI::App& app, const GlobalOptions& /*g*/) {
  auto* sub = app.add_subcommand("compare", "Score a segmentation (mask or closed mesh) against a truth mask");
  auto opts = std::make_shared<CompareOptions>();
  sub->add_option("--mask", opts->mask, "Segmentation mask volume (voxels != 0 inside)");
  sub->add_option("--mesh", opts->mesh, "Closed surface (.stl, .ply, .obj, .vtp) to rasterise on the truth grid");
  sub->add_option("--truth", opts->truth, "Ground-truth mask volume")->required();
  sub->add_option("--label", opts->label, "Only voxels equal to this value are inside (both volumes)");
  sub->add_option("--truth-below", opts->truth_below,
                  "The truth is a level set or distance map: inside where its value is below this (e.g. 0 for "
                  "VMTK's level sets); --label then applies to the mask only");
  sub->add_flag("--json", opts->json, "Print the scores as JSON");
  sub->callback([opts] { run(*opts); });
}

const bool kRegistered = register_command({"compare", 32, setup});

}  // namespace
}  // namespace ido::cli

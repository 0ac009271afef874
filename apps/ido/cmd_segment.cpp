// SPDX-License-Identifier: Apache-2.0
// `ido segment CT --seed X,Y,Z | --seed-voxel I,J,K [--reference HU --tolerance HU]
//  [--roi x0,y0,z0,x1,y1,z1] -o SURFACE [--mask MASK] [--report R.json]`: balloon
// segmentation. Presentation only: the method is ido::segment::Balloon.
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "command.h"
#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "ido/segment/balloon.h"

namespace ido::cli {
namespace {

struct SegmentCliOptions {
  std::string input;
  std::vector<std::string> seeds;
  std::vector<std::string> seed_voxels;
  std::optional<double> reference;
  std::optional<double> tolerance;
  std::string roi;
  std::string output;
  std::string mask;
  std::string report;
  bool bone = false;
  int max_iterations = 4000;
};

std::array<Vec3, 2> parse_roi(const std::string& text) {
  std::vector<double> v;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    try {
      std::size_t used = 0;
      v.push_back(std::stod(part, &used));
      if (used != part.size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw InvalidInput(fmt::format("--roi: '{}' is not a number (expected x0,y0,z0,x1,y1,z1 in mm)", part));
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 6) throw InvalidInput(fmt::format("--roi: expected 6 numbers x0,y0,z0,x1,y1,z1 (mm), got {}", v.size()));
  const Vec3 a(v[0], v[1], v[2]), b(v[3], v[4], v[5]);
  if ((a.array() >= b.array()).any()) throw InvalidInput("--roi: each minimum must be below its maximum");
  return {a, b};
}

void run(const SegmentCliOptions& o, const GlobalOptions& g) {
  if (o.seeds.empty() && o.seed_voxels.empty()) throw InvalidInput("give at least one --seed X,Y,Z or --seed-voxel I,J,K");
  if (o.reference.has_value() != o.tolerance.has_value())
    throw InvalidInput("give --reference and --tolerance together (or neither, to estimate both at the seeds)");
  if (o.tolerance && !(*o.tolerance > 0)) throw InvalidInput("--tolerance must be positive");
  const std::string ext = std::filesystem::path(o.output).extension().string();
  if (ext != ".stl" && ext != ".ply" && ext != ".obj" && ext != ".vtp")
    throw InvalidInput(fmt::format("{}: the surface output must be .stl, .ply, .obj or .vtp", o.output));
  if (!o.mask.empty() && !io::looks_like_volume(o.mask))
    throw InvalidInput(fmt::format("{}: the mask output must be a volume file (.nii, .nii.gz, .nrrd, .mha)", o.mask));
  const image::Volume<float> ct = io::read_volume(o.input);
  std::vector<Vec3> seeds;
  for (const auto& s : o.seeds) seeds.push_back(parse_vec3(s, "--seed"));
  for (const auto& s : o.seed_voxels) {
    const Index3 idx = parse_index3(s, "--seed-voxel");
    if (!ct.contains(idx[0], idx[1], idx[2]))
      throw InvalidInput(fmt::format("--seed-voxel {}: outside the {}x{}x{} volume", s, ct.size(0), ct.size(1), ct.size(2)));
    seeds.push_back(ct.index_to_world(Vec3(double(idx[0]), double(idx[1]), double(idx[2]))));
  }
  segment::BalloonOptions bo;
  bo.reference = o.reference;
  bo.tolerance = o.tolerance;
  bo.accept_brighter = o.bone;
  bo.max_iterations = o.max_iterations;
  if (!o.roi.empty()) bo.roi_mm = parse_roi(o.roi);
  auto progress = make_progress(g.quiet);
  const segment::BalloonResult r = segment::segment_balloon(ct, seeds, bo, progress.get());
  io::write_triangle_mesh(o.output, r.surface);
  if (!o.mask.empty()) io::write_volume(o.mask, segment::surface_to_mask(r.surface, ct));
  const segment::BalloonReport& rep = r.report;
  if (!o.report.empty()) {
    nlohmann::json seeds_json = nlohmann::json::array();
    for (const Vec3& s : seeds) seeds_json.push_back({s.x(), s.y(), s.z()});
    const nlohmann::json j = {
        {"input", o.input},
        {"seeds_mm", seeds_json},
        {"reference", rep.model.reference},
        {"tolerance", rep.model.tolerance},
        {"accept_brighter", rep.model.accept_brighter},
        {"iterations", rep.iterations},
        {"seconds", rep.seconds},
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
        {"frozen_vertices", rep.frozen_vertices},
        {"converged", rep.converged},
        {"stop_reason", rep.stop_reason},
        {"leak_warning", rep.leak_warning},
        {"surface", o.output},
        {"mask", o.mask.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.mask)}};
    write_text_file(o.report, j.dump(2) + "\n");
  }
  if (!g.quiet) {
    std::printf("reference %.1f, tolerance %.1f; %lld iterations, %.2f s (%s)\n", rep.model.reference, rep.model.tolerance,
                static_cast<long long>(rep.iterations), rep.seconds, rep.stop_reason.c_str());
    std::printf("surface: %lld vertices, %lld triangles, Euler %lld, volume %.1f mm3, area %.1f mm2, %s, %s, %lld self-intersections\n",
                static_cast<long long>(rep.vertices), static_cast<long long>(rep.triangles),
                static_cast<long long>(rep.euler_characteristic), rep.volume_mm3, rep.area_mm2,
                rep.closed ? "closed" : "OPEN", rep.manifold ? "manifold" : "NON-MANIFOLD",
                static_cast<long long>(rep.self_intersections));
    if (rep.leak_warning) std::printf("warning: the volume was still growing when a safeguard stopped it (leak?)\n");
  }
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand("segment", "Balloon segmentation from seed points: surface, mask and report");
  auto opts = std::make_shared<SegmentCliOptions>();
  sub->add_option("CT", opts->input, "CT volume (any supported format, or a DICOM folder)")->required();
  sub->add_option("--seed", opts->seeds, "seed point X,Y,Z in world mm (LPS); repeatable");
  sub->add_option("--seed-voxel", opts->seed_voxels, "seed voxel I,J,K; repeatable");
  sub->add_option("--reference", opts->reference, "organ grey level (e.g. HU); estimated at the seeds if omitted");
  sub->add_option("--tolerance", opts->tolerance, "accepted departure from the reference (same units)");
  sub->add_option("--roi", opts->roi, "region of interest x0,y0,z0,x1,y1,z1 (world mm), a safeguard");
  sub->add_flag("--bone", opts->bone, "anything brighter than the reference also belongs (bone)");
  sub->add_option("--max-iterations", opts->max_iterations, "safeguard on inflation steps");
  sub->add_option("-o,--output", opts->output, "surface file (.stl .ply .obj .vtp)")->required();
  sub->add_option("--mask", opts->mask, "binary mask on the input grid (1 inside)");
  sub->add_option("--report", opts->report, "JSON report");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"segment", 30, setup});

}  // namespace
}  // namespace ido::cli

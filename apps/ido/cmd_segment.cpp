// SPDX-License-Identifier: Apache-2.0
// `ido segment CT --seed X,Y,Z | --seed-voxel I,J,K [--reference HU --tolerance HU]
//  [--roi x0,y0,z0,x1,y1,z1] [--edge-reach VOXELS] -o SURFACE [--mask MASK] [--report R.json]
//  [--calcium HU [--calcium-reach MM]] [--snapshots DIR [--snapshot-every N] [--snapshot-size WxH]]`:
//  balloon segmentation.
// Presentation only: the method is ido::segment::Balloon.
#include <algorithm>
#include <cmath>
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
#include "ido/geometry/aabb.h"
#include "ido/image/index_box.h"
#include "ido/io/mesh_io.h"
#include "ido/io/report_json.h"
#include "ido/io/volume_io.h"
#include "ido/segment/balloon.h"
#include "ido/segment/calcification.h"
#include "ido/segment/organ.h"
#include "ido/view/segment_output.h"
#include "ido/viz/renderer.h"
#include "snapshots.h"

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
  std::string organ = "generic";
  bool white_noise = false;
  std::optional<double> calcium;
  double calcium_reach_mm = 4.0;
  int max_iterations = 4000;
  double edge_reach_voxels = 0.0;  // 0: no limit
  std::optional<double> outside_level;
  std::string snapshots;
  std::int64_t snapshot_every = 0;  // 0: chosen so that a run gives 15–30 pictures
  std::string snapshot_size = "1000x500";
};

/// A surface kept for a picture, after @p step balloon steps.
struct KeptSurface {
  std::int64_t step = 0;
  geometry::TriangleMesh surface;
};

/// The most pictures the automatic --snapshot-every keeps before thinning (then 15–30).
constexpr std::size_t kAutoMaxPictures = 30;
/// Upper bound on the pictures an explicit --snapshot-every may ask for (the surfaces are
/// kept in memory until the final surface fixes the camera).
constexpr std::int64_t kMaxPictures = 1000;

/// A balloon run with the surfaces kept on the way.
struct SteppedRun {
  segment::BalloonResult result;
  std::vector<KeptSurface> kept;
  std::int64_t inflation_steps = 0;  ///< Balloon::step() calls until it reported done
};

/// Runs the balloon step by step, keeping the surface every @p every steps (doubling
/// @p every whenever more than kAutoMaxPictures are kept, if @p adaptive), then finishes with
/// Balloon::run() (edge stage and final repair), which continues from the current state.
SteppedRun run_keeping_surfaces(segment::Balloon& balloon, std::int64_t every, bool adaptive, Progress* progress,
                                std::int64_t max_iterations) {
  SteppedRun out;
  auto& kept = out.kept;
  auto& inflation_steps = out.inflation_steps;
  bool done = false;
  while (!done) {
    done = balloon.step();
    ++inflation_steps;
    if (inflation_steps % every == 0) kept.push_back({inflation_steps, balloon.surface()});
    if (adaptive && kept.size() > kAutoMaxPictures) {
      every *= 2;
      std::erase_if(kept, [every](const KeptSurface& k) { return k.step % every != 0; });
    }
    if (inflation_steps % 50 == 0)
      report(progress, std::min(0.8, 0.8 * double(inflation_steps) / double(max_iterations)), "inflating");
  }
  out.result = balloon.run(progress);
  return out;
}

/// One picture: on the left the surface (3-D, camera @p camera), on the right the CT slice
/// @p slice (a one-voxel-thick sub-volume) with the surface's contour on it in red.
viz::Image segment_picture(const geometry::TriangleMesh& surface, const viz::Camera& camera,
                           const image::Volume<float>& slice, const viz::SliceOptions& window, int width,
                           int height) {
  const int left_w = width / 2;
  viz::Renderer left(left_w, height);
  left.add_surface(surface, Vec3(0.85, 0.55, 0.4));
  left.set_camera(camera);
  viz::Renderer right(width - left_w, height);
  right.add_slice(slice, 2, 0, window);
  right.add_contour(segment::surface_to_mask(surface, slice), 2, 0);
  right.set_camera(right.slice_camera(0));
  return side_by_side(left.render(), right.render());
}

/// The axial slice (index axis k) through @p seed of @p ct, cropped in i and j to the box
/// [lo, hi] (mm) with a margin, as a one-voxel-thick volume on the CT's grid.
image::Volume<float> seed_slice(const image::Volume<float>& ct, const Vec3& seed, const Vec3& lo, const Vec3& hi) {
  const Vec3 margin = 0.15 * (hi - lo) + 2.0 * ct.spacing().maxCoeff() * Vec3::Ones();
  const image::IndexBox crop = image::voxels_in_box(ct, geometry::Aabb{lo - margin, hi + margin});
  const std::int64_t i0 = crop.lo[0], i1 = crop.hi[0], j0 = crop.lo[1], j1 = crop.hi[1];
  const std::int64_t k = std::clamp<std::int64_t>(std::lround(ct.world_to_index(seed).z()), 0, ct.size(2) - 1);
  image::Volume<float> out({i1 - i0 + 1, j1 - j0 + 1, 1}, ct.spacing(),
                           ct.index_to_world(Vec3(double(i0), double(j0), double(k))), ct.direction());
  for (std::int64_t j = j0; j <= j1; ++j)
    for (std::int64_t i = i0; i <= i1; ++i) out(i - i0, j - j0, 0) = ct(i, j, k);
  return out;
}

void run(const SegmentCliOptions& o, const GlobalOptions& g) {
  if (o.seeds.empty() && o.seed_voxels.empty()) throw InvalidInput("give at least one --seed X,Y,Z or --seed-voxel I,J,K");
  const segment::Organ organ = parse_organ_option(o.organ, "--organ");
  segment::BalloonChoices choices;
  choices.organ = organ;
  choices.reference = o.reference;
  choices.tolerance = o.tolerance;
  choices.bone = o.bone;
  choices.white_noise = o.white_noise;
  choices.edge_reach_voxels = o.edge_reach_voxels;
  choices.outside_level = o.outside_level;
  choices.max_iterations = o.max_iterations;
  if (!o.roi.empty()) choices.roi_mm = parse_roi(o.roi);
  const segment::BalloonOptions bo = balloon_options_from_flags("--", choices);
  if (o.calcium && !std::isfinite(*o.calcium)) throw InvalidInput("--calcium must be a finite intensity");
  if (!(o.calcium_reach_mm > 0) || !std::isfinite(o.calcium_reach_mm))
    throw InvalidInput(fmt::format("--calcium-reach must be a positive length in mm, got {}", o.calcium_reach_mm));
  view::check_segment_outputs({o.output, o.mask, o.report});
  std::optional<SnapshotWriter> writer;
  if (!o.snapshots.empty()) {
    if (o.snapshot_every < 0) throw InvalidInput(fmt::format("--snapshot-every must be >= 1, got {}", o.snapshot_every));
    if (o.snapshot_every > 0 && o.max_iterations / o.snapshot_every > kMaxPictures)
      throw InvalidInput(fmt::format("--snapshot-every {} allows up to {} pictures with --max-iterations {}; at most {} "
                                     "(the surfaces stay in memory until the end): give a larger N",
                                     o.snapshot_every, o.max_iterations / o.snapshot_every, o.max_iterations,
                                     kMaxPictures));
    const auto [w, h] = parse_picture_size(o.snapshot_size, "--snapshot-size");
    if (w < 2) throw InvalidInput("--snapshot-size: the width must be at least 2 pixels (two panels)");
    writer.emplace(o.snapshots, SnapshotOptions{.width_px = w, .height_px = h});
  } else if (o.snapshot_every != 0) {
    throw InvalidInput("--snapshot-every needs --snapshots DIR");
  }
  const image::Volume<float> ct = io::read_volume(o.input);
  std::vector<Vec3> seeds;
  for (const auto& s : o.seeds) seeds.push_back(parse_vec3(s, "--seed"));
  for (const auto& s : o.seed_voxels) {
    const Index3 idx = parse_index3(s, "--seed-voxel");
    if (!ct.contains(idx[0], idx[1], idx[2]))
      throw InvalidInput(fmt::format("--seed-voxel {}: outside the {}x{}x{} volume", s, ct.size(0), ct.size(1), ct.size(2)));
    seeds.push_back(ct.index_to_world(Vec3(double(idx[0]), double(idx[1]), double(idx[2]))));
  }
  auto progress = make_progress(g.quiet);
  std::vector<KeptSurface> kept;
  std::int64_t inflation_steps = 0;
  std::optional<segment::BalloonResult> result;
  if (writer) {
    segment::Balloon balloon(ct, seeds, bo);
    SteppedRun stepped = run_keeping_surfaces(balloon, std::max<std::int64_t>(1, o.snapshot_every),
                                              o.snapshot_every == 0, progress.get(), bo.max_iterations);
    result = std::move(stepped.result);
    kept = std::move(stepped.kept);
    inflation_steps = stepped.inflation_steps;
  } else {
    result = segment::segment_balloon(ct, seeds, bo, progress.get());
  }
  std::optional<segment::CalcificationResult> calcified;
  if (o.calcium) {
    report(progress.get(), 0.95, "calcification");
    calcified = segment::add_calcification(*result, ct, {.threshold = *o.calcium, .max_reach_mm = o.calcium_reach_mm});
  }
  const segment::BalloonResult& r = *result;
  nlohmann::json snapshot_steps = nlohmann::json::array();
  if (writer) {
    // The camera frames every kept surface and the final one; the slice is cropped to them.
    kept.push_back({r.report.iterations, r.surface});
    geometry::Aabb box;
    for (const auto& k : kept) box.extend(geometry::Aabb::of(k.surface.vertices));
    const Vec3 &lo = box.min, &hi = box.max;
    const int left_w = writer->width() / 2;
    const viz::Camera camera =
        viz::Camera::orbit(lo, hi, 30.0, 20.0, viz::Projection::Perspective, double(left_w) / writer->height());
    const image::Volume<float> slice = seed_slice(ct, seeds.front(), lo, hi);
    const viz::SliceOptions window{.window = 8.0 * r.report.model.tolerance, .level = r.report.model.reference};
    for (std::size_t i = 0; i < kept.size(); ++i) {
      check_cancel(progress.get());
      writer->write(segment_picture(kept[i].surface, camera, slice, window, writer->width(), writer->height()));
      snapshot_steps.push_back(kept[i].step);
      report(progress.get(), double(i + 1) / double(kept.size()), "snapshots");
    }
  }
  io::write_triangle_mesh(o.output, r.surface);
  if (!o.mask.empty()) io::write_volume(o.mask, segment::surface_to_mask(r.surface, ct));
  const segment::BalloonReport& rep = r.report;
  if (!o.report.empty()) {
    io::Json j = io::segment_report({o.input, seeds, organ, bo}, r, o.output, o.mask);
    if (calcified)
      j["calcification"] = {{"threshold", *o.calcium},
                            {"reach_mm", o.calcium_reach_mm},
                            {"plaque_voxels", calcified->plaque_voxels},
                            {"plaque_volume_mm3", calcified->plaque_volume_mm3}};
    if (writer) {
      j["inflation_steps"] = inflation_steps;
      j["snapshots"] = writer->files_json();
      j["snapshot_steps"] = snapshot_steps;
    }
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
    if (bo.outside_level && !rep.outside_level)
      std::printf("note: the organ's level %.1f lies within half its tolerance of the outside level %g (no contrast): "
                  "the outside level was not used\n",
                  rep.model.reference, *bo.outside_level);
    if (calcified)
      std::printf("calcification above %g: %lld plaque voxels (%.1f mm3) added\n", *o.calcium,
                  static_cast<long long>(calcified->plaque_voxels), calcified->plaque_volume_mm3);
    for (const segment::LeakEvent& e : rep.leaks)
      std::printf("leak stopped (%s) at (%.1f, %.1f, %.1f) mm, step %lld: neck radius %.1f mm\n",
                  segment::leak_cause_name(e.cause), e.position_mm.x(), e.position_mm.y(), e.position_mm.z(),
                  static_cast<long long>(e.iteration), e.neck_radius_mm);
    if (rep.stop_reason == "work_limit")
      std::printf("warning: stopped by the work limit while still growing: a leak the leak control did not stop; "
                  "give a stop point or a region of interest%s\n",
                  o.bone && organ != segment::Organ::Vertebra ? " (for one vertebra of a spine: --organ vertebra)" : "");
    else if (rep.leak_warning)
      std::printf("warning: the volume was still growing when a safeguard stopped it (leak?)\n");
    if (writer) std::printf("%zu snapshots written to %s\n", writer->files().size(), o.snapshots.c_str());
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
  sub->add_option("--organ", opts->organ,
                  "what the seed is in: generic (default), artery, vein (contrast CT vessels: the lumen), vertebra "
                  "(bone, kept apart from the vertebrae above and below); settings in docs/segmentation.md");
  sub->add_flag("--bone", opts->bone, "anything brighter than the reference also belongs (bone)");
  sub->add_flag("--white-noise", opts->white_noise,
                "estimate the tolerance from the residual noise of a ball 5x the seed's (for uncorrelated noise, "
                "e.g. synthetic phantoms; a real scan's correlated noise makes it too narrow)");
  sub->add_option("--calcium", opts->calcium,
                  "add calcified plaque: voxels brighter than this (e.g. HU, above the lumen's band) touching the "
                  "lumen, for references that count the vessel wall's calcium");
  sub->add_option("--calcium-reach", opts->calcium_reach_mm, "how far (mm) plaque may reach from the lumen; default 4");
  sub->add_option("--edge-reach", opts->edge_reach_voxels,
                  "how far (voxels of the smallest spacing) the final snap to the wall may move the surface from "
                  "where the inflation stopped; 0 = no limit (default). 2 keeps the surface to the vessel the "
                  "inflation filled (not creeping along distal branches a reference may leave out), but also "
                  "stops it following vessels thinner than about 2.5 voxels, whose blurred interior the "
                  "inflation rejects");
  sub->add_option("--outside-level", opts->outside_level,
                  "level of the tissue bounding the organ (e.g. 40 for a vessel's soft-tissue wall in HU): the wall "
                  "is placed half-way between the inside and this level where the image goes on beyond it (lung "
                  "or fat past a wall too thin to resolve), so the surface is the lumen's; unset = half-way to the "
                  "surroundings' own level");
  sub->add_option("--max-iterations", opts->max_iterations, "safeguard on inflation steps");
  sub->add_option("-o,--output", opts->output, "surface file (.stl .ply .obj .vtp)")->required();
  sub->add_option("--mask", opts->mask, "binary mask on the input grid (1 inside)");
  sub->add_option("--report", opts->report, "JSON report");
  sub->add_option("--snapshots", opts->snapshots,
                  "Folder for pictures of the inflating balloon (snapshot_NNNN.png: surface left, CT slice through "
                  "the first seed with the contour right; every N steps and the final surface); earlier "
                  "snapshot_NNNN.png files there are replaced");
  sub->add_option("--snapshot-every", opts->snapshot_every,
                  "Picture every this many inflation steps; default: chosen so that a run gives 15-30 pictures");
  sub->add_option("--snapshot-size", opts->snapshot_size, "Picture size WIDTHxHEIGHT in pixels (two panels); default 1000x500");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"segment", 30, setup});

}  // namespace
}  // namespace ido::cli

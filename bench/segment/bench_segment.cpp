// SPDX-License-Identifier: Apache-2.0
// Balloon segmentation against ITK's level sets (issue 4 §Performance, issue 27): for each real
// case of ../shared/data (seeds from its README; abdomen-spine's five lumbar vertebrae from their
// README seeds), the four leak phantoms and the Y phantom, ido's segment_balloon with the
// defaults and with the case's organ choice (segment::organ_options: artery for the CT
// arteries, vertebra for the spine, the leak phantoms' own organ), ITK's
// ThresholdSegmentationLevelSetImageFilter and GeodesicActiveContourLevelSetImageFilter run on
// the same volume from the same seed, whole image, no region of interest. Reported per run:
// wall time, process CPU time (all threads), Dice and HD95 against the reference
// (segment::compare_masks), and the volume ratio. A table with the ratios is printed at the end.
//
// The peers are untuned: their parameters derive from the same intensity model the balloon
// estimates at the seed (reference ± tolerance; for bone the threshold band is open upwards, as
// the balloon's), with the ITK Software Guide's defaults otherwise (curvature 1, advection 1,
// propagation 1 for the threshold filter and 2 for the geodesic active contour, whose curvature
// term otherwise collapses the small initial front; RMS 0.02, initial radius 3 mm, at most 1000
// iterations).
//
// Data folder: $IDO_SHARED_DATA, else <source>/../shared/data; real cases are skipped when
// it is missing. Run: build/bench/bench/segment/bench_segment [--benchmark_filter=ctpa]
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "ido/core/memory.h"
#include "ido/io/volume_io.h"
#include "ido/segment/balloon.h"
#include "ido/segment/intensity_model.h"
#include "ido/segment/metrics.h"
#include "ido/segment/organ.h"
#include "ido/segment/phantom.h"
#include "itk_level_set_peer.h"

namespace {

using namespace ido;
namespace fs = std::filesystem;

struct Case {
  std::string name;
  image::Volume<float> ct;
  image::Volume<std::uint8_t> truth;
  Vec3 seed_mm;
  segment::Organ organ = segment::Organ::Generic;  ///< the organ choice of the "ido_organ" run
};

std::optional<fs::path> data_dir() {
  if (const char* env = std::getenv("IDO_SHARED_DATA"); env && fs::is_directory(env)) return fs::path(env);
  const fs::path p = fs::path(IDO_SOURCE_DIR).parent_path() / "shared" / "data";
  if (fs::is_directory(p)) return p;
  return std::nullopt;
}

image::Volume<std::uint8_t> reference_mask(const image::Volume<float>& ref, bool level_set) {
  auto m = ref.like<std::uint8_t>(0);
  for (std::size_t i = 0; i < ref.data().size(); ++i)
    m.data()[i] = level_set ? ref.data()[i] < 0.0f : ref.data()[i] > 0.5f;
  return m;
}

/// A phantom case: the accuracy suite's noise (20 % of the contrast) and blur (0.7 voxel),
/// noise draw 11; label 1 is the intended organ.
Case phantom_case(segment::PhantomKind kind, segment::Organ organ) {
  segment::PhantomOptions po;
  po.blur_voxels = 0.7;
  po.seed = 11;
  po.noise_hu = 0.2 * segment::make_phantom(kind, po).contrast_hu;
  segment::Phantom p = segment::make_phantom(kind, po);
  Case c;
  c.ct = std::move(p.ct_hu);
  c.truth = c.ct.like<std::uint8_t>(0);
  for (std::size_t i = 0; i < c.truth.data().size(); ++i) c.truth.data()[i] = p.labels.data()[i] == 1;
  c.seed_mm = p.seeds_mm.front();
  c.organ = organ;
  return c;
}

/// The case names, in the order they run.
const std::vector<std::string>& case_names() {
  static const std::vector<std::string> names = {
      "phantom_y_bifurcation", "phantom_valve_chamber", "phantom_vein_in_parenchyma", "phantom_vertebra_stack",
      "phantom_lung_seed",     "ctpa",                  "abdomen_dicom",              "vmtk_aorta",
      "spine_L1",              "spine_L2",              "spine_L3",                   "spine_L4",
      "spine_L5"};
  return names;
}

// Loaded once, on first use.
const Case& get_case(const std::string& name) {
  static std::map<std::string, Case> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  using segment::Organ;
  using segment::PhantomKind;
  Case c;
  if (name == "phantom_y_bifurcation") {
    c = phantom_case(PhantomKind::YBifurcation, Organ::Generic);
  } else if (name == "phantom_valve_chamber") {
    c = phantom_case(PhantomKind::ValveChamber, Organ::Artery);
  } else if (name == "phantom_vein_in_parenchyma") {
    c = phantom_case(PhantomKind::VeinInParenchyma, Organ::Vein);
  } else if (name == "phantom_vertebra_stack") {
    c = phantom_case(PhantomKind::VertebraStack, Organ::Vertebra);
  } else if (name == "phantom_lung_seed") {
    c = phantom_case(PhantomKind::LungSeed, Organ::Generic);
  } else {
    const fs::path d = *data_dir();
    struct Spec {
      const char *ct, *ref;
      bool level_set;
      Vec3 seed;
      segment::Organ organ;
      int label;  ///< the reference's label (0: any non-zero voxel)
    };
    // abdomen-spine: the README's world seeds for L1, L3, L5; L2 and L4 are the voxel seeds
    // (57, 41, 86) and (56, 46, 61) in world mm (3-mm grid, README's affine).
    const std::map<std::string, Spec> specs = {
        {"vmtk_aorta", {"vmtk-aorta/aorta.mha", "vmtk-aorta/aorta-reference-levelset.mha", true, {-219.73, -174.90, 21.00}, Organ::Generic, 0}},
        {"ctpa", {"ctpa/ct.nii.gz", "ctpa/pulmonary_artery.nii.gz", false, {33.34, -186.66, 693.20}, Organ::Artery, 0}},
        {"abdomen_dicom", {"abdomen-dicom/series", "abdomen-dicom/aorta.nii.gz", false, {7.32, -145.52, -782.50}, Organ::Artery, 0}},
        {"spine_L1", {"abdomen-spine/ct.nii.gz", "abdomen-spine/vertebrae.nii.gz", false, {9.96, -119.32, 385.30}, Organ::Vertebra, 31}},
        {"spine_L2", {"abdomen-spine/ct.nii.gz", "abdomen-spine/vertebrae.nii.gz", false, {6.96, -134.32, 352.30}, Organ::Vertebra, 30}},
        {"spine_L3", {"abdomen-spine/ct.nii.gz", "abdomen-spine/vertebrae.nii.gz", false, {3.96, -146.32, 316.30}, Organ::Vertebra, 29}},
        {"spine_L4", {"abdomen-spine/ct.nii.gz", "abdomen-spine/vertebrae.nii.gz", false, {9.96, -149.32, 277.30}, Organ::Vertebra, 28}},
        {"spine_L5", {"abdomen-spine/ct.nii.gz", "abdomen-spine/vertebrae.nii.gz", false, {6.96, -134.32, 241.30}, Organ::Vertebra, 27}}};
    const Spec& s = specs.at(name);
    c.ct = io::read_volume(d / s.ct);
    const image::Volume<float> ref = io::read_volume(d / s.ref);
    c.truth = s.label > 0 ? ref.like<std::uint8_t>(0) : reference_mask(ref, s.level_set);
    if (s.label > 0)
      for (std::size_t i = 0; i < ref.data().size(); ++i) c.truth.data()[i] = std::lround(ref.data()[i]) == s.label;
    c.seed_mm = s.seed;
    c.organ = s.organ;
  }
  c.name = name;
  return cache.emplace(name, std::move(c)).first->second;
}

std::string fmt_ratio(double r) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", r);
  return buf;
}

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Row {
  double wall_s = 0, cpu_s = 0, dice = 0, hd95_mm = 0, volume_ratio = 0;
};
std::map<std::string, std::map<std::string, Row>>& table() {
  static std::map<std::string, std::map<std::string, Row>> t;
  return t;
}

bench::PeerImage peer_image(const image::Volume<float>& ct) {
  bench::PeerImage p;
  for (int a = 0; a < 3; ++a) {
    p.size[a] = ct.size(a);
    p.spacing[a] = ct.spacing()[a];
    p.origin[a] = ct.origin()[a];
    for (int b = 0; b < 3; ++b) p.direction[3 * a + b] = ct.direction()(a, b);
  }
  p.voxels = ct.data().data();
  return p;
}

bench::PeerOptions peer_options(const Case& c) {
  // The same intensity model the balloon estimates at the seed.
  const segment::IntensityModel m = segment::estimate_intensity_model(c.ct, {c.seed_mm});
  const double h = c.ct.spacing().minCoeff();
  bench::PeerOptions o;
  const Vec3 idx = c.ct.world_to_index(c.seed_mm);
  for (int a = 0; a < 3; ++a) o.seed_index[a] = std::llround(idx[a]);
  o.lower = m.reference - m.tolerance;
  // Bone: brighter belongs too, as for the balloon (accept_brighter).
  o.upper = c.organ == segment::Organ::Vertebra ? 1e9 : m.reference + m.tolerance;
  o.gradient_sigma_mm = 0.7 * h;
  // Edge potential 1 / (1 + exp((|∇I| − β) / |α|)): with K = tolerance per voxel (the
  // gradient of a wall of contrast about 2 tolerances blurred over 2 voxels), β = K / 2 and
  // |α| = 0.15 K, speed ≈ 0.7 on noise gradients and ≈ 0.1 on a wall.
  const double k = m.tolerance / h;
  o.sigmoid_beta = 0.5 * k;
  o.sigmoid_alpha = -0.15 * k;
  return o;
}

void run_method(benchmark::State& state, const std::string& case_name, const std::string& method) {
  if (case_name.rfind("phantom", 0) != 0 && !data_dir()) {
    state.SkipWithError("no shared data folder (set IDO_SHARED_DATA)");
    for (auto _ : state) {
    }
    return;
  }
  const Case& c = get_case(case_name);
  Row row;
  for (auto _ : state) {
    const double cpu0 = process_cpu_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    image::Volume<std::uint8_t> mask;
    if (method.rfind("ido_", 0) == 0) {
      // ido_default: BalloonOptions{}; ido_organ: the case's organ choice, as
      // `ido segment --organ NAME` runs it.
      const segment::BalloonOptions bo =
          method == "ido_organ" ? segment::organ_options(c.organ) : segment::BalloonOptions{};
      const segment::BalloonResult r = segment::segment_balloon(c.ct, {c.seed_mm}, bo);
      mask = segment::surface_to_mask(r.surface, c.ct);
    } else {
      bench::PeerOptions o = peer_options(c);
      if (method == "itk_geodesic") o.propagation_scaling = 2.0;
      const bench::PeerResult r = method == "itk_threshold" ? bench::itk_threshold_level_set(peer_image(c.ct), o)
                                                            : bench::itk_geodesic_active_contour(peer_image(c.ct), o);
      mask = c.ct.like<std::uint8_t>(0);
      mask.data() = r.inside;
      state.counters["iterations"] = r.iterations;
    }
    row.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    row.cpu_s = process_cpu_seconds() - cpu0;
    state.PauseTiming();
    const segment::SegmentationScores s = segment::compare_masks(mask, c.truth);
    row.dice = s.dice;
    row.hd95_mm = s.hd95_mm;
    row.volume_ratio = s.volume_ratio;
    state.ResumeTiming();
  }
  state.counters["dice"] = row.dice;
  state.counters["hd95_mm"] = row.hd95_mm;
  state.counters["volume_ratio"] = row.volume_ratio;
  state.counters["cpu_s"] = row.cpu_s;
  table()[case_name][method] = row;
}

void print_table() {
  std::printf("\n%-28s %-14s %9s %9s %7s %9s %7s %12s %12s\n", "case", "method", "wall s", "cpu s", "Dice", "HD95 mm",
              "vol", "wall/organ", "cpu/organ");
  for (const std::string& name : case_names()) {
    const auto found = table().find(name);
    if (found == table().end()) continue;
    const auto& rows = found->second;
    const auto organ = rows.find("ido_organ");
    for (const char* method : {"ido_default", "ido_organ", "itk_threshold", "itk_geodesic"}) {
      const auto r = rows.find(method);
      if (r == rows.end()) continue;
      std::string wr = "-", cr = "-";
      if (organ != rows.end() && r != organ) {
        wr = fmt_ratio(r->second.wall_s / organ->second.wall_s);
        cr = fmt_ratio(r->second.cpu_s / organ->second.cpu_s);
      }
      std::printf("%-28s %-14s %9.2f %9.2f %7.4f %9.2f %7.2f %12s %12s\n", name.c_str(), method, r->second.wall_s,
                  r->second.cpu_s, r->second.dice, r->second.hd95_mm, r->second.volume_ratio, wr.c_str(), cr.c_str());
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  // The heap policy of the `ido` CLI, so the balloon is timed as `ido segment` runs it; the
  // ITK peers in this process get it too.
  ido::use_huge_page_heap();
  for (const std::string& case_name : case_names())
    for (const char* m : {"ido_default", "ido_organ", "itk_threshold", "itk_geodesic"}) {
      const std::string method = m;
      benchmark::RegisterBenchmark((case_name + "/" + m).c_str(),
                                   [case_name, method](benchmark::State& s) { run_method(s, case_name, method); })
          ->Iterations(1)
          ->Unit(benchmark::kSecond)
          ->UseRealTime();
    }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  print_table();
  return 0;
}

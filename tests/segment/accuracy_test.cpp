// SPDX-License-Identifier: Apache-2.0
// Balloon accuracy on every phantom: noise σ = 20 % of the contrast, 0.7-voxel blur,
// isotropic and anisotropic spacing. Dice ≥ 0.97, Euler characteristic = truth's, closed,
// manifold, no self-intersection (issue 4 §Required accuracy).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "ido/geometry/self_intersection.h"
#include "ido/meshing/signed_distance.h"
#include "ido/segment/balloon.h"
#include "ido/segment/metrics.h"
#include "ido/segment/organ.h"
#include "ido/segment/phantom.h"

namespace ido::segment {
namespace {

struct Case {
  PhantomKind kind;
  bool anisotropic;
};

class PhantomAccuracy : public ::testing::TestWithParam<Case> {};

/// The phantom's noise draw: IDO_PHANTOM_NOISE_SEED when set, else @p fallback.
std::uint64_t noise_draw(std::uint64_t fallback) {
  const char* env = std::getenv("IDO_PHANTOM_NOISE_SEED");
  return env ? std::strtoull(env, nullptr, 10) : fallback;
}

TEST_P(PhantomAccuracy, DiceEulerAndValidSurface) {
  const Case c = GetParam();
  PhantomOptions po;
  po.spacing_mm = c.anisotropic ? Vec3(0.9, 0.9, 1.4) : Vec3(1.0, 1.0, 1.0);
  po.blur_voxels = 0.7;
  // The suite's noise realisation is seed 11; IDO_PHANTOM_NOISE_SEED=N runs the same
  // checks on another one (bench/results/segment-seeds.md: over 20 draws several rows
  // fall below 0.97, so seed 11 is not a worst case).
  po.seed = noise_draw(11);
  Phantom clean = make_phantom(c.kind, po);
  po.noise_hu = 0.2 * clean.contrast_hu;
  const Phantom p = make_phantom(c.kind, po);
  BalloonOptions bo;
  // Bone: the cortex is far brighter than the marrow at the seed and belongs to the object.
  bo.accept_brighter = c.kind == PhantomKind::Vertebra;
  const BalloonResult r = segment_balloon(p.ct_hu, p.seeds_mm, bo);
  const auto mask = surface_to_mask(r.surface, p.ct_hu);
  const SegmentationScores s = compare_masks(mask, p.labels);
  std::printf("%-18s %-5s dice %.4f vr %.3f hd95 %.2f mm euler %lld (truth %d) V %lld it %lld %.2f s repairs %lld%s\n",
              std::string(phantom_kind_name(c.kind)).c_str(), c.anisotropic ? "aniso" : "iso", s.dice, s.volume_ratio, s.hd95_mm,
              static_cast<long long>(r.report.euler_characteristic), p.truth_euler_characteristic,
              static_cast<long long>(r.report.vertices), static_cast<long long>(r.report.iterations), r.report.seconds,
              static_cast<long long>(r.report.repairs), r.report.leak_warning ? " LEAK" : "");
  std::printf("%-18s %-5s local repairs %lld, vertex steps %lld moved / %lld asleep\n",
              std::string(phantom_kind_name(c.kind)).c_str(), c.anisotropic ? "aniso" : "iso",
              static_cast<long long>(r.report.local_repairs), static_cast<long long>(r.report.inflation_vertex_steps),
              static_cast<long long>(r.report.slept_vertex_steps));
  // Validity and topology are required of every case.
  EXPECT_TRUE(r.report.closed);
  EXPECT_TRUE(r.report.manifold);
  EXPECT_TRUE(r.report.oriented);
  EXPECT_EQ(r.report.self_intersections, 0);
  EXPECT_FALSE(geometry::has_self_intersections(r.surface));
  // Every row must meet it.
  EXPECT_GE(s.dice, 0.97);
  EXPECT_EQ(r.report.euler_characteristic, p.truth_euler_characteristic);
}

// Less noise must not make the bone harder: with σ = 10 % of the contrast the estimated
// tolerance, and with it the edge-stop constant, halve; the balloon must still thread the
// pedicles and close the ring of the posterior arch (genus 1), at 1 mm and at the demo's 0.8 mm.
TEST(BoneAccuracy, LowNoiseStillClosesThePosteriorArch) {
  for (double spacing : {1.0, 0.8}) {
    PhantomOptions po;
    po.spacing_mm = Vec3::Constant(spacing);
    po.blur_voxels = 0.7;
    po.seed = 7;
    po.noise_hu = 0.1 * make_phantom(PhantomKind::Vertebra, po).contrast_hu;
    const Phantom p = make_phantom(PhantomKind::Vertebra, po);
    BalloonOptions bo;
    bo.accept_brighter = true;
    const BalloonResult r = segment_balloon(p.ct_hu, p.seeds_mm, bo);
    const SegmentationScores s = compare_masks(surface_to_mask(r.surface, p.ct_hu), p.labels);
    std::printf("vertebra, 10 %% noise, %.1f mm: dice %.4f euler %lld (truth %d)\n", spacing, s.dice,
                static_cast<long long>(r.report.euler_characteristic), p.truth_euler_characteristic);
    EXPECT_GE(s.dice, 0.97) << spacing << " mm";
    EXPECT_EQ(r.report.euler_characteristic, p.truth_euler_characteristic) << spacing << " mm";
    EXPECT_EQ(r.report.self_intersections, 0);
  }
}

// Noise draw 3 of the isotropic vessel near bone gives a tolerance of 233 HU (the truth is
// 155): the band reaches into the bone's cortex, and the repair pinched a 29 mm³ piece of it
// off the balloon, a second component (Euler 4). A repair keeps only what holds the seed.
TEST(BoneNeighbour, RepairKeepsOnlyTheSeededComponent) {
  PhantomOptions po;
  po.blur_voxels = 0.7;
  po.seed = 3;
  po.noise_hu = 0.2 * make_phantom(PhantomKind::VesselNearBone, po).contrast_hu;
  const Phantom p = make_phantom(PhantomKind::VesselNearBone, po);
  const BalloonResult r = segment_balloon(p.ct_hu, p.seeds_mm, {});
  const SegmentationScores s = compare_masks(surface_to_mask(r.surface, p.ct_hu), p.labels);
  std::printf("vessel near bone, noise draw 3: tolerance %.0f HU, repairs %lld, components %lld, euler %lld, dice %.4f\n",
              r.report.model.tolerance, static_cast<long long>(r.report.repairs), static_cast<long long>(r.report.components),
              static_cast<long long>(r.report.euler_characteristic), s.dice);
  EXPECT_GE(r.report.repairs, 1);  // the case goes through a repair
  EXPECT_EQ(r.report.components, 1);
  EXPECT_EQ(r.report.euler_characteristic, p.truth_euler_characteristic);
  EXPECT_TRUE(r.report.closed && r.report.manifold);
  EXPECT_EQ(r.report.self_intersections, 0);
}

// The vessel tree phantom of the suite's noise draw (seed 11): σ = 20 % of the contrast,
// 0.7-voxel blur, 1-mm voxels.
Phantom noisy_vessel_tree() {
  PhantomOptions po;
  po.blur_voxels = 0.7;
  po.seed = 11;
  po.noise_hu = 0.2 * make_phantom(PhantomKind::VesselTree, po).contrast_hu;
  return make_phantom(PhantomKind::VesselTree, po);
}

// The active front (BalloonOptions::sleep_steps) skips the settled part of the surface: on
// the vessel tree, whose ends travel long after its trunk has settled, at least half of the
// vertex updates while inflating are skipped, and the result is as accurate as updating every
// vertex every step (same Euler number, Dice within 0.005, both ≥ 0.97).
TEST(ActiveFront, SkipsTheSettledSurfaceWithoutLosingAccuracy) {
  const Phantom p = noisy_vessel_tree();
  double dice[2] = {0, 0};
  for (const int sleep : {0, 10}) {
    BalloonOptions bo;
    bo.sleep_steps = sleep;
    const BalloonResult r = segment_balloon(p.ct_hu, p.seeds_mm, bo);
    const double d = compare_masks(surface_to_mask(r.surface, p.ct_hu), p.labels).dice;
    dice[sleep > 0 ? 1 : 0] = d;
    const auto moved = r.report.inflation_vertex_steps, slept = r.report.slept_vertex_steps;
    std::printf("vessel tree, sleep_steps %d: dice %.4f, vertex steps %lld moved / %lld asleep\n", sleep, d,
                static_cast<long long>(moved), static_cast<long long>(slept));
    EXPECT_GE(d, 0.97) << sleep;
    EXPECT_EQ(r.report.euler_characteristic, p.truth_euler_characteristic) << sleep;
    EXPECT_EQ(r.report.self_intersections, 0);
    if (sleep == 0) {
      EXPECT_EQ(slept, 0);
    } else {
      EXPECT_GE(slept, moved);
    }
  }
  EXPECT_NEAR(dice[1], dice[0], 0.005);
}

// The edge stage's reach (BalloonOptions::edge_reach_voxels): on the vessel tree, whose 2-mm
// twigs the inflation leaves short (their blurred interior lies below the accepted band) and
// the unlimited edge stage follows for several voxels, every vertex of the final surface stays
// within the reach (plus one voxel for the final remesh and repair) of the surface the inflation
// left; without the limit some go well beyond it. The trunk's wall is found either way: the
// limited surface loses only the twigs' tips (Dice within 0.03 of the unlimited one).
TEST(EdgeReach, KeepsTheEdgeStageNearTheInflatedSurface) {
  const Phantom p = noisy_vessel_tree();
  const double h = p.ct_hu.spacing().minCoeff();
  double farthest[2] = {0, 0}, dice[2] = {0, 0};
  for (const double reach : {0.0, 2.0}) {
    BalloonOptions bo;
    bo.edge_reach_voxels = reach;
    Balloon b(p.ct_hu, p.seeds_mm, bo);
    while (!b.step()) {
    }
    const geometry::TriangleMesh inflated = b.surface();
    const BalloonResult r = b.run();
    // The inflated surface's signed distance on a 0.5-voxel grid around both surfaces.
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const auto* m : {&inflated, &r.surface})
      for (const Vec3& v : m->vertices) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
    Index3 size;
    for (int a = 0; a < 3; ++a) size[a] = static_cast<std::int64_t>(std::ceil((hi[a] - lo[a] + 4 * h) / (0.5 * h))) + 1;
    const image::Volume<float> grid(size, Vec3::Constant(0.5 * h), lo - Vec3::Constant(2 * h));
    meshing::SignedDistanceOptions sd;
    sd.band_mm = 6 * h;  // beyond it ±6 voxels, enough to tell 3 from 4
    const image::Volume<float> d = meshing::signed_distance(inflated, grid, sd);
    double far = 0;
    for (const Vec3& v : r.surface.vertices) far = std::max(far, std::abs(d.sample(v)));
    const int k = reach > 0 ? 1 : 0;
    farthest[k] = far / h;
    dice[k] = compare_masks(surface_to_mask(r.surface, p.ct_hu), p.labels).dice;
    std::printf("vessel tree, edge reach %.0f voxels: farthest vertex %.2f voxels from the inflated surface, dice %.4f\n",
                reach, farthest[k], dice[k]);
    EXPECT_TRUE(r.report.closed);
    EXPECT_EQ(r.report.self_intersections, 0);
  }
  EXPECT_LE(farthest[1], 2.0 + 1.0);
  EXPECT_GT(farthest[0], 2.0 + 2.0);
  EXPECT_NEAR(dice[1], dice[0], 0.03);
}

std::vector<Case> all_cases() {
  std::vector<Case> out;
  for (PhantomKind k : all_phantom_kinds())
    for (bool aniso : {false, true}) out.push_back({k, aniso});
  return out;
}

INSTANTIATE_TEST_SUITE_P(AllKinds, PhantomAccuracy, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                           std::string n(phantom_kind_name(param_info.param.kind));
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n + (param_info.param.anisotropic ? "_aniso" : "_iso");
                         });

// The leak phantoms at the accuracy suite's noise (20 % of the contrast) and blur (0.7 voxel),
// draw 1 (IDO_PHANTOM_NOISE_SEED=N: draw N), one seed, the organ choice only: with leak
// control and without.
struct PhantomRun {
  SegmentationScores guarded, flooded;
  BalloonReport report;
};
PhantomRun run_phantom(PhantomKind kind, Organ organ) {
  PhantomOptions po;
  po.blur_voxels = 0.7;
  po.noise_hu = 0.2 * make_phantom(kind).contrast_hu;
  po.seed = noise_draw(po.seed);
  const Phantom ph = make_phantom(kind, po);
  BalloonOptions o = organ_options(organ);
  const BalloonResult with = segment_balloon(ph.ct_hu, {ph.seeds_mm.front()}, o);
  o.leak.enabled = false;
  const BalloonResult without = segment_balloon(ph.ct_hu, {ph.seeds_mm.front()}, o);
  return {compare_masks(surface_to_mask(with.surface, ph.ct_hu), ph.labels),
          compare_masks(surface_to_mask(without.surface, ph.ct_hu), ph.labels), with.report};
}

TEST(LeakPhantoms, ValveChamberStopsAtTheValve) {
  const PhantomRun r = run_phantom(PhantomKind::ValveChamber, Organ::Generic);
  EXPECT_GT(r.flooded.volume_ratio, 5.0);  // without the guard: the chamber (measured 20x)
  EXPECT_GE(r.guarded.dice, 0.95);         // measured 0.981
  EXPECT_EQ(r.report.euler_characteristic, 2);
  ASSERT_FALSE(r.report.leaks.empty());
  EXPECT_EQ(r.report.leaks.front().cause, LeakCause::Chamber);
}

TEST(LeakPhantoms, VertebraStackKeepsTheSeededVertebra) {
  const PhantomRun r = run_phantom(PhantomKind::VertebraStack, Organ::Vertebra);
  EXPECT_GT(r.flooded.volume_ratio, 2.0);  // without: all three (measured 3.45)
  // Measured 0.9635 (0.937 when the three-plateau wall read the neighbour's end plate beyond a
  // disc as surroundings and put the wall 1.5 mm into the disc); 0.958-0.964 over 20 draws.
  EXPECT_GE(r.guarded.dice, 0.95);
  EXPECT_LT(r.guarded.volume_ratio, 1.1);
  EXPECT_TRUE(r.report.closed && r.report.manifold);
  // The ring around the canal (Euler 0); one draw in 20 has −2, a second handle where a facet
  // plate meets the arch (docs/segmentation.md).
  EXPECT_EQ(r.report.euler_characteristic, 0);
  EXPECT_EQ(r.report.neighbour_markers_mm.size(), 2u);
}

TEST(LeakPhantoms, VeinInParenchymaDoesNotFloodTheLiver) {
  const PhantomRun r = run_phantom(PhantomKind::VeinInParenchyma, Organ::Generic);
  EXPECT_GT(r.flooded.volume_ratio, 5.0);  // without: the liver (measured 8.4x)
  // With: the liver is closed as a chamber, and the vein where the liver wraps it is opened
  // again, being nearer the vein's grey level (measured Dice 0.964, volume ratio 0.96; 0.81 and
  // 0.70 when the wrap stayed closed).
  EXPECT_GE(r.guarded.dice, 0.95);
  EXPECT_LT(r.guarded.volume_ratio, 1.1);
  EXPECT_EQ(r.report.euler_characteristic, 2);
  ASSERT_FALSE(r.report.leaks.empty());
  EXPECT_EQ(r.report.leaks.front().cause, LeakCause::Chamber);
}

}  // namespace
}  // namespace ido::segment

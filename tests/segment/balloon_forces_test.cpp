// SPDX-License-Identifier: Apache-2.0
// The balloon's per-vertex forces: surface differentials (against a brute-force one-ring),
// the umbrella curvature and normal speed formulas, the wall search along a normal on
// analytic blurred profiles, and the three-plateau profile fit.
#include "ido/segment/balloon_forces.h"

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/segment/balloon.h"
#include "support/test_support.h"

namespace ido::segment {
namespace {

TEST(SurfaceDifferentials, UmbrellaCurvatureOfSphere) {
  const double r = 7.0;
  const auto m = balloon_icosphere(Vec3(1, 2, 3), r, 4);
  const auto d = surface_differentials(m.vertices, m.triangles);
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    const Vec3 radial = (m.vertices[i] - Vec3(1, 2, 3)).normalized();
    ASSERT_GT(d.normals[i].dot(radial), 0.999);
    ASSERT_TRUE(test::rel_near(umbrella_mean_curvature(d.umbrella_mm[i], d.normals[i], d.mean_edge2_mm2[i]), 1.0 / r, 0.1));
    ASSERT_LT(tangential_umbrella(d.umbrella_mm[i], d.normals[i]).norm(), 0.2 * std::sqrt(d.mean_edge2_mm2[i]));
  }
}

TEST(EdgeOffset, FindsBlurredStepHalfway) {
  // Bright half-space x < 10.3 mm blurred by a Gaussian of σ = 1 mm: the wall (steepest
  // point of the erfc profile) is at 10.3.
  image::Volume<float> v({30, 4, 4}, Vec3(1, 1, 1));
  for (std::int64_t i = 0; i < 30; ++i)
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t k = 0; k < 4; ++k) v(i, j, k) = float(150.0 * std::erfc((double(i) - 10.3) / std::sqrt(2.0)));
  const IntensityModel m{300, 100};
  for (double x0 : {9.2, 10.0, 11.1}) {
    const auto t = edge_offset_along_normal(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, 1.5, 0.05, 10.0, 1.0);
    ASSERT_TRUE(t.has_value());
    // Trilinear interpolation of the sampled profile: the steepest point is within a few
    // hundredths of a voxel.
    EXPECT_TRUE(test::near(x0 + *t, 10.3, 0.08)) << x0;
  }
  // Flat region: no wall within reach.
  EXPECT_FALSE(edge_offset_along_normal(v, Vec3(3, 1.5, 1.5), Vec3::UnitX(), m, 1.5, 0.05, 10.0, 1.0).has_value());
}

// A profile along x built from pieces [x_k, x_{k+1}) of constant level, blurred by a Gaussian
// of σ (analytic: sums of normal CDFs), sampled at voxel centres x = i.
image::Volume<float> blurred_layers(const std::vector<double>& edges, const std::vector<double>& levels, double sigma) {
  image::Volume<float> v({40, 4, 4}, Vec3(1, 1, 1));
  auto cdf = [&](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  for (std::int64_t i = 0; i < 40; ++i) {
    double value = levels[0];
    for (std::size_t e = 0; e < edges.size(); ++e) value += (levels[e + 1] - levels[e]) * cdf((double(i) - edges[e]) / sigma);
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t k = 0; k < 4; ++k) v(i, j, k) = float(value);
  }
  return v;
}

TEST(EdgeOffset, ThinGapToBrightNeighbourStopsAtTheVesselWall) {
  // Vessel (350) up to x = 10, one voxel of soft tissue (40), bone (1200) from x = 11, all
  // blurred by σ = 1 voxel (scanner blur and pre-smoothing): the gap shows only as a shallow
  // dip. The steepest rise of |I − reference| is the bone's rim; the first-transition limit
  // keeps the wall at the band's exit, within about half a voxel of the true wall (x = 10).
  const auto v = blurred_layers({10.0, 11.0}, {350, 40, 1200}, 1.0);
  const IntensityModel m{350, 155};
  for (double x0 : {9.0, 9.6, 10.2}) {
    const auto t = edge_offset_along_normal(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 155, 1.0);
    ASSERT_TRUE(t.has_value());
    EXPECT_GT(x0 + *t, 10.8) << "the unlimited search should find the bone's rim, x0 = " << x0;
    const double limited = first_transition_limit(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, *t, -1);
    EXPECT_GE(x0 + limited, 10.0) << x0;
    EXPECT_LE(x0 + limited, 10.65) << x0;  // the exit I = 505 lies at x ≈ 10.56
  }
  // The surroundings are darker than this vessel elsewhere: its usual exit is downward; here
  // the first exit is upward.
  EXPECT_EQ(first_exit_direction(v, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2), 1);
  EXPECT_EQ(first_exit_direction(v, Vec3(9.6, 1.5, 1.5), -Vec3::UnitX(), m, 2.0, 0.2), 0);
  // Disabled without a known background side, and for bone (accept_brighter).
  EXPECT_EQ(first_transition_limit(v, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, 1.5, 0), 1.5);
  IntensityModel bone = m;
  bone.accept_brighter = true;
  EXPECT_EQ(first_transition_limit(v, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), bone, 2.0, 0.2, 1.5, -1), 1.5);
}

TEST(EdgeOffset, ValleyToBrightNeighbourIsReadAgainstTheSurroundingsLevel) {
  // Vessel (350) up to x = 10, 3.5 voxels of soft tissue (40), bone (1200) beyond, blurred by
  // σ = 1 voxel: the valley's floor stays near 100, and within the reach the profile climbs
  // back towards the bone, so half-way to the floor lies inside the wall. Half-way to the
  // surroundings' level (departure 310, where the tissue is wide) reads it.
  const auto v = blurred_layers({10.0, 13.5}, {350, 40, 1200}, 1.0);
  const IntensityModel m{350, 85};
  for (double x0 : {9.4, 9.6, 9.8}) {
    const Vec3 p(x0, 1.5, 1.5);
    const auto floor_read = edge_offset_along_normal(v, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 85, 1.0);
    const auto bg_read = edge_offset_along_normal(v, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 85, 1.0, 310.0);
    ASSERT_TRUE(floor_read && bg_read) << x0;
    EXPECT_LT(x0 + *floor_read, 9.85) << "the floor's half-way level should lie inside, x0 = " << x0;
    EXPECT_TRUE(test::near(x0 + *bg_read, 10.0, 0.1)) << x0 << " -> " << x0 + *bg_read << " (floor " << x0 + *floor_read << ")";
  }
  // A plain wall: unchanged, bit for bit.
  const auto step = blurred_layers({10.0}, {350, 40}, 1.0);
  for (double x0 : {9.4, 9.6, 9.8}) {
    const Vec3 p(x0, 1.5, 1.5);
    const auto a = edge_offset_along_normal(step, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 85, 1.0);
    const auto b = edge_offset_along_normal(step, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 85, 1.0, 310.0);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(*a, *b);
  }
}

TEST(EdgeOffset, OutsideLevelReadsTheLumenAgainstAThinWall) {
  // Lumen (540) up to x = 10, a wall of soft tissue (40) 0.7 voxel thin, lung (−800) beyond,
  // blurred by σ = 1 voxel (CT pulmonary angiography at 1.5 mm). The wall is not resolved:
  // the profile falls from the lumen straight towards the lung. Half-way to the lung's level
  // (−130) lies at x = 10.45, outside the lumen's edge; half-way to the wall's level (290),
  // which --outside-level 40 asks for, lies at x = 9.50, inside it (analytic crossings).
  const auto v = blurred_layers({10.0, 10.7}, {540, 40, -800}, 1.0);
  const IntensityModel m{540, 60};
  for (double x0 : {9.4, 9.8, 10.2}) {
    const Vec3 p(x0, 1.5, 1.5);
    const auto lung = edge_offset_along_normal(v, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 60, 1.0);
    const auto wall = edge_offset_along_normal(v, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 60, 1.0, 0.0, 40.0);
    ASSERT_TRUE(lung && wall) << x0;
    EXPECT_TRUE(test::near(x0 + *lung, 10.45, 0.1)) << x0 << " -> " << x0 + *lung;
    EXPECT_TRUE(test::near(x0 + *wall, 9.50, 0.1)) << x0 << " -> " << x0 + *wall;
  }
  // Where the surroundings are the wall's own tissue, or lie on the other side of the
  // reference (a brighter neighbour), the level changes nothing, bit for bit.
  for (const auto& [levels, x0] : {std::pair{std::vector<double>{540, 40}, 9.6}, std::pair{std::vector<double>{540, 1500}, 9.6}}) {
    const auto plain = blurred_layers({10.0}, levels, 1.0);
    const Vec3 p(x0, 1.5, 1.5);
    const auto a = edge_offset_along_normal(plain, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 60, 1.0);
    const auto b = edge_offset_along_normal(plain, p, Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 60, 1.0, 0.0, 40.0);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(*a, *b) << levels[1];
  }
}

TEST(EdgeOffset, BrightDepositWithoutGapIsNotACap) {
  // A much brighter deposit directly against the vessel (no gap, no dip): the limit keeps the
  // wall found by the steepest rise.
  const auto v = blurred_layers({10.0}, {350, 1200}, 1.0);
  const IntensityModel m{350, 155};
  EXPECT_EQ(first_transition_limit(v, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, 0.9, -1), 0.9);
}

TEST(EdgeOffset, OrdinaryWallIsUnchangedAndDarkValleyIsNeverCrossed) {
  const IntensityModel m{350, 155};
  // A plain blurred wall to darker tissue: the limit changes nothing.
  const auto step = blurred_layers({10.0}, {350, 40}, 1.0);
  for (double wall : {0.3, 0.5, 0.8})
    EXPECT_EQ(first_transition_limit(step, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, wall, -1), wall);
  EXPECT_EQ(first_exit_direction(step, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2), -1);
  // Two vessels (350) 2 voxels apart across dark tissue (40), σ = 0.7: a wall offered beyond
  // the valley's floor (x ≈ 11) is pulled back to the first vessel's wall, x = 10. The level
  // used is half-way between the reference and the sampled floor (≈ 98: the blur lifts the
  // floor of a 2-voxel valley above 40), 224 instead of 195, which by the profile's slope
  // (≈ 130 per voxel) puts the wall 0.22 voxel inside the true one: never beyond it.
  const auto valley = blurred_layers({10.0, 12.0}, {350, 40, 350}, 0.7);
  const double limited = first_transition_limit(valley, Vec3(10.5, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, 1.8, -1);
  EXPECT_LE(10.5 + limited, 10.0);
  EXPECT_GE(10.5 + limited, 9.75);
  // A wall offered before the floor is kept.
  EXPECT_EQ(first_transition_limit(valley, Vec3(10.5, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, -0.4, -1), -0.4);
  // The mirror image (a dark organ among brighter tissue, background side +1) behaves alike.
  auto mirrored = valley;
  for (float& x : mirrored.data()) x = -x;
  const IntensityModel dark{-350, 155};
  const double mirrored_limited =
      first_transition_limit(mirrored, Vec3(10.5, 1.5, 1.5), Vec3::UnitX(), dark, 2.0, 0.2, 1.8, +1);
  EXPECT_NEAR(mirrored_limited, limited, 1e-9);
}

TEST(PlateauFit, RecoversBlurredThinLayersExactly) {
  // Profiles made exactly of the model (three plateaus blurred by the fitter's σ), with the
  // transitions on the candidate grid: the fit returns them and the levels.
  const double sigma = 1.0;
  const PlateauProfileFitter fitter(sigma, 0.2, 4.0, 2.0, 0.1, 0.5);
  auto cdf = [&](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
  const std::array<std::array<double, 5>, 3> cases = {{{0.3, 1.8, 350, 40, 1200},   // vessel, gap, bone
                                                       {-0.5, 1.0, 250, 1200, 40},  // marrow, cortex, tissue
                                                       {0.0, 1.0, 350, 40, 1200}}};
  for (const auto& [a, b, c, m, o] : cases) {
    std::vector<double> samples(fitter.sample_count());
    for (std::size_t k = 0; k < samples.size(); ++k) {
      const double t = fitter.sample_offset_mm(k);
      samples[k] = c + (m - c) * cdf((t - a) / sigma) + (o - m) * cdf((t - b) / sigma);
    }
    const auto f = fitter.fit(samples);
    ASSERT_TRUE(f.has_value());
    EXPECT_TRUE(test::near(f->inner_mm, a, 1e-9)) << a;
    EXPECT_TRUE(test::near(f->outer_mm, b, 1e-9)) << b;
    EXPECT_TRUE(test::near(f->levels[0], c, 1e-6 * 1200));
    EXPECT_TRUE(test::near(f->levels[1], m, 1e-6 * 1200));
    EXPECT_TRUE(test::near(f->levels[2], o, 1e-6 * 1200));
    EXPECT_LT(f->rms_residual, 1e-3);
  }
  EXPECT_FALSE(fitter.fit(std::vector<double>(3, 0.0)).has_value());
  EXPECT_THROW(PlateauProfileFitter(1.0, 0.2, 3.0, 2.0, 0.1, 0.5), InvalidInput);  // reach < search + 2σ
}

TEST(PlateauFit, ThinCortexWallIsItsOuterEdgeNotTheHalfWayLevel) {
  // Bone: marrow (250) up to x = 8.5, a 1.5-voxel cortex (1200) up to x = 10, soft tissue (40)
  // beyond, blurred by σ = 1 voxel. The blur lowers the cortex's peak to about 720, so the
  // half-way level between the profile's extremes (≈ 380, what edge_offset_along_normal reads)
  // lies about half a voxel outside the true wall; the plateau fit reads the wall at x = 10.
  const auto v = blurred_layers({8.5, 10.0}, {250, 1200, 40}, 1.0);
  IntensityModel bone{250, 100};
  bone.accept_brighter = true;
  const PlateauProfileFitter fitter(std::sqrt(1.0 + 1.0 / 6.0), 0.2, 4.4, 2.0, 0.1, 0.5);
  for (double x0 : {9.2, 10.0, 10.7}) {
    const auto half_way = edge_offset_along_normal(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), bone, 2.0, 0.2, 25.0, 1.0);
    ASSERT_TRUE(half_way.has_value());
    EXPECT_GT(x0 + *half_way, 10.3) << x0;
    const auto w = plateau_wall_offset(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), bone, fitter);
    ASSERT_TRUE(w.has_value()) << x0;
    // Trilinear interpolation between voxel centres blurs the sampled profile a little more.
    EXPECT_TRUE(test::near(x0 + *w, 10.0, 0.15)) << x0 << " -> " << x0 + *w;
  }
  // A plain blurred step of an organ into darker tissue: the wall is the step.
  const auto step = blurred_layers({10.0}, {350, 40}, 1.0);
  const IntensityModel vessel{350, 100};
  const auto w = plateau_wall_offset(step, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), vessel, fitter);
  ASSERT_TRUE(w.has_value());
  EXPECT_TRUE(test::near(9.6 + *w, 10.0, 0.15)) << 9.6 + *w;
  // The inside level outside the band (the point is not in the organ): no wall.
  EXPECT_FALSE(plateau_wall_offset(step, Vec3(14.0, 1.5, 1.5), Vec3::UnitX(), vessel, fitter).has_value());
}

TEST(PlateauFit, ADiscBetweenTwoEndPlatesIsLeftToTheHalfWayLevel) {
  // Two vertebral bodies: marrow (250) up to x = 8.5, an end plate (1200) up to x = 10, a
  // 3.5-voxel disc (80), the neighbour's end plate from x = 13.5 to 15, its marrow beyond;
  // σ = 1 voxel. The profile falls into the disc and rises again into the band: the three
  // plateaus would read the neighbour's plate as surroundings, so no plateau wall is given,
  // and the half-way level lies between the true wall and the disc's middle (x = 11.75).
  const auto v = blurred_layers({8.5, 10.0, 13.5, 15.0}, {250, 1200, 80, 1200, 250}, 1.0);
  IntensityModel bone{250, 100};
  bone.accept_brighter = true;
  const PlateauProfileFitter fitter(std::sqrt(1.0 + 1.0 / 6.0), 0.2, 4.4, 2.0, 0.1, 0.5);
  for (double x0 : {9.6, 10.4, 11.0}) {
    EXPECT_FALSE(plateau_wall_offset(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), bone, fitter).has_value()) << x0;
    const auto half_way = edge_offset_along_normal(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), bone, 2.0, 0.2, 25.0, 1.0);
    ASSERT_TRUE(half_way.has_value()) << x0;
    EXPECT_GT(x0 + *half_way, 10.0) << x0;
    EXPECT_LT(x0 + *half_way, 11.2) << x0;
  }
  // The same plate with soft tissue beyond (no neighbour): the plateau wall is read.
  const auto lone = blurred_layers({8.5, 10.0}, {250, 1200, 80}, 1.0);
  EXPECT_TRUE(plateau_wall_offset(lone, Vec3(10.4, 1.5, 1.5), Vec3::UnitX(), bone, fitter).has_value());
}

TEST(PlateauFit, ThinGapToBoneIsReadAtTheVesselWall) {
  // Vessel (350) up to x = 10, one voxel of soft tissue (40), a 2-voxel cortex (1200), marrow
  // (250), blurred by σ = 1 voxel: the blurred bone fills the gap, and the band's exit lies
  // half a voxel beyond the vessel's wall. The gap fit, up to the bone's rim, reads the wall.
  const auto v = blurred_layers({10.0, 11.0, 13.0}, {350, 40, 1200, 250}, 1.0);
  const IntensityModel m{350, 155};
  const double sigma = std::sqrt(1.0 + 1.0 / 6.0);  // trilinear sampling adds ≈ 1/6 voxel²
  for (double x0 : {9.2, 9.6, 10.2}) {
    const auto rim = edge_offset_along_normal(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, 0.25 * 155, 1.0);
    ASSERT_TRUE(rim.has_value());
    const double exit = first_transition_limit(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, 2.0, 0.2, *rim, -1);
    EXPECT_GT(x0 + exit, 10.4) << x0;
    const auto w = thin_gap_wall_offset(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, -1, sigma, 2.0, 0.2, *rim);
    ASSERT_TRUE(w.has_value()) << x0;
    EXPECT_TRUE(test::near(x0 + *w, 10.0, 0.15)) << x0 << " -> " << x0 + *w;
  }
  // A plain wall into darker tissue has no neighbour beyond the band: no gap reading.
  const auto step = blurred_layers({10.0}, {350, 40}, 1.0);
  EXPECT_FALSE(thin_gap_wall_offset(step, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, -1, sigma, 2.0, 0.2, 1.5).has_value());
  // Without a known background side: nothing.
  EXPECT_FALSE(thin_gap_wall_offset(v, Vec3(9.6, 1.5, 1.5), Vec3::UnitX(), m, 0, sigma, 2.0, 0.2, 1.5).has_value());
}


TEST(SurfaceDifferentials, EqualABruteForceOneRingOnAnIrregularSurface) {
  // A jittered icosphere: still closed and oriented, but no two one-rings alike.
  auto m = balloon_icosphere(Vec3(0.5, -1, 2), 5.0, 2);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (Vec3& v : m.vertices) v += Vec3(u(rng), u(rng), u(rng));
  const auto d = surface_differentials(m.vertices, m.triangles);
  ASSERT_EQ(d.normals.size(), m.vertices.size());
  // Brute force: the neighbours of i, each once; the area-weighted normal from the sum of the
  // incident triangles' cross products.
  std::vector<std::set<std::int32_t>> ring(m.vertices.size());
  std::vector<Vec3> normal(m.vertices.size(), Vec3::Zero());
  for (const Tri& t : m.triangles) {
    const Vec3 c = (m.vertices[std::size_t(t[1])] - m.vertices[std::size_t(t[0])])
                       .cross(m.vertices[std::size_t(t[2])] - m.vertices[std::size_t(t[0])]);
    for (int k = 0; k < 3; ++k) {
      normal[std::size_t(t[k])] += c;
      ring[std::size_t(t[k])].insert(t[(k + 1) % 3]);
      ring[std::size_t(t[k])].insert(t[(k + 2) % 3]);
    }
  }
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    Vec3 centroid = Vec3::Zero();
    double edge2 = 0.0;
    for (std::int32_t w : ring[i]) {
      centroid += m.vertices[std::size_t(w)];
      edge2 += (m.vertices[std::size_t(w)] - m.vertices[i]).squaredNorm();
    }
    centroid /= double(ring[i].size());
    ASSERT_TRUE(d.normals[i].isApprox(normal[i].normalized(), 1e-12)) << i;
    EXPECT_TRUE(test::near(d.normals[i].norm(), 1.0, 1e-12));
    ASSERT_TRUE((d.umbrella_mm[i] - (centroid - m.vertices[i])).norm() < 1e-12) << i;
    ASSERT_TRUE(test::rel_near(d.mean_edge2_mm2[i], edge2 / double(ring[i].size()), 1e-12)) << i;
  }
  // With flags, the needed vertices' values are the full computation's, bit for bit.
  std::vector<std::uint8_t> needed(m.vertices.size(), 0);
  for (std::size_t i = 0; i < needed.size(); i += 7) needed[i] = 1;
  const auto partial = surface_differentials(m.vertices, m.triangles, needed);
  for (std::size_t i = 0; i < needed.size(); ++i)
    if (needed[i]) {
      EXPECT_EQ(partial.normals[i], d.normals[i]) << i;
      EXPECT_EQ(partial.umbrella_mm[i], d.umbrella_mm[i]) << i;
      EXPECT_EQ(partial.mean_edge2_mm2[i], d.mean_edge2_mm2[i]) << i;
    }
}

TEST(SurfaceDifferentials, CurvatureSpeedAndTangentialFormulas) {
  // On a sphere of radius R with edge ℓ the one-ring centroid lies ℓ²/(2R) inside: H = 1/R.
  const Vec3 n = Vec3(1, 2, -2).normalized();
  const double R = 8.0, l2 = 1.5;
  EXPECT_TRUE(test::near(umbrella_mean_curvature(-l2 / (2 * R) * n, n, l2), 1.0 / R, 1e-15));
  EXPECT_TRUE(test::near(umbrella_mean_curvature(l2 / (2 * R) * n, n, l2), -1.0 / R, 1e-15));  // concave
  EXPECT_EQ(umbrella_mean_curvature(Vec3(1, 1, 1), n, 0.0), 0.0);  // no edges: no curvature
  // The tangential part is orthogonal to n and differs from the umbrella along n only.
  const Vec3 L(0.3, -0.7, 0.2);
  const Vec3 t = tangential_umbrella(L, n);
  EXPECT_TRUE(test::near(t.dot(n), 0.0, 1e-15));
  EXPECT_TRUE(test::near((L - t).cross(n).norm(), 0.0, 1e-15));
  // Normal speed: w_i · s(I) − w_c · h · H.
  const IntensityModel model{200, 50};
  const BalloonForceWeights w{.inflation = 1.5, .curvature = 0.6};
  EXPECT_TRUE(test::near(balloon_normal_speed(225, 0.25, 0.8, model, w), 1.5 * 0.5 - 0.6 * 0.8 * 0.25, 1e-15));
  EXPECT_TRUE(test::near(balloon_normal_speed(200, 0.0, 0.8, model, w), 1.5, 1e-15));
  // A front whose radius is below h · curvature / speed stops (the neck rule of the weights).
  const double h = 1.0, speed = w.inflation * inflation_speed(200, model);
  const double stop_radius = h * w.curvature / speed;
  EXPECT_GT(balloon_normal_speed(200, 1.0 / (1.1 * stop_radius), h, model, w), 0.0);
  EXPECT_LT(balloon_normal_speed(200, 1.0 / (0.9 * stop_radius), h, model, w), 0.0);
}

TEST(PlateauFit, BadParametersAreRefusedAndTheCachedModelEqualsTheOneCall) {
  EXPECT_THROW(PlateauProfileFitter(0.0, 0.2, 4.0, 2.0, 0.1, 0.5), InvalidInput);
  EXPECT_THROW(PlateauProfileFitter(1.0, 0.0, 4.0, 2.0, 0.1, 0.5), InvalidInput);
  EXPECT_THROW(PlateauProfileFitter(1.0, 0.2, 4.0, 2.0, 0.0, 0.5), InvalidInput);
  EXPECT_THROW(PlateauProfileFitter(1.0, 0.2, {2.0, -2.0}, {-1.0, 1.0}, 0.1, 0.5), InvalidInput);  // empty samples
  EXPECT_THROW(PlateauProfileFitter(1.0, 0.2, {-2.0, 2.0}, {1.0, -1.0}, 0.1, 0.5), InvalidInput);  // empty candidates
  EXPECT_THROW(ThinGapWallModel(0.0, 2.0, 0.2), InvalidInput);
  EXPECT_THROW(ThinGapWallModel(1.0, -2.0, 0.2), InvalidInput);
  EXPECT_THROW(ThinGapWallModel(1.0, 2.0, 0.0), InvalidInput);
  // Samples at samples_mm[0] + k · step up to samples_mm[1].
  const PlateauProfileFitter ranged(1.0, 0.25, {-3.0, 2.0}, {-1.0, 1.0}, 0.1, 0.5);
  ASSERT_EQ(ranged.sample_count(), 21U);
  for (std::size_t k = 0; k < ranged.sample_count(); ++k)
    EXPECT_TRUE(test::near(ranged.sample_offset_mm(k), -3.0 + 0.25 * double(k), 1e-12));
  // ThinGapWallModel is thin_gap_wall_offset with its fitters kept: the same answers.
  const auto v = blurred_layers({10.0, 11.0, 13.0}, {350, 40, 1200, 250}, 1.0);
  const IntensityModel m{350, 155};
  const double sigma = std::sqrt(1.0 + 1.0 / 6.0);
  const ThinGapWallModel model(sigma, 2.0, 0.2);
  int found = 0;
  for (double x0 : {9.2, 9.6, 10.2}) {
    for (double rim : {0.8, 1.2, 1.5}) {
      const auto a = model.wall_offset(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, -1, rim);
      const auto b = thin_gap_wall_offset(v, Vec3(x0, 1.5, 1.5), Vec3::UnitX(), m, -1, sigma, 2.0, 0.2, rim);
      ASSERT_EQ(a.has_value(), b.has_value()) << x0 << " " << rim;
      if (a) {
        EXPECT_EQ(*a, *b);
        ++found;
      }
    }
  }
  EXPECT_GT(found, 0);
}

}  // namespace
}  // namespace ido::segment

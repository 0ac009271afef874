// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/balloon.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/self_intersection.h"
#include "ido/geometry/winding_number.h"
#include "ido/image/filters.h"
#include "ido/meshing/remesh.h"
#include "ido/meshing/signed_distance.h"
#include "ido/segment/balloon_forces.h"
#include "ido/segment/intensity_model.h"
#include "ido/segment/topology_repair.h"
#include "support/test_support.h"

namespace ido::segment {
namespace {

// A CT-like test volume: `inside(p)` voxels at `hu_in`, others at 0, with Gaussian noise,
// and the truth mask. Partial volume by 4×4×4 supersampling.
struct Synthetic {
  image::Volume<float> ct;
  image::Volume<std::uint8_t> truth;
};
Synthetic make_volume(Index3 size, const Vec3& spacing, const std::function<bool(const Vec3&)>& inside,
                      double hu_in, double noise, unsigned seed = 7) {
  Synthetic s{image::Volume<float>(size, spacing), image::Volume<std::uint8_t>(size, spacing)};
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  for (std::int64_t k = 0; k < size[2]; ++k)
    for (std::int64_t j = 0; j < size[1]; ++j)
      for (std::int64_t i = 0; i < size[0]; ++i) {
        int hits = 0;
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b)
            for (int c = 0; c < 4; ++c)
              hits += inside(s.ct.index_to_world(Vec3(i - 0.375 + 0.25 * a, j - 0.375 + 0.25 * b, k - 0.375 + 0.25 * c)));
        s.ct(i, j, k) = static_cast<float>(hu_in * hits / 64.0 + (noise > 0 ? g(rng) : 0.0));
        s.truth(i, j, k) = inside(s.ct.index_to_world(Vec3(double(i), double(j), double(k))));
      }
  return s;
}

double dice(const image::Volume<std::uint8_t>& a, const image::Volume<std::uint8_t>& b) {
  double inter = 0, na = 0, nb = 0;
  for (std::size_t i = 0; i < a.data().size(); ++i) {
    inter += a.data()[i] && b.data()[i];
    na += a.data()[i] != 0;
    nb += b.data()[i] != 0;
  }
  return 2 * inter / (na + nb);
}

TEST(InflationSpeed, InflatesInsideBandDeflatesBeyond) {
  const IntensityModel m{200, 50};
  EXPECT_DOUBLE_EQ(inflation_speed(200, m), 1.0);
  EXPECT_DOUBLE_EQ(inflation_speed(225, m), 0.5);
  EXPECT_DOUBLE_EQ(inflation_speed(175, m), 0.5);
  EXPECT_DOUBLE_EQ(inflation_speed(250, m), 0.0);
  EXPECT_LT(inflation_speed(100, m), 0.0);
  EXPECT_LT(inflation_speed(320, m), 0.0);
  EXPECT_DOUBLE_EQ(inflation_speed(-1000, m), -1.0);
}

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

TEST(IntensityModel, RobustEstimateFromSeedNeighbourhood) {
  const auto s = make_volume({30, 30, 30}, Vec3(1, 1, 1), [](const Vec3& p) { return (p - Vec3(15, 15, 15)).norm() < 10; },
                             400.0, 40.0);
  const auto m = estimate_intensity_model(s.ct, {Vec3(15, 15, 15)}, {.radius_mm = 4.0});
  EXPECT_TRUE(test::near(m.reference, 400.0, 15.0));
  EXPECT_TRUE(test::rel_near(m.tolerance, 2.5 * 40.0, 0.25));
  EXPECT_THROW((void)estimate_intensity_model(s.ct, {}), InvalidInput);
  EXPECT_THROW((void)estimate_intensity_model(s.ct, {Vec3(-10, 0, 0)}), InvalidInput);
}

// The residual second pass of the noise estimate: on white noise inside a sphere whose
// wall lies within the big ball (anisotropic case), every draw's tolerance is near the
// true 2.5 σ, and the spread over draws is smaller than the seed ball's alone.
TEST(IntensityModel, ResidualSecondPassRecoversWhiteNoiseWithLessSpread) {
  const double sigma = 60.0, truth = 2.5 * sigma;
  for (const Vec3& spacing : {Vec3(1, 1, 1), Vec3(0.9, 0.9, 1.4)}) {
    double worst_first = 0, worst_second = 0;
    for (unsigned seed = 1; seed <= 12; ++seed) {
      const Vec3 c(18, 18, 18);
      const auto s = make_volume({40, 40, 28}, spacing, [&](const Vec3& p) { return (p - c).norm() < 12.0; }, 300.0,
                                 sigma, seed);
      const double smoothing_mm = 0.7 * spacing.minCoeff();
      const auto smoothed = image::gaussian_smooth(s.ct, smoothing_mm);
      IntensityEstimateOptions o;
      o.residual_ball_factor = 0;
      const double first = estimate_intensity_model(s.ct, {c}, o).tolerance;
      o.residual_ball_factor = 5;
      const double second = estimate_intensity_model(s.ct, {c}, o, smoothed, smoothing_mm).tolerance;
      EXPECT_TRUE(test::rel_near(second, truth, 0.12)) << spacing.transpose() << " seed " << seed << ": " << second;
      worst_first = std::max(worst_first, std::abs(first / truth - 1));
      worst_second = std::max(worst_second, std::abs(second / truth - 1));
    }
    std::printf("spacing %.1f,%.1f,%.1f: worst relative error first pass %.3f, second %.3f\n", spacing[0], spacing[1],
                spacing[2], worst_first, worst_second);
    EXPECT_LT(worst_second, 0.5 * worst_first) << spacing.transpose();
  }
  // A smoothed image on another grid is refused.
  const auto s = make_volume({20, 20, 20}, Vec3(1, 1, 1), [](const Vec3&) { return true; }, 300.0, sigma);
  const image::Volume<float> other({10, 10, 10}, Vec3(1, 1, 1));
  EXPECT_THROW((void)estimate_intensity_model(s.ct, {Vec3(10, 10, 10)}, {.residual_ball_factor = 5}, other, 0.7),
               InvalidInput);
}

void expect_valid(const BalloonResult& r, std::int64_t euler) {
  EXPECT_TRUE(r.report.closed);
  EXPECT_TRUE(r.report.manifold);
  EXPECT_TRUE(r.report.oriented);
  EXPECT_EQ(r.report.self_intersections, 0);
  EXPECT_EQ(r.report.euler_characteristic, euler);
  const auto c = geometry::check_mesh(r.surface);
  EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
  EXPECT_EQ(c.euler_characteristic, euler);
  EXPECT_FALSE(geometry::has_self_intersections(r.surface));
}

TEST(Balloon, InflatesToSphereWall) {
  const Vec3 c(16.2, 15.7, 16.4);
  const double radius = 8.0;
  const auto s = make_volume({33, 33, 33}, Vec3(1, 1, 1), [&](const Vec3& p) { return (p - c).norm() < radius; }, 300.0, 60.0);
  const auto r = segment_balloon(s.ct, {Vec3(16, 16, 16)});
  expect_valid(r, 2);
  EXPECT_TRUE(r.report.converged);
  EXPECT_FALSE(r.report.leak_warning);
  EXPECT_TRUE(test::rel_near(r.report.volume_mm3, 4.0 / 3.0 * kPi * radius * radius * radius, 0.04));
  const double d = dice(surface_to_mask(r.surface, s.ct), s.truth);
  EXPECT_GE(d, 0.95);
  // Vertices lie on the wall: mean |distance − R| well below a voxel.
  double err = 0;
  double bias = 0;
  for (const Vec3& v : r.surface.vertices) err += std::abs((v - c).norm() - radius), bias += (v - c).norm() - radius;
  EXPECT_LT(err / double(r.surface.vertices.size()), 0.3);
}

TEST(Balloon, EdgeStageKeepsTheWallOfVerticesThatStoppedAndStaysOnTheWall) {
  // The per-vertex stop of the edge stage: vertices that barely moved since their last profile
  // search keep its wall. It must skip searches, and the surface it gives must lie on the wall
  // as well as the one that searches every vertex every step.
  const Vec3 c(16.2, 15.7, 16.4);
  const double radius = 8.0;
  const auto s = make_volume({33, 33, 33}, Vec3(1, 1, 1), [&](const Vec3& p) { return (p - c).norm() < radius; }, 300.0, 60.0);
  BalloonOptions every_step;
  every_step.edge_reuse_move_voxels = 0;
  const auto a = segment_balloon(s.ct, {Vec3(16, 16, 16)}, every_step);
  const auto b = segment_balloon(s.ct, {Vec3(16, 16, 16)});
  expect_valid(b, 2);
  EXPECT_EQ(a.report.edge_profile_reuses, 0);
  EXPECT_GT(a.report.edge_profile_searches, 0);
  // At least a third of the vertex-steps keep their wall on a converged sphere.
  EXPECT_GT(3 * b.report.edge_profile_reuses, b.report.edge_profile_searches + b.report.edge_profile_reuses);
  auto mean_error = [&](const geometry::TriangleMesh& m) {
    double err = 0;
    for (const Vec3& v : m.vertices) err += std::abs((v - c).norm() - radius);
    return err / double(m.vertices.size());
  };
  EXPECT_LT(mean_error(b.surface), 0.3);
  EXPECT_LT(std::abs(mean_error(b.surface) - mean_error(a.surface)), 0.02);
  EXPECT_NEAR(dice(surface_to_mask(b.surface, s.ct), s.truth), dice(surface_to_mask(a.surface, s.ct), s.truth), 0.003);
}

TEST(Balloon, MeetsItselfAroundTorusHoleAndBecomesGenusOne) {
  const Vec3 c(20, 20, 10);
  const double R = 10, rr = 4;
  auto in_torus = [&](const Vec3& p) {
    const Vec3 q = p - c;
    const double ring = std::hypot(q.x(), q.y()) - R;
    return ring * ring + q.z() * q.z() < rr * rr;
  };
  const auto s = make_volume({41, 41, 21}, Vec3(1, 1, 1), in_torus, 300.0, 30.0);
  const auto r = segment_balloon(s.ct, {c + Vec3(R, 0, 0)});
  expect_valid(r, 0);
  EXPECT_GE(r.report.repairs, 1);
  EXPECT_GE(dice(surface_to_mask(r.surface, s.ct), s.truth), 0.93);
}

TEST(Balloon, OneVoxelGapStopsTheSurface) {
  // Two bright boxes of the same grey level, 1 voxel of tissue between them.
  auto left = [](const Vec3& p) { return p.x() > 3.5 && p.x() < 14.5 && p.y() > 4.5 && p.y() < 15.5 && p.z() > 4.5 && p.z() < 15.5; };
  auto right = [](const Vec3& p) { return p.x() > 15.5 && p.x() < 26.5 && p.y() > 4.5 && p.y() < 15.5 && p.z() > 4.5 && p.z() < 15.5; };
  const auto s = make_volume({31, 21, 21}, Vec3(1, 1, 1), [&](const Vec3& p) { return left(p) || right(p); }, 300.0, 30.0);
  const auto r = segment_balloon(s.ct, {Vec3(9, 10, 10)});
  expect_valid(r, 2);
  const double box = 11.0 * 11.0 * 11.0;
  EXPECT_LT(r.report.volume_mm3, 1.15 * box);
  EXPECT_GT(r.report.volume_mm3, 0.85 * box);
}

// Overlapping closed spheres (a self-intersecting surface) → one closed, exact-checked
// surface of the union; a ring of overlapping spheres → a torus (Euler 0).
geometry::TriangleMesh union_of_spheres(const std::vector<Vec3>& centres, double r) {
  geometry::TriangleMesh m;
  for (const Vec3& c : centres) {
    const auto s = balloon_icosphere(c, r, 3);
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), s.vertices.begin(), s.vertices.end());
    for (const Tri& t : s.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return m;
}

TEST(TopologyRepair, MergesOverlapsIntoAValidSurfaceOfTheRightTopology) {
  TopologyRepairOptions ro;
  ro.grid_spacing_mm = 0.5;
  ro.target_edge_mm = 0.75;
  {
    const double r = 4.0, d = 4.0;  // two spheres, centres 4 mm apart
    const auto m = union_of_spheres({Vec3(0, 0, 0), Vec3(d, 0, 0)}, r);
    const auto pairs = geometry::self_intersections(m);
    ASSERT_FALSE(pairs.empty());
    const auto out = repair_topology(m, pairs, ro);
    const auto c = geometry::check_mesh(out);
    EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
    EXPECT_EQ(c.euler_characteristic, 2);
    EXPECT_FALSE(geometry::has_self_intersections(out));
    // Union of two balls: 2 · (4/3 π r³) − lens volume π (4r + d)(2r − d)² / 12.
    const double exact = 2 * 4.0 / 3.0 * kPi * r * r * r - kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
    EXPECT_TRUE(test::rel_near(c.signed_volume_mm3, exact, 0.05));
  }
  {
    std::vector<Vec3> ring;
    for (int i = 0; i < 10; ++i) ring.emplace_back(10 * std::cos(2 * kPi * i / 10), 10 * std::sin(2 * kPi * i / 10), 0);
    const auto m = union_of_spheres(ring, 3.5);  // neighbours 6.18 mm apart overlap by 0.8 mm
    const auto out = repair_topology(m, geometry::self_intersections(m), ro);
    const auto c = geometry::check_mesh(out);
    EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
    EXPECT_EQ(c.euler_characteristic, 0);
    EXPECT_EQ(c.components, 1);
    EXPECT_FALSE(geometry::has_self_intersections(out));
  }
  EXPECT_THROW((void)repair_topology(geometry::TriangleMesh{}, {}, ro), InvalidInput);
}

// A repair keeps what holds the seeds: of three disjoint spheres (one holding a seed, one
// holding none, one too small) only the seeded one stays; with no seed inside any, every
// sphere above the volume floor stays; an inward-facing sphere (a cavity) has negative
// volume and goes with the floor. Kept vertices are renumbered in order of first use.
TEST(TopologyRepair, KeepsTheComponentsHoldingASeed) {
  const auto three = union_of_spheres({Vec3(0, 0, 0), Vec3(20, 0, 0)}, 4.0);
  geometry::TriangleMesh m = three;
  {
    const auto small = balloon_icosphere(Vec3(-20, 0, 0), 0.5, 2);
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), small.vertices.begin(), small.vertices.end());
    for (const Tri& t : small.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  const double floor = 1.0;  // mm³: the r 0.5 sphere encloses ≈ 0.5
  const auto seeded = keep_components(m, floor, {Vec3(20.5, 0.3, -0.2)});
  auto c = geometry::check_mesh(seeded);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.euler_characteristic, 2);
  for (const Vec3& v : seeded.vertices) EXPECT_NEAR((v - Vec3(20, 0, 0)).norm(), 4.0, 1e-9);  // the sphere at x = 20
  EXPECT_EQ(seeded.triangles.size(), three.triangles.size() / 2);
  EXPECT_EQ(seeded.vertices.size(), three.vertices.size() / 2);
  // No component holds the point: the floor alone decides.
  const auto unseeded = keep_components(m, floor, {Vec3(10, 0, 0)});
  c = geometry::check_mesh(unseeded);
  EXPECT_EQ(c.components, 2);
  EXPECT_EQ(unseeded.triangles.size(), three.triangles.size());
  EXPECT_EQ(unseeded.vertices.size(), three.vertices.size());
  // A cavity: the inner sphere turned inward, inside the seeded sphere.
  geometry::TriangleMesh hollow = union_of_spheres({Vec3(0, 0, 0)}, 6.0);
  {
    const auto inner = balloon_icosphere(Vec3(0, 0, 0), 2.0, 2);
    const auto base = static_cast<std::int32_t>(hollow.vertices.size());
    hollow.vertices.insert(hollow.vertices.end(), inner.vertices.begin(), inner.vertices.end());
    for (const Tri& t : inner.triangles) hollow.triangles.push_back({t[0] + base, t[2] + base, t[1] + base});
  }
  const auto filled = keep_components(hollow, floor, {Vec3(4, 0, 0)});
  EXPECT_EQ(geometry::check_mesh(filled).components, 1);
  EXPECT_GT(geometry::check_mesh(filled).signed_volume_mm3, 4.0 / 3.0 * kPi * 5.9 * 5.9 * 5.9);
}

// The repair's signed distance evaluates the winding number only within about a grid spacing
// of the surface (and near uncounted triangles) and takes every other sign from a neighbour
// or a connected component. The full path — the winding number at every grid point, the
// distance to the nearest counted triangle by brute force — must give the same field. Both
// sign methods: the crossing parity these closed meshes take by default, and the winding
// number with its safe-step components.
void expect_field_equals_full_evaluation(const geometry::TriangleMesh& m, const image::Volume<float>& grid,
                                         meshing::SignedDistanceOptions o) {
  for (const auto method : {meshing::SignMethod::automatic, meshing::SignMethod::winding_number}) {
    o.sign = method;
    const image::Volume<float> f = meshing::signed_distance(m, grid, o);
    const geometry::WindingNumber winding(m, {.beta = o.winding_beta});
    std::int64_t wrong_sign = 0, wrong_distance = 0, inside = 0;
    for (std::int64_t k = 0; k < grid.size(2); ++k)
      for (std::int64_t j = 0; j < grid.size(1); ++j)
        for (std::int64_t i = 0; i < grid.size(0); ++i) {
          const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
          const bool in = winding.at(p) > 0.5;
          inside += in ? 1 : 0;
          if ((f(i, j, k) < 0.0f) != in) ++wrong_sign;
          double d = o.band_mm;
          for (std::size_t t = 0; t < m.triangles.size(); ++t) {
            if (!o.distance_triangles.empty() && !o.distance_triangles[t]) continue;
            const Tri& tr = m.triangles[t];
            const Vec3 c = meshing::closest_point_on_triangle_mm(p, m.vertices[tr[0]], m.vertices[tr[1]], m.vertices[tr[2]]);
            d = std::min(d, (c - p).norm());
          }
          if (std::abs(std::abs(double(f(i, j, k))) - d) > 1e-5) ++wrong_distance;
        }
    EXPECT_GT(inside, 0);
    EXPECT_EQ(wrong_sign, 0) << int(method);
    EXPECT_EQ(wrong_distance, 0) << int(method);
  }
}

// A vertex dragged past its neighbour folds its fan over the surface (pairs one ring apart):
// untangle_folds opens it in place, leaving every vertex outside its region bit for bit and
// the connectivity as it was; the surface is then closed, manifold and free of intersections.
// A spike pushed through the far side of the sphere meets triangles many rings away: not a fold,
// so nothing is touched and the caller must rebuild.
TEST(TopologyRepair, UntanglesAFoldInPlaceAndLeavesContactsToTheRebuild) {
  const geometry::TriangleMesh sphere = balloon_icosphere(Vec3::Zero(), 10.0, 3);
  // Vertex 0 and its first neighbour.
  std::int32_t w = -1;
  for (const Tri& t : sphere.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] == 0) w = t[(k + 1) % 3];
  ASSERT_GE(w, 0);
  geometry::TriangleMesh folded = sphere;
  folded.vertices[0] += 1.8 * (sphere.vertices[std::size_t(w)] - sphere.vertices[0]);
  const auto pairs = geometry::self_intersections(folded);
  ASSERT_FALSE(pairs.empty());
  geometry::TriangleMesh fixed_up = folded;
  const auto region = untangle_folds(fixed_up, pairs, {});
  ASSERT_TRUE(region.has_value());
  EXPECT_TRUE(geometry::self_intersections(fixed_up).empty());
  const auto c = geometry::check_mesh(fixed_up);
  EXPECT_TRUE(c.closed && c.edge_manifold && c.vertex_manifold && c.oriented);
  EXPECT_EQ(c.euler_characteristic, 2);
  EXPECT_EQ(fixed_up.triangles, folded.triangles);
  std::vector<std::uint8_t> in_region(folded.vertices.size(), 0);
  for (std::int32_t v : *region) in_region[std::size_t(v)] = 1;
  EXPECT_LT(region->size(), folded.vertices.size() / 10);
  for (std::size_t v = 0; v < folded.vertices.size(); ++v)
    if (!in_region[v]) {
      EXPECT_EQ(fixed_up.vertices[v], folded.vertices[v]) << v;
    }
  // With the dragged vertex's whole neighbourhood fixed, the fold cannot open.
  std::vector<std::uint8_t> fixed(folded.vertices.size(), 1);
  geometry::TriangleMesh stuck = folded;
  EXPECT_FALSE(untangle_folds(stuck, pairs, fixed).has_value());
  EXPECT_EQ(stuck.vertices, folded.vertices);
  // A contact: vertex 0 pushed through the sphere and out of its far side.
  geometry::TriangleMesh spiked = sphere;
  spiked.vertices[0] *= -1.3;
  const auto contact = geometry::self_intersections(spiked);
  ASSERT_FALSE(contact.empty());
  geometry::TriangleMesh untouched = spiked;
  EXPECT_FALSE(untangle_folds(untouched, contact, {}).has_value());
  EXPECT_EQ(untouched.vertices, spiked.vertices);
}

TEST(TopologyRepair, SignedDistanceFastSignEqualsWindingNumberEverywhere) {
  // Two overlapping spheres: the intersecting triangles are left out of the distance, as the
  // repair does, so grid points near them must still read the winding number directly.
  const auto two = union_of_spheres({Vec3(0, 0, 0), Vec3(3.0, 0, 0)}, 2.5);
  const auto pairs = geometry::self_intersections(two);
  ASSERT_FALSE(pairs.empty());
  meshing::SignedDistanceOptions o;
  o.band_mm = 1.0;
  o.distance_triangles.assign(two.triangles.size(), 1);
  for (const auto& [a, b] : pairs) o.distance_triangles[std::size_t(a)] = o.distance_triangles[std::size_t(b)] = 0;
  expect_field_equals_full_evaluation(two, image::Volume<float>({24, 16, 16}, Vec3::Constant(0.5), Vec3(-3.1, -3.9, -4.05)), o);
  // Uncounted triangles far from the counted ones: a second sphere left out of the distance
  // entirely still bounds an inside, which only the direct evaluations near it can see.
  const auto apart = union_of_spheres({Vec3(0, 0, 0), Vec3(6.0, 0, 0)}, 2.0);
  meshing::SignedDistanceOptions half;
  half.band_mm = 1.0;
  half.distance_triangles.assign(apart.triangles.size(), 1);
  std::fill(half.distance_triangles.begin() + std::ptrdiff_t(apart.triangles.size() / 2), half.distance_triangles.end(), 0);
  expect_field_equals_full_evaluation(apart, image::Volume<float>({26, 12, 12}, Vec3::Constant(0.5), Vec3(-3.1, -2.9, -2.95)), half);
  // Every triangle counted, an anisotropic rotated grid and a band of three spacings.
  meshing::SignedDistanceOptions all;
  all.band_mm = 3 * 0.7;
  image::Volume<float> rotated({20, 18, 14}, Vec3(0.45, 0.5, 0.7), Vec3(-4.2, -4.3, -4.4));
  rotated.set_direction(test::rotation(0.3, -0.2, 0.5));
  expect_field_equals_full_evaluation(two, rotated, all);
  // A ring of spheres (genus one once repaired): an inner far region the surface encloses.
  std::vector<Vec3> ring;
  for (int i = 0; i < 8; ++i) ring.emplace_back(6 * std::cos(2 * kPi * i / 8), 6 * std::sin(2 * kPi * i / 8), 0);
  const auto torus = union_of_spheres(ring, 2.6);
  expect_field_equals_full_evaluation(torus, image::Volume<float>({36, 36, 14}, Vec3::Constant(0.5), Vec3(-9.1, -8.9, -3.3)), all);
}

// The remesher's check of its input (each edge runs once each way) still rejects an open
// mesh and a mesh with one triangle turned over, and accepts the closed ones it remeshes.
TEST(TopologyRepair, RemesherInputCheckRejectsOpenAndMisorientedMeshes) {
  const auto s = balloon_icosphere(Vec3::Zero(), 2.0, 1);
  EXPECT_NO_THROW(meshing::SurfaceRemesher{s});
  auto open = s;
  open.triangles.pop_back();
  EXPECT_THROW(meshing::SurfaceRemesher{open}, InvalidInput);
  auto flipped = s;
  std::swap(flipped.triangles[3][0], flipped.triangles[3][1]);
  EXPECT_THROW(meshing::SurfaceRemesher{flipped}, InvalidInput);
  auto doubled = s;
  doubled.triangles.push_back(s.triangles[0]);
  EXPECT_THROW(meshing::SurfaceRemesher{doubled}, InvalidInput);
}

TEST(Balloon, RejectsBadInput) {
  const image::Volume<float> ct({10, 10, 10});
  EXPECT_THROW(Balloon(ct, {}), InvalidInput);
  EXPECT_THROW(Balloon(ct, {Vec3(50, 0, 0)}), InvalidInput);
  EXPECT_THROW(Balloon(image::Volume<float>{}, {Vec3(0, 0, 0)}), InvalidInput);
  BalloonOptions o;
  o.tolerance = -1.0;
  EXPECT_THROW(Balloon(ct, {Vec3(5, 5, 5)}, o), InvalidInput);
  for (const double reach : {-1.0, double(NAN), double(INFINITY)}) {
    BalloonOptions r;
    r.edge_reach_voxels = reach;
    EXPECT_THROW(Balloon(ct, {Vec3(5, 5, 5)}, r), InvalidInput) << reach;
  }
  // A grid too thin to hold a closed surface (a 1x1x1 volume used to inflate without end).
  EXPECT_THROW(Balloon(image::Volume<float>({1, 1, 1}), {Vec3(0, 0, 0)}), InvalidInput);
  EXPECT_THROW(Balloon(image::Volume<float>({64, 64, 2}), {Vec3(30, 30, 0)}), InvalidInput);
  BalloonOptions w;
  w.max_inflation_work = -1;
  EXPECT_THROW(Balloon(ct, {Vec3(5, 5, 5)}, w), InvalidInput);
  w = {};
  w.max_iterations = 0;
  EXPECT_THROW(Balloon(ct, {Vec3(5, 5, 5)}, w), InvalidInput);
}

// The work limit bounds a flood: a seed in a uniform block whose band is the whole grid stops
// once the inflation has moved that many vertices, with the leak warning and no edge stage.
TEST(Balloon, WorkLimitStopsAFloodAndSaysSo) {
  image::Volume<float> ct({60, 60, 60}, Vec3(1, 1, 1), Vec3::Zero(), Mat3::Identity(), 100.0f);
  BalloonOptions o;
  o.reference = 100;
  o.tolerance = 20;
  o.max_inflation_work = 20000;
  const BalloonResult r = segment_balloon(ct, {Vec3(30, 30, 30)}, o);
  EXPECT_EQ(r.report.stop_reason, "work_limit");
  EXPECT_TRUE(r.report.leak_warning);
  EXPECT_GT(r.report.inflation_vertex_steps, 20000);
  EXPECT_EQ(r.report.edge_profile_searches, 0);
  EXPECT_TRUE(r.report.closed && r.report.manifold);
}

}  // namespace
}  // namespace ido::segment

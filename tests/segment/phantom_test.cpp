// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/phantom.h"

#include <cmath>

#include <gtest/gtest.h>

#include "ido/geometry/mesh_checks.h"
#include "ido/meshing/marching_cubes.h"
#include "ido/segment/metrics.h"
#include "support/test_support.h"

namespace ido::segment {
using test::near;
using test::rel_near;

TEST(Phantom, KindNamesRoundTripAndUnknownIsRejected) {
  for (PhantomKind k : all_phantom_kinds()) EXPECT_EQ(parse_phantom_kind(phantom_kind_name(k)), k);
  EXPECT_EQ(parse_phantom_kind("Vessel_Tree"), PhantomKind::VesselTree);
  try {
    (void)parse_phantom_kind("banana");
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("banana"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("vertebra"), std::string::npos);
  }
}

TEST(Phantom, SameSeedGivesIdenticalBytesWithOrWithoutThreads) {
  PhantomOptions o{.spacing_mm = {1.2, 1.0, 1.5}, .noise_hu = 30.0, .blur_voxels = 0.7, .seed = 77};
  const Phantom a = make_phantom(PhantomKind::YBifurcation, o);
  o.threaded = false;
  const Phantom b = make_phantom(PhantomKind::YBifurcation, o);
  EXPECT_EQ(a.ct_hu.data(), b.ct_hu.data());
  EXPECT_EQ(a.labels.data(), b.labels.data());
  o.seed = 78;
  const Phantom c = make_phantom(PhantomKind::YBifurcation, o);
  EXPECT_NE(a.ct_hu.data(), c.ct_hu.data());
  EXPECT_EQ(a.labels.data(), c.labels.data());  // the truth does not depend on the noise
}

TEST(Phantom, NoiseSigmaMeasuredInFlatRegionMatchesRequest) {
  const double sigma = 60.0;
  const Phantom p = make_phantom(PhantomKind::Sphere, {.noise_hu = sigma, .seed = 5});
  const Phantom clean = make_phantom(PhantomKind::Sphere, {});
  // Flat soft tissue: 5 mm beyond the sphere, well inside the body cylinder.
  double sum = 0, sum2 = 0;
  std::size_t n = 0;
  for (std::int64_t k = 0; k < p.ct_hu.size(2); ++k)
    for (std::int64_t j = 0; j < p.ct_hu.size(1); ++j)
      for (std::int64_t i = 0; i < p.ct_hu.size(0); ++i) {
        const Vec3 w = p.ct_hu.index_to_world(Vec3(double(i), double(j), double(k)));
        const double r = (w - p.seeds_mm[0]).norm();
        if (r < 20.0 || std::hypot(w.x() - 24, w.y() - 24) > 20.0) continue;
        ASSERT_EQ(clean.ct_hu(i, j, k), 40.f);
        const double v = p.ct_hu(i, j, k);
        sum += v;
        sum2 += v * v;
        ++n;
      }
  ASSERT_GT(n, 10000u);
  const double mean = sum / double(n);
  const double sd = std::sqrt(sum2 / double(n) - mean * mean);
  EXPECT_TRUE(near(mean, 40.0, 4.0 * sigma / std::sqrt(double(n))));
  EXPECT_TRUE(rel_near(sd, sigma, 0.03));
}

TEST(Phantom, IntensitiesAndSeedsAreCtLike) {
  for (PhantomKind k : all_phantom_kinds()) {
    const Phantom p = make_phantom(k, {});
    ASSERT_FALSE(p.seeds_mm.empty());
    for (std::size_t s = 0; s < p.seeds_mm.size(); ++s) {
      const Index3 v = p.seeds_voxel[s];
      EXPECT_EQ(p.labels(v[0], v[1], v[2]), 1) << phantom_kind_name(k);
      EXPECT_TRUE(near(p.ct_hu(v[0], v[1], v[2]), p.object_hu, 1e-3)) << phantom_kind_name(k);
    }
    EXPECT_GT(p.contrast_hu, 150.0);
    EXPECT_EQ(count_components(p.labels), 1) << phantom_kind_name(k);
    EXPECT_FALSE(p.description.empty());
  }
}

/// The truth topology of every kind, isotropic and anisotropic, with the voxel formula
/// cross-checked against the marching-cubes surface of the label.
TEST(Phantom, TruthEulerCharacteristicsAreRightAndAgreeWithMarchingCubes) {
  const std::pair<PhantomKind, int> expected[] = {
      {PhantomKind::Sphere, 2},       {PhantomKind::Torus, 0},          {PhantomKind::YBifurcation, 2},
      {PhantomKind::UTube, 2},        {PhantomKind::VesselNearBone, 2}, {PhantomKind::VesselTree, 2},
      {PhantomKind::Vertebra, 0}};
  for (const Vec3& spacing : {Vec3(1.0, 1.0, 1.0), Vec3(0.8, 0.9, 1.6)}) {
    for (const auto& [kind, chi] : expected) {
      const Phantom p = make_phantom(kind, {.spacing_mm = spacing});
      EXPECT_EQ(p.truth_euler_characteristic, chi) << phantom_kind_name(kind) << " " << spacing.transpose();
      const auto mesh = meshing::marching_cubes_mask(p.labels);
      const auto r = geometry::check_mesh(mesh);
      EXPECT_TRUE(r.closed && r.edge_manifold && r.vertex_manifold && r.oriented);
      EXPECT_EQ(r.euler_characteristic, p.truth_euler_characteristic) << phantom_kind_name(kind);
      EXPECT_EQ(r.components, 1) << phantom_kind_name(kind);
    }
  }
}

TEST(Phantom, AnisotropicSpacingKeepsPhysicalSize) {
  for (const Vec3& spacing : {Vec3(1.0, 1.0, 1.0), Vec3(0.7, 0.9, 1.5)}) {
    for (PhantomKind k : {PhantomKind::Sphere, PhantomKind::Torus, PhantomKind::VesselNearBone}) {
      const Phantom p = make_phantom(k, {.spacing_mm = spacing});
      // The partial-volume intensities hold the object's volume: Σ (hu − 40) / 310 over the
      // voxels that are not bone or fat. 4³ midpoint samples per boundary voxel: the error is
      // about 0.5 % when the shape is aligned with the sample lattice (the vessel beside the
      // bone is, by construction), far below what a wrong spacing would give.
      // Beside the bone, only the vessel's side of the one-voxel gap counts.
      const double x_max = k == PhantomKind::VesselNearBone ? p.seeds_mm[0].x() + 5.0 + 0.5 * spacing.x() : 1e9;
      double vol = 0.0;
      for (std::int64_t kk = 0; kk < p.ct_hu.size(2); ++kk)
        for (std::int64_t j = 0; j < p.ct_hu.size(1); ++j)
          for (std::int64_t i = 0; i < p.ct_hu.size(0); ++i) {
            const double hu = p.ct_hu(i, j, kk);
            if (hu >= 40.0 && hu <= 350.0 && p.ct_hu.index_to_world(Vec3(double(i), 0, 0)).x() < x_max)
              vol += (hu - 40.0) / 310.0;
          }
      vol *= spacing.prod();
      EXPECT_TRUE(rel_near(vol, p.analytic_volume_mm3, 0.01)) << phantom_kind_name(k) << " " << spacing.transpose();
    }
    // Labels (more than half of a voxel inside) match the volume of a large object to 1 %;
    // thin ones (the 5 mm torus tube over 1.5 mm slices) are off by a few % by discretisation.
    const Phantom s = make_phantom(PhantomKind::Sphere, {.spacing_mm = spacing});
    const double label_vol = double(std::count(s.labels.data().begin(), s.labels.data().end(), 1)) * spacing.prod();
    EXPECT_TRUE(rel_near(label_vol, s.analytic_volume_mm3, 0.01));
    for (int a = 0; a < 3; ++a) EXPECT_TRUE(near(double(s.ct_hu.size(a)) * spacing[a], 48.0, spacing[a]));
    EXPECT_TRUE(near(s.ct_hu.sample(s.seeds_mm[0]), 350.0, 1e-3));
  }
}

TEST(Phantom, VesselAndBoneAreSeparatedByOneVoxelOfSoftTissue) {
  for (const Vec3& spacing : {Vec3(1.0, 1.0, 1.0), Vec3(0.6, 0.8, 1.5)}) {
    const Phantom p = make_phantom(PhantomKind::VesselNearBone, {.spacing_mm = spacing});
    const Index3 s = p.seeds_voxel[0];
    std::int64_t last = s[0];
    while (p.labels(last + 1, s[1], s[2])) ++last;
    EXPECT_TRUE(near(p.ct_hu(last, s[1], s[2]), 350.0, 1e-3));       // last vessel voxel: pure
    EXPECT_TRUE(near(p.ct_hu(last + 1, s[1], s[2]), 40.0, 1e-3));    // the gap: pure soft tissue
    EXPECT_GT(p.ct_hu(last + 2, s[1], s[2]), 1000.f);                // cortical bone
    EXPECT_EQ(p.labels(last + 2, s[1], s[2]), 0);                    // bone is not labelled
  }
}

TEST(Phantom, BlurTurnsTheWallIntoARampAndBadOptionsAreRejected) {
  const Phantom a = make_phantom(PhantomKind::Sphere, {});
  const Phantom b = make_phantom(PhantomKind::Sphere, {.blur_voxels = 1.0});
  const Vec3 c = a.seeds_mm[0];
  for (const Vec3& u : {Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0.6, 0.0, 0.8), Vec3(-0.48, 0.6, -0.64)}) {
    // Far from the wall the intensity is unchanged; on the wall (r = 15 mm) a blurred step
    // sits near the mean of the two sides, a little lower on a convex surface:
    // 40 + 310 · (½ − σ/(R·√(2π))) ≈ 187 HU for σ = 1 mm, R = 15 mm.
    EXPECT_TRUE(near(b.ct_hu.sample(c + 5.0 * u), 350.0, 0.5));
    EXPECT_TRUE(near(b.ct_hu.sample(c + 21.0 * u), 40.0, 0.5));
    EXPECT_TRUE(near(b.ct_hu.sample(c + 15.0 * u), 187.0, 15.0));
    EXPECT_GT(std::abs(b.ct_hu.sample(c + 15.7 * u) - a.ct_hu.sample(c + 15.7 * u)), 10.0);
  }
  EXPECT_THROW((void)make_phantom(PhantomKind::Sphere, {.spacing_mm = {1, 0, 1}}), InvalidInput);
  EXPECT_THROW((void)make_phantom(PhantomKind::Sphere, {.noise_hu = -1}), InvalidInput);
  EXPECT_THROW((void)make_phantom(PhantomKind::Sphere, {.blur_voxels = NAN}), InvalidInput);
}

}  // namespace ido::segment

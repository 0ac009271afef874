// SPDX-License-Identifier: Apache-2.0
// Calcified plaque added to a balloon's lumen (segment::add_calcification) on the
// calcified-vessel phantom: the plaques are gained, the bone beside the vessel is not, the
// reach limits what is taken, and the output stays a valid closed surface.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/self_intersection.h"
#include "ido/segment/balloon.h"
#include "ido/segment/calcification.h"
#include "ido/segment/metrics.h"
#include "ido/segment/phantom.h"

namespace ido::segment {
namespace {

struct Fixture {
  Phantom phantom;
  image::Volume<std::uint8_t> truth;  // label 1: lumen and plaque
  BalloonResult lumen;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    PhantomOptions po;
    po.blur_voxels = 0.7;
    po.seed = 11;
    po.noise_hu = 0.2 * make_phantom(PhantomKind::CalcifiedVessel, po).contrast_hu;
    Fixture out{make_phantom(PhantomKind::CalcifiedVessel, po), {}, {}};
    out.truth = out.phantom.labels.like(std::uint8_t{0});
    for (std::size_t i = 0; i < out.truth.voxel_count(); ++i)
      out.truth.data()[i] = out.phantom.labels.data()[i] == 1 ? 1 : 0;
    out.lumen = segment_balloon(out.phantom.ct_hu, out.phantom.seeds_mm);
    return out;
  }();
  return f;
}

/// Voxels of @p mask that the truth labels @p label.
std::int64_t voxels_labelled(const image::Volume<std::uint8_t>& mask, const Phantom& p, std::uint8_t label) {
  std::int64_t n = 0;
  for (std::size_t i = 0; i < mask.voxel_count(); ++i) n += mask.data()[i] && p.labels.data()[i] == label;
  return n;
}

TEST(Calcification, GainsThePlaquesAndNotTheBone) {
  const Fixture& f = fixture();
  // The threshold lies above the lumen's accepted band and below the plaque's cortical HU.
  const double band_top = f.lumen.report.model.reference + f.lumen.report.model.tolerance;
  const double threshold = 600.0;
  ASSERT_LT(band_top, threshold);
  const CalcificationResult c = add_calcification(f.lumen.surface, f.phantom.ct_hu, {.threshold = threshold});
  const auto lumen_mask = surface_to_mask(f.lumen.surface, f.phantom.ct_hu);
  const auto mask = surface_to_mask(c.surface, f.phantom.ct_hu);
  const SegmentationScores before = compare_masks(lumen_mask, f.truth), after = compare_masks(mask, f.truth);
  std::printf("lumen only: dice %.4f vr %.3f; with plaque: dice %.4f vr %.3f, %lld plaque voxels\n", before.dice,
              before.volume_ratio, after.dice, after.volume_ratio, static_cast<long long>(c.plaque_voxels));
  // Four balls of r 2.5 mm half outside the lumen: about 131 mm³ outside it, more with blur.
  EXPECT_GT(c.plaque_volume_mm3, 100.0);
  EXPECT_LT(c.plaque_volume_mm3, 400.0);
  EXPECT_GE(after.dice, 0.965);
  EXPECT_GT(after.dice, before.dice + 0.015);
  EXPECT_EQ(voxels_labelled(mask, f.phantom, 2), 0) << "bone 2 mm beside the vessel was taken as plaque";
  const geometry::MeshCheckReport check = geometry::check_mesh(c.surface);
  EXPECT_TRUE(check.closed);
  EXPECT_TRUE(check.edge_manifold && check.vertex_manifold);
  EXPECT_TRUE(check.oriented);
  EXPECT_EQ(check.components, 1);  // every plaque joined to the lumen
  EXPECT_EQ(check.euler_characteristic, 2);
  EXPECT_FALSE(geometry::has_self_intersections(c.surface));
}

TEST(Calcification, ReachLimitsWhatIsTaken) {
  const Fixture& f = fixture();
  double previous = 0.0;
  for (double reach : {1.0, 2.0, 4.0}) {
    const CalcificationResult c =
        add_calcification(f.lumen.surface, f.phantom.ct_hu, {.threshold = 600.0, .max_reach_mm = reach});
    // Every plaque voxel lies within the reach of a lumen voxel.
    const auto lumen_mask = surface_to_mask(f.lumen.surface, f.phantom.ct_hu);
    const auto mask = surface_to_mask(c.surface, f.phantom.ct_hu);
    for (std::int64_t k = 0; k < mask.size(2); ++k)
      for (std::int64_t j = 0; j < mask.size(1); ++j)
        for (std::int64_t i = 0; i < mask.size(0); ++i) {
          if (!mask(i, j, k) || lumen_mask(i, j, k)) continue;
          bool near = false;
          const auto r = static_cast<std::int64_t>(std::ceil(reach)) + 1;
          for (std::int64_t c3 = k - r; c3 <= k + r && !near; ++c3)
            for (std::int64_t c2 = j - r; c2 <= j + r && !near; ++c2)
              for (std::int64_t c1 = i - r; c1 <= i + r && !near; ++c1)
                near = lumen_mask.contains(c1, c2, c3) && lumen_mask(c1, c2, c3) &&
                       std::hypot(double(c1 - i), double(c2 - j), double(c3 - k)) <= reach + 1.0;
          ASSERT_TRUE(near) << "voxel " << i << "," << j << "," << k << " beyond the reach " << reach << " mm";
        }
    EXPECT_GT(c.plaque_volume_mm3, previous) << reach;
    previous = c.plaque_volume_mm3;
  }
}

TEST(Calcification, NothingBrighterLeavesTheSurfaceUnchanged) {
  const Fixture& f = fixture();
  const CalcificationResult c = add_calcification(f.lumen.surface, f.phantom.ct_hu, {.threshold = 1e5});
  EXPECT_EQ(c.plaque_voxels, 0);
  EXPECT_EQ(c.surface.vertices, f.lumen.surface.vertices);
  EXPECT_EQ(c.surface.triangles, f.lumen.surface.triangles);
}

TEST(Calcification, RejectsBadOptions) {
  const Fixture& f = fixture();
  EXPECT_THROW((void)add_calcification(f.lumen.surface, f.phantom.ct_hu, {.threshold = NAN}), InvalidInput);
  EXPECT_THROW((void)add_calcification(f.lumen.surface, f.phantom.ct_hu, {.threshold = 600, .max_reach_mm = 0}),
               InvalidInput);
  EXPECT_THROW((void)add_calcification({}, f.phantom.ct_hu, {.threshold = 600}), InvalidInput);
  EXPECT_THROW((void)add_calcification(f.lumen.surface, image::Volume<float>{}, {.threshold = 600}), InvalidInput);
}

}  // namespace
}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/leak_guard.h"

#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/image/filters.h"
#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"

namespace ido::segment {
namespace {

// 350 HU where inside(p), 40 HU elsewhere, blurred by σ = 0.7 mm, with white noise of σ = 15 HU,
// on a 1-mm grid of @p size voxels (origin 0).
image::Volume<float> vessel_volume(Index3 size, const std::function<bool(const Vec3&)>& inside) {
  image::Volume<float> v(size, Vec3(1, 1, 1));
  for (std::int64_t k = 0; k < size[2]; ++k)
    for (std::int64_t j = 0; j < size[1]; ++j)
      for (std::int64_t i = 0; i < size[0]; ++i) v(i, j, k) = inside(Vec3(double(i), double(j), double(k))) ? 350.f : 40.f;
  v = image::gaussian_smooth(v, 0.7);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 15.f);
  for (float& x : v.data()) x += noise(rng);
  return v;
}

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

// A tube of radius 4 mm along z from z = 4 to z = 44 opening into a ball of radius 14 mm centred
// at z = 58: a vessel leaving a chamber of the same grey level.
bool tube_and_chamber(const Vec3& p) {
  return segment_distance(p, Vec3(24, 24, 4), Vec3(24, 24, 46)) <= 4.0 || (p - Vec3(24, 24, 58)).norm() <= 14.0;
}

TEST(LeakGuard, ClosesAChamberWiderThanTheSeedRegion) {
  const auto ct = vessel_volume({48, 48, 76}, tube_and_chamber);
  const image::Volume<float> smoothed = image::gaussian_smooth(ct, 0.7);
  const IntensityModel model{350, 120};
  const LeakGuard guard(smoothed, model, {Vec3(24, 24, 16)}, {});
  ASSERT_TRUE(guard.active());
  // The seed region's radius is the tube's (4 mm, read between voxel centres, so within a voxel).
  EXPECT_NEAR(guard.seed_radius_mm(), 4.0, 1.0);
  EXPECT_NEAR(guard.chamber_radius_mm(), 2.5 * guard.seed_radius_mm(), 1e-9);
  EXPECT_EQ(guard.cause_at(Vec3(24, 24, 58)), LeakCause::Chamber);  // the chamber's centre
  EXPECT_EQ(guard.cause_at(Vec3(24, 24, 68)), LeakCause::Chamber);  // its far side
  EXPECT_EQ(guard.cause_at(Vec3(24, 24, 30)), LeakCause::None);     // the tube
  EXPECT_EQ(guard.cause_at(Vec3(24, 24, 16)), LeakCause::None);     // the seed
  // Off: nothing closed.
  LeakControlOptions off;
  off.enabled = false;
  EXPECT_FALSE(LeakGuard(smoothed, model, {Vec3(24, 24, 16)}, off).active());
}

// An aorta leaving the heart, at scale: a tube of radius 6 mm (z = 4–40), a root 1.4 times as
// wide (r 8.4 mm, z = 40–50, the sinuses), then a chamber of radius 13 mm centred at z = 64 —
// a left ventricle's inscribed radius is about twice the descending aorta's (21–29 mm against
// 10–14 mm), not the 4× of the valve-chamber phantom.
bool aorta_root_and_ventricle(const Vec3& p) {
  return segment_distance(p, Vec3(24, 24, 4), Vec3(24, 24, 40)) <= 6.0 ||
         segment_distance(p, Vec3(24, 24, 40), Vec3(24, 24, 50)) <= 8.4 || (p - Vec3(24, 24, 64)).norm() <= 13.0;
}

// A tube running through a chamber 60 HU darker than it (4 sigmas of the noise; a vein through
// the liver that wraps it): the band holds both, the chamber is closed, and the tube's voxels
// inside it are opened again because they are nearer the seed's level, so the tube beyond is
// reached. A chamber of the tube's own level keeps the tube closed where it passes through.
TEST(LeakGuard, ATubeThroughAChamberOfAnotherLevelStaysOpen) {
  for (const float chamber_hu : {290.f, 350.f}) {
    auto ct = vessel_volume({48, 48, 80}, [](const Vec3& p) {
      return segment_distance(p, Vec3(24, 24, 4), Vec3(24, 24, 76)) <= 4.0 || (p - Vec3(24, 24, 40)).norm() <= 16.0;
    });
    // Repaint the chamber off the tube at its own level (the blur's rim stays as it was).
    for (std::int64_t k = 0; k < 80; ++k)
      for (std::int64_t j = 0; j < 48; ++j)
        for (std::int64_t i = 0; i < 48; ++i) {
          const Vec3 p{double(i), double(j), double(k)};
          if ((p - Vec3(24, 24, 40)).norm() <= 15.0 && segment_distance(p, Vec3(24, 24, 4), Vec3(24, 24, 76)) > 5.0)
            ct(i, j, k) += chamber_hu - 350.f;
        }
    const image::Volume<float> smoothed = image::gaussian_smooth(ct, 0.7);
    const LeakGuard guard(smoothed, {350, 120}, {Vec3(24, 24, 12)}, {});
    ASSERT_TRUE(std::isfinite(guard.chamber_radius_mm())) << chamber_hu;
    EXPECT_EQ(guard.cause_at(Vec3(34, 24, 40)), LeakCause::Chamber) << chamber_hu;  // the chamber off the tube
    const LeakCause on_axis = guard.cause_at(Vec3(24, 24, 40));
    if (chamber_hu < 350.f) {
      EXPECT_EQ(on_axis, LeakCause::None);
      EXPECT_EQ(guard.cause_at(Vec3(24, 24, 66)), LeakCause::None);  // the tube past the chamber
    } else {
      EXPECT_EQ(on_axis, LeakCause::Chamber);
    }
  }
}

TEST(LeakGuard, TheArteryChoiceClosesAVentricleTwiceTheAortasRadiusButNotTheRoot) {
  const auto ct = vessel_volume({48, 48, 80}, aorta_root_and_ventricle);
  const image::Volume<float> smoothed = image::gaussian_smooth(ct, 0.7);
  const IntensityModel model{350, 120};
  const Vec3 seed(24, 24, 16);
  const LeakGuard artery(smoothed, model, {seed}, organ_options(Organ::Artery).leak);
  EXPECT_NEAR(artery.seed_radius_mm(), 6.0, 1.0);
  EXPECT_EQ(artery.cause_at(Vec3(24, 24, 64)), LeakCause::Chamber);  // the ventricle's centre
  EXPECT_EQ(artery.cause_at(Vec3(24, 24, 72)), LeakCause::Chamber);  // its far side
  EXPECT_EQ(artery.cause_at(Vec3(24, 24, 45)), LeakCause::None);     // the root
  EXPECT_EQ(artery.cause_at(Vec3(24, 24, 30)), LeakCause::None);     // the tube
  // The generic default (2.5 × the seed's radius) lets such a ventricle through.
  const LeakGuard generic(smoothed, model, {seed}, BalloonOptions{}.leak);
  EXPECT_EQ(generic.cause_at(Vec3(24, 24, 64)), LeakCause::None);
}

TEST(LeakGuard, TheBalloonStopsAtTheNeckAndReportsIt) {
  const auto ct = vessel_volume({48, 48, 76}, tube_and_chamber);
  BalloonOptions o;
  o.reference = 350;
  o.tolerance = 120;
  const BalloonResult guarded = segment_balloon(ct, {Vec3(24, 24, 16)}, o);
  o.leak.enabled = false;
  const BalloonResult flooded = segment_balloon(ct, {Vec3(24, 24, 16)}, o);
  const double tube = kPi * 16.0 * 42.0, chamber = 4.0 / 3.0 * kPi * 14.0 * 14.0 * 14.0;
  // Without the guard the balloon fills the chamber; with it, the tube and at most a cap of it.
  EXPECT_GT(flooded.report.volume_mm3, tube + 0.8 * chamber);
  EXPECT_LT(guarded.report.volume_mm3, tube + 0.15 * chamber);
  EXPECT_GT(guarded.report.volume_mm3, 0.8 * tube);
  EXPECT_TRUE(guarded.report.closed && guarded.report.manifold);
  ASSERT_FALSE(guarded.report.leaks.empty());
  const LeakEvent& e = guarded.report.leaks.front();
  EXPECT_EQ(e.cause, LeakCause::Chamber);
  // Where the tube meets the chamber (z ≈ 44), not far inside either.
  EXPECT_NEAR(e.position_mm.z(), 44.0, 8.0);
  EXPECT_GT(e.neck_radius_mm, 1.0);
  EXPECT_TRUE(flooded.report.leaks.empty());
}

TEST(LeakGuard, AStopPointClosesTheVesselBeyondIt) {
  const auto ct = vessel_volume({40, 40, 80}, [](const Vec3& p) { return segment_distance(p, Vec3(20, 20, 4), Vec3(20, 20, 76)) <= 5.0; });
  BalloonOptions o;
  o.reference = 350;
  o.tolerance = 120;
  o.leak.stop_points_mm = {Vec3(20, 20, 50)};
  const BalloonResult r = segment_balloon(ct, {Vec3(20, 20, 20)}, o);
  double zmax = -INFINITY;
  for (const Vec3& v : r.surface.vertices) zmax = std::max(zmax, v.z());
  // The ball closed around the stop point has 1.5 × the local radius (5 mm): the front halts before it.
  EXPECT_LT(zmax, 50.0 - 5.0);
  EXPECT_GT(zmax, 50.0 - 12.0);
  ASSERT_FALSE(r.report.leaks.empty());
  EXPECT_EQ(r.report.leaks.front().cause, LeakCause::StopPoint);
  // The report records the user's controls of the run.
  ASSERT_EQ(r.report.stop_points_mm.size(), 1u);
  EXPECT_EQ(r.report.stop_points_mm[0], Vec3(20, 20, 50));
  EXPECT_TRUE(std::isinf(r.report.max_radius_mm));
}

TEST(LeakGuard, MaxRadiusClosesWhereAWiderBallFits) {
  const auto ct = vessel_volume({48, 48, 76}, tube_and_chamber);
  const image::Volume<float> smoothed = image::gaussian_smooth(ct, 0.7);
  LeakControlOptions o;
  o.chamber_factor = 0;
  o.max_radius_mm = 8.0;
  const LeakGuard guard(smoothed, {350, 120}, {Vec3(24, 24, 16)}, o);
  EXPECT_EQ(guard.cause_at(Vec3(24, 24, 58)), LeakCause::Chamber);
  EXPECT_EQ(guard.cause_at(Vec3(24, 24, 30)), LeakCause::None);
}

// A column of vertebral bodies along z on a 1 x 1 x 2 mm grid (a 2 mm-slice scan): a cylinder
// of radius 12 mm whose slices k have the grey levels of @p slices (HU), 40 HU around it,
// blurred by 0.7 voxel. Slices of @p disc HU have a bony rim (r > 9 mm, @p rim HU), as real
// neighbours touch through osteophytes. Slices are 2 mm apart: slice k lies at z = 2k mm.
image::Volume<float> column_volume(const std::vector<float>& slices, float disc, float rim) {
  const auto nz = std::int64_t(slices.size());
  image::Volume<float> v({40, 40, nz}, Vec3(1, 1, 2));
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < 40; ++j)
      for (std::int64_t i = 0; i < 40; ++i) {
        const double r = std::hypot(double(i) - 20.0, double(j) - 20.0);
        const float x = slices[std::size_t(k)];
        v(i, j, k) = r > 12.0 ? 40.f : (x == disc && r > 9.0 ? rim : x);
      }
  return image::gaussian_smooth(v, 0.7);
}

// A body is darker in places than at its end plates. Where its disc lies in the image's last
// slices, the dip is the only valley with a far side, and once cut the body in half; the image
// ending in a valley as deep as the disc now ranks it, so no neighbour is put there. With the
// neighbour in view the disc is still found.
TEST(LeakGuard, ABodyWhoseDiscLiesAtTheImagesBorderIsNotCutAtItsOwnDip) {
  const float disc = 70, plate = 190, marrow = 150, dip = 130;
  LeakControlOptions o;
  o.separate_neighbours = true;
  const IntensityModel bone{marrow, 50, true};
  // Slices 0-1 the disc, 2-3 the end plate, 6-7 the dip, marrow up to the image's top.
  std::vector<float> cut = {disc, disc, plate, plate, marrow, marrow, dip, dip};
  cut.resize(20, marrow);
  const LeakGuard at_border(column_volume(cut, disc, plate), bone, {Vec3(20, 20, 20)}, o);
  ASSERT_TRUE(at_border.active());
  EXPECT_TRUE(at_border.neighbour_markers_mm().empty());
  EXPECT_EQ(at_border.cause_at(Vec3(20, 20, 6)), LeakCause::None);  // the body's lower end plate
  EXPECT_EQ(at_border.cause_at(Vec3(20, 20, 10)), LeakCause::None);

  // The same body with its neighbour below: slices 0-7 the neighbour's marrow, 8-9 its end
  // plate, 10-11 the disc, then the body above as before (seed at slice 22).
  std::vector<float> stack = {marrow, marrow, marrow, marrow, marrow, marrow, marrow, marrow, plate, plate};
  stack.insert(stack.end(), cut.begin(), cut.end());
  const LeakGuard with_neighbour(column_volume(stack, disc, plate), bone, {Vec3(20, 20, 44)}, o);
  ASSERT_EQ(with_neighbour.neighbour_markers_mm().size(), 1u);
  EXPECT_LT(with_neighbour.neighbour_markers_mm().front().z(), 20.0);  // below the disc (z 20-22 mm)
  EXPECT_EQ(with_neighbour.cause_at(Vec3(20, 20, 6)), LeakCause::Neighbour);
  EXPECT_EQ(with_neighbour.cause_at(Vec3(20, 20, 26)), LeakCause::None);  // the seed's end plate
  EXPECT_EQ(with_neighbour.cause_at(Vec3(20, 20, 34)), LeakCause::None);  // its dip
}

// The competition between the seed's body and its neighbours reaches 3 x neighbour_search_mm
// of steps from the markers; what lies farther is not the seed's vertebra (a bone band that takes
// in a whole MRA, or a contrast scan's vessels, was visited whole: vmtk-aorta with the vertebra
// choice 1.8 s of set-up). A column going on above the seed with no disc: open within reach,
// closed past it.
TEST(LeakGuard, TheSeedsTerritoryEndsAtThreeSearchLengths) {
  const float disc = 70, plate = 190, marrow = 150;
  LeakControlOptions o;
  o.separate_neighbours = true;
  o.neighbour_search_mm = 20.0;  // reach: 60 mm of steps
  const IntensityModel bone{marrow, 50, true};
  // Slices 0-7 the neighbour's marrow, 8-9 its end plate, 10-11 the disc, 12-13 the seed's end
  // plate, then its marrow up to slice 69 (z = 138 mm); the seed at slice 20 (z = 40 mm).
  std::vector<float> stack = {marrow, marrow, marrow, marrow, marrow, marrow, marrow, marrow, plate, plate,
                              disc,   disc,   plate,  plate};
  stack.resize(70, marrow);
  const LeakGuard guard(column_volume(stack, disc, plate), bone, {Vec3(20, 20, 40)}, o);
  ASSERT_EQ(guard.neighbour_markers_mm().size(), 1u);
  EXPECT_EQ(guard.cause_at(Vec3(20, 20, 6)), LeakCause::Neighbour);  // below the disc
  EXPECT_EQ(guard.cause_at(Vec3(20, 20, 80)), LeakCause::None);       // 40 mm above the seed
  EXPECT_EQ(guard.cause_at(Vec3(20, 20, 120)), LeakCause::Neighbour); // 80 mm above it
}

TEST(LeakGuard, RejectsBadOptions) {
  const auto ct = vessel_volume({16, 16, 16}, [](const Vec3& p) { return (p - Vec3(8, 8, 8)).norm() < 5; });
  LeakControlOptions o;
  o.chamber_factor = 0.5;
  EXPECT_THROW(LeakGuard(ct, {350, 100}, {Vec3(8, 8, 8)}, o), InvalidInput);
  o = {};
  o.max_radius_mm = -1;
  EXPECT_THROW(LeakGuard(ct, {350, 100}, {Vec3(8, 8, 8)}, o), InvalidInput);
  o = {};
  o.stop_points_mm = {Vec3(100, 0, 0)};
  EXPECT_THROW(LeakGuard(ct, {350, 100}, {Vec3(8, 8, 8)}, o), InvalidInput);
}

TEST(Organ, NamesRoundTripAndUnknownIsRejected) {
  for (Organ o : {Organ::Generic, Organ::Artery, Organ::Vein, Organ::Vertebra}) EXPECT_EQ(parse_organ(organ_name(o)), o);
  EXPECT_THROW((void)parse_organ("liver"), InvalidInput);
  EXPECT_TRUE(organ_options(Organ::Vertebra).accept_brighter);
  EXPECT_TRUE(organ_options(Organ::Vertebra).leak.separate_neighbours);
  EXPECT_EQ(organ_options(Organ::Artery).outside_level, 40.0);
}

}  // namespace
}  // namespace ido::segment

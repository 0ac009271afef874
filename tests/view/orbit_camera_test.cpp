// SPDX-License-Identifier: Apache-2.0
// The 3-D view's orbit camera: framing shows the box whole down to 3:4, drags turn and pan it
// as documented, and the pick ray goes through the pixel it was asked for.
#include "ido/view/orbit_camera.h"

#include <array>
#include <cmath>
#include <utility>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido {
namespace {

// Pixel (x right, y down, (0, 0) top-left) of world point @p p in a width × height view.
std::array<double, 2> pixel_of(const view::OrbitCamera& cam, const Vec3& p, double width, double height) {
  const viz::Camera c = cam.camera();
  const Vec4 h = c.projection_matrix(width / height) * c.view_matrix() * Vec4(p.x(), p.y(), p.z(), 1.0);
  return {(h.x() / h.w() + 1.0) / 2.0 * width, (1.0 - h.y() / h.w()) / 2.0 * height};
}

TEST(OrbitCamera, CentreRayHitsTheTargetAndTurningKeepsTheDistance) {
  view::OrbitCamera cam;
  cam.frame(Vec3(-10, -20, 0), Vec3(30, 20, 50));
  const Vec3 target = cam.target();
  for (int turn = 0; turn < 4; ++turn) {
    const auto [origin, dir] = cam.pick_ray(200, 150, 400, 300);
    const double along = (target - origin).dot(dir);
    EXPECT_TRUE(test::near((origin + along * dir - target).norm(), 0.0, 1e-9));
    EXPECT_TRUE(test::near((cam.camera().eye() - target).norm(), cam.distance_mm(), 1e-9));
    cam.rotate(37, -11);
  }
  // A pixel right of the centre looks right of the target.
  const auto [o, d] = cam.pick_ray(300, 150, 400, 300);
  const Mat4 view = cam.camera().view_matrix();
  const Vec3 right = view.block<1, 3>(0, 0).transpose();
  EXPECT_GT(d.dot(right), 0.0);
  const double before = cam.distance_mm();
  cam.zoom(2);
  EXPECT_TRUE(test::near(cam.distance_mm(), before * 0.81, 1e-9));
}

TEST(OrbitCamera, FramedBoxIsWholeInViewsDownToThreeByFour) {
  const Vec3 lo(-12, 3, -40), hi(25, 40, 10);
  for (const double az : {0.0, 30.0, 135.0, 300.0})
    for (const double el : {-60.0, 0.0, 20.0, 85.0}) {
      view::OrbitCamera cam;
      cam.frame(lo, hi, az, el);
      EXPECT_EQ(cam.azimuth_deg(), az);
      EXPECT_EQ(cam.elevation_deg(), el);
      EXPECT_TRUE(cam.target().isApprox(0.5 * (lo + hi), 1e-12));
      const viz::Camera c = cam.camera();
      EXPECT_EQ(c.projection, viz::Projection::Perspective);
      EXPECT_EQ(c.fov_y_deg, 30.0);
      for (const double aspect : {0.75, 1.0, 16.0 / 9.0}) {
        const Mat4 m = c.projection_matrix(aspect) * c.view_matrix();
        for (int k = 0; k < 8; ++k) {
          const Vec3 p((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
          const Vec4 h = m * Vec4(p.x(), p.y(), p.z(), 1.0);
          EXPECT_LE(std::abs(h.x() / h.w()), 1.0) << az << " " << el << " " << aspect;
          EXPECT_LE(std::abs(h.y() / h.w()), 1.0) << az << " " << el << " " << aspect;
          EXPECT_LE(std::abs(h.z() / h.w()), 1.0) << "outside near/far";
        }
      }
    }
}

TEST(OrbitCamera, DragsTurnPointFourDegreesPerTenPixelsAndStopShortOfThePoles) {
  view::OrbitCamera cam;
  cam.frame(Vec3(0, 0, 0), Vec3(10, 10, 10), 30.0, 20.0);
  cam.rotate(10, 0);
  EXPECT_TRUE(test::near(cam.azimuth_deg(), 26.0, 1e-12));
  cam.rotate(0, 25);
  EXPECT_TRUE(test::near(cam.elevation_deg(), 30.0, 1e-12));
  cam.rotate(0, 1000);
  EXPECT_EQ(cam.elevation_deg(), 89.0);
  cam.rotate(0, -5000);
  EXPECT_EQ(cam.elevation_deg(), -89.0);
  // A turn keeps the target and the distance.
  const Vec3 target = cam.target();
  const double d = cam.distance_mm();
  cam.rotate(-123, 45);
  EXPECT_EQ(cam.target(), target);
  EXPECT_EQ(cam.distance_mm(), d);
  // Zoom: 0.9 per notch, never closer than 1 mm.
  cam.zoom(-1);
  EXPECT_TRUE(test::near(cam.distance_mm(), d / 0.9, 1e-9));
  cam.zoom(1000);
  EXPECT_EQ(cam.distance_mm(), 1.0);
}

TEST(OrbitCamera, PanMovesTheSceneWithTheDrag) {
  const double w = 800, h = 600;
  view::OrbitCamera cam;
  cam.frame(Vec3(-5, -5, -5), Vec3(5, 5, 5), 40.0, 25.0);
  const Vec3 old_target = cam.target();
  const auto before = pixel_of(cam, old_target, w, h);
  EXPECT_TRUE(test::near(before[0], w / 2, 1e-9));
  EXPECT_TRUE(test::near(before[1], h / 2, 1e-9));
  cam.pan(30, -20, h);
  // What was under the cursor at the centre follows it: 30 px right, 20 px up.
  const auto after = pixel_of(cam, old_target, w, h);
  EXPECT_TRUE(test::near(after[0], w / 2 + 30, 1e-6));
  EXPECT_TRUE(test::near(after[1], h / 2 - 20, 1e-6));
}

TEST(OrbitCamera, PickRayThroughEveryPixelProjectsBackToIt) {
  view::OrbitCamera cam;
  cam.frame(Vec3(-20, 0, 5), Vec3(20, 30, 45), 210.0, -35.0);
  const double w = 640, h = 360;
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {639.0, 0.0}, {320.0, 180.0}, {17.5, 301.25}, {600.0, 359.0}}) {
    const auto [origin, dir] = cam.pick_ray(x, y, w, h);
    EXPECT_TRUE(test::near(dir.norm(), 1.0, 1e-12));
    EXPECT_TRUE(origin.isApprox(cam.camera().eye(), 1e-12));
    for (const double s : {cam.distance_mm() * 0.5, cam.distance_mm(), cam.distance_mm() * 1.5}) {
      const auto p = pixel_of(cam, origin + s * dir, w, h);
      EXPECT_TRUE(test::near(p[0], x, 1e-6)) << x << "," << y;
      EXPECT_TRUE(test::near(p[1], y, 1e-6)) << x << "," << y;
    }
  }
}

}  // namespace
}  // namespace ido

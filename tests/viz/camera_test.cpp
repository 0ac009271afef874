// SPDX-License-Identifier: Apache-2.0
// The look-at camera: the view matrix is a rigid motion putting the eye at the origin looking
// down −z with `up` on +y; the projections map the frustum's corners to the NDC cube; orbit()
// frames the whole box at every angle and aspect.
#include "ido/viz/camera.h"

#include <cmath>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido::viz {
namespace {

Vec3 transform(const Mat4& m, const Vec3& p) {
  const Vec4 h = m * Vec4(p.x(), p.y(), p.z(), 1.0);
  return h.head<3>() / h.w();
}

TEST(Camera, ViewMatrixIsARigidMotionToTheEyeFrame) {
  Camera c;
  c.target = Vec3(3, -2, 7);
  c.direction = Vec3(1, -2, 0.5).normalized();
  c.up = Vec3(0, 0, 1);
  c.distance_mm = 40;
  EXPECT_TRUE(test::near((c.eye() - (c.target + 40 * c.direction)).norm(), 0.0, 1e-12));
  const Mat4 v = c.view_matrix();
  const Mat3 r = v.block<3, 3>(0, 0);
  EXPECT_TRUE((r * r.transpose()).isApprox(Mat3::Identity(), 1e-12));
  EXPECT_TRUE(test::near(r.determinant(), 1.0, 1e-12));
  EXPECT_TRUE(v.row(3).isApprox(Vec4(0, 0, 0, 1).transpose()));
  // The eye goes to the origin, the target straight ahead on −z at the distance.
  EXPECT_TRUE(transform(v, c.eye()).isZero(1e-12));
  EXPECT_TRUE(transform(v, c.target).isApprox(Vec3(0, 0, -40), 1e-12));
  // Up is shown upwards: a point above the target has x = 0 and y > 0 in the eye frame.
  const Vec3 above = transform(v, c.target + Vec3(0, 0, 5));
  EXPECT_TRUE(test::near(above.x(), 0.0, 1e-12));
  EXPECT_GT(above.y(), 0.0);
  // Right-handed: eye x = y × z, so a point to the right of the view direction has x > 0.
  const Vec3 right = (-c.direction).cross(c.up).normalized();
  EXPECT_GT(transform(v, c.target + right).x(), 0.0);
  // An up parallel to the direction still gives a rigid motion (the documented precondition is
  // broken, but no NaN comes out).
  c.up = c.direction;
  EXPECT_TRUE(c.view_matrix().allFinite());
  EXPECT_TRUE(test::near(c.view_matrix().block<3, 3>(0, 0).determinant(), 1.0, 1e-12));
}

TEST(Camera, PerspectiveMapsTheFrustumToTheNdcCube) {
  Camera c;
  c.projection = Projection::Perspective;
  c.fov_y_deg = 40;
  c.near_mm = 2;
  c.far_mm = 300;
  const double aspect = 1.6;
  const Mat4 p = c.projection_matrix(aspect);
  const double t = std::tan(20.0 * kPi / 180.0);
  for (const double d : {2.0, 17.0, 300.0}) {
    // The frustum's corner at depth d (eye coordinates, looking down −z).
    const Vec3 ndc = transform(p, Vec3(d * t * aspect, d * t, -d));
    EXPECT_TRUE(test::near(ndc.x(), 1.0, 1e-12)) << d;
    EXPECT_TRUE(test::near(ndc.y(), 1.0, 1e-12)) << d;
  }
  EXPECT_TRUE(test::near(transform(p, Vec3(0, 0, -2)).z(), -1.0, 1e-12));
  EXPECT_TRUE(test::near(transform(p, Vec3(0, 0, -300)).z(), 1.0, 1e-12));
  // Farther points are smaller in the picture; depth grows monotonically.
  EXPECT_GT(transform(p, Vec3(1, 0, -10)).x(), transform(p, Vec3(1, 0, -20)).x());
  EXPECT_LT(transform(p, Vec3(0, 0, -10)).z(), transform(p, Vec3(0, 0, -20)).z());
}

TEST(Camera, OrthographicSizesDoNotDependOnDepth) {
  Camera c;
  c.projection = Projection::Orthographic;
  c.half_height_mm = 25;
  c.near_mm = 1;
  c.far_mm = 201;
  const Mat4 p = c.projection_matrix(2.0);
  for (const double d : {1.0, 50.0, 201.0}) {
    const Vec3 ndc = transform(p, Vec3(50, 25, -d));
    EXPECT_TRUE(test::near(ndc.x(), 1.0, 1e-12));
    EXPECT_TRUE(test::near(ndc.y(), 1.0, 1e-12));
  }
  EXPECT_TRUE(test::near(transform(p, Vec3(0, 0, -1)).z(), -1.0, 1e-12));
  EXPECT_TRUE(test::near(transform(p, Vec3(0, 0, -201)).z(), 1.0, 1e-12));
}

TEST(Camera, OrbitFramesTheWholeBoxAtEveryAngleAndAspect) {
  const Vec3 lo(-10, 5, -3), hi(30, 25, 60);
  int cases = 0;
  for (const Projection proj : {Projection::Orthographic, Projection::Perspective})
    for (const double aspect : {0.5, 1.0, 2.5})
      for (const double az : {0.0, 37.0, 90.0, 200.0})
        for (const double el : {-90.0, -30.0, 0.0, 45.0, 90.0}) {
          const Camera c = Camera::orbit(lo, hi, az, el, proj, aspect);
          EXPECT_TRUE(c.target.isApprox(0.5 * (lo + hi), 1e-12));
          EXPECT_TRUE(test::near(c.direction.norm(), 1.0, 1e-12));
          EXPECT_LT(std::abs(c.up.normalized().dot(c.direction)), 1.0 - 1e-6) << "up not parallel to direction";
          EXPECT_GT(c.near_mm, 0.0);
          EXPECT_GT(c.far_mm, c.near_mm);
          const Mat4 m = c.projection_matrix(aspect) * c.view_matrix();
          double reach = 0.0;
          for (int k = 0; k < 8; ++k) {
            const Vec3 corner((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
            const Vec3 ndc = transform(m, corner);
            EXPECT_LE(std::abs(ndc.x()), 1.0) << az << " " << el << " " << aspect;
            EXPECT_LE(std::abs(ndc.y()), 1.0) << az << " " << el << " " << aspect;
            EXPECT_LE(std::abs(ndc.z()), 1.0) << "clipped by near/far";
            reach = std::max({reach, std::abs(ndc.x()), std::abs(ndc.y())});
          }
          EXPECT_GT(reach, 0.2) << "the box fills a fair part of the picture";
          if (proj == Projection::Orthographic) {
            // Tight: the box's bounding sphere (radius half its diagonal) spans 1/1.05 of the
            // picture's narrower side.
            const double r = 0.5 * (hi - lo).norm();
            const Mat4 v = c.view_matrix();
            const Vec3 right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
            const double sx = transform(m, c.target + r * right).x(), sy = transform(m, c.target + r * up).y();
            EXPECT_TRUE(test::near(std::max(sx, sy), 1.0 / 1.05, 1e-9)) << az << " " << el << " " << aspect;
          }
          ++cases;
        }
  EXPECT_EQ(cases, 120);
  // The documented angles: azimuth 0 looks from −y, 90 from +x; elevation 90 from +z.
  const Vec3 a(0, 0, 0), b(2, 2, 2);
  EXPECT_TRUE(Camera::orbit(a, b, 0, 0, Projection::Orthographic, 1).direction.isApprox(Vec3(0, -1, 0), 1e-12));
  EXPECT_TRUE(Camera::orbit(a, b, 90, 0, Projection::Orthographic, 1).direction.isApprox(Vec3(1, 0, 0), 1e-12));
  const Camera top = Camera::orbit(a, b, 30, 90, Projection::Orthographic, 1);
  EXPECT_TRUE(top.direction.isApprox(Vec3(0, 0, 1), 1e-12));
  EXPECT_TRUE(test::near(top.up.dot(Vec3::UnitZ()), 0.0, 1e-12)) << "looking along z, up is in the xy plane";
  EXPECT_TRUE(Camera::orbit(a, b, 0, 20, Projection::Orthographic, 1).up.isApprox(Vec3(0, 0, 1)));
}

}  // namespace
}  // namespace ido::viz

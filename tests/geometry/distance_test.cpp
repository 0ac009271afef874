// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/distance.h"

#include <gtest/gtest.h>

#include <random>

#include "support/test_support.h"

namespace ido::geometry {
namespace {

/// Reference: minimum over a fine barycentric sampling, refined by the exact optimality
/// condition (the closest point q makes p − q orthogonal to the triangle's plane or lies on
/// the boundary). Here we only use the sampled minimum as an upper bound and check the
/// optimality of the returned point by perturbation.
TEST(Distance, ClosestPointIsOptimalAndOnTriangle) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int n = 0; n < 2000; ++n) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3 p(u(rng), u(rng), u(rng));
    const Vec3 q = closest_point_on_triangle(p, a, b, c);
    // q lies in the triangle: barycentric coordinates in [0, 1].
    const Vec3 nrm = (b - a).cross(c - a);
    const double area2 = nrm.squaredNorm();
    const double l1 = (b - q).cross(c - q).dot(nrm) / area2;
    const double l2 = (c - q).cross(a - q).dot(nrm) / area2;
    const double l3 = 1.0 - l1 - l2;
    EXPECT_GE(l1, -1e-9);
    EXPECT_GE(l2, -1e-9);
    EXPECT_GE(l3, -1e-9);
    EXPECT_TRUE(test::near(std::abs((q - a).dot(nrm)) / std::sqrt(area2), 0.0, 1e-9));
    // No sampled point of the triangle is closer.
    const double d = (p - q).norm();
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; i + j <= 20; ++j) {
        const Vec3 s = a + (b - a) * (i / 20.0) + (c - a) * (j / 20.0);
        EXPECT_LE(d, (p - s).norm() + 1e-12);
      }
    }
    EXPECT_TRUE(test::near(point_triangle_distance(p, a, b, c), d, 1e-15));
  }
}

TEST(Distance, RegionsOfRightTriangle) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(closest_point_on_triangle(Vec3(0.2, 0.3, 5), a, b, c).isApprox(Vec3(0.2, 0.3, 0), 1e-15));  // face
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, -1, 1), a, b, c), a);                     // vertex
  EXPECT_EQ(closest_point_on_triangle(Vec3(3, -1, 0), a, b, c), b);
  EXPECT_TRUE(closest_point_on_triangle(Vec3(0.5, -2, 0), a, b, c).isApprox(Vec3(0.5, 0, 0)));  // edge ab
  EXPECT_TRUE(closest_point_on_triangle(Vec3(1, 1, 0), a, b, c).isApprox(Vec3(0.5, 0.5, 0)));   // edge bc
  EXPECT_TRUE(test::near(point_triangle_distance(Vec3(1, 1, 0), a, b, c), std::sqrt(0.5), 1e-15));
}

TEST(Distance, DegenerateTriangle) {
  const Vec3 a(0, 0, 0), b(2, 0, 0), c(1, 0, 0);
  EXPECT_TRUE(closest_point_on_triangle(Vec3(1.5, 3, 0), a, b, c).isApprox(Vec3(1.5, 0, 0)));
  EXPECT_EQ(closest_point_on_triangle(Vec3(5, 5, 5), a, a, a), a);
}

}  // namespace
}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/signed_distance.h"

#include <cmath>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/winding_number.h"
#include "support/octahedron_sphere.h"
#include "support/test_support.h"

namespace ido::meshing {
namespace {

geometry::TriangleMesh sphere(const Vec3& c, double r, int subdivisions) {
  return test::octahedron_sphere(c, r, subdivisions);
}

TEST(ClosestPointOnTriangle, MatchesDenseSampling) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3 p(u(rng), u(rng), u(rng));
    const double d = (closest_point_on_triangle_mm(p, a, b, c) - p).norm();
    double best = INFINITY;
    const int n = 200;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Vec3 q = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
        best = std::min(best, (q - p).norm());
      }
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GE(d, best - 0.02 * (b - a).norm() - 0.02 * (c - a).norm());
  }
}

// The sign of signed_distance relies on geometry::WindingNumber counting overlaps twice.
TEST(SignedDistanceWinding, InsideOneOutsideZeroOverlapTwo) {
  geometry::TriangleMesh m = sphere(Vec3::Zero(), 5.0, 4);
  const auto second = sphere(Vec3(4, 0, 0), 5.0, 4);
  const auto base = static_cast<std::int32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), second.vertices.begin(), second.vertices.end());
  for (const Tri& t : second.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  const geometry::WindingNumber w(m);
  EXPECT_TRUE(test::near(w.at(Vec3(-3, 0, 0)), 1.0, 0.02));
  EXPECT_TRUE(test::near(w.at(Vec3(2, 0, 0)), 2.0, 0.02));
  EXPECT_TRUE(test::near(w.at(Vec3(7, 1, 0)), 1.0, 0.02));
  EXPECT_TRUE(test::near(w.at(Vec3(0, 9, 0)), 0.0, 0.02));
  EXPECT_TRUE(test::near(w.at(Vec3(40, 0, 3)), 0.0, 0.01));
}

TEST(SignedDistance, SphereMatchesAnalyticDistanceAndSign) {
  const Vec3 c(1.3, -0.7, 0.4);
  const double r = 6.0;
  const auto m = sphere(c, r, 5);  // chord error r(1 − cos θ) ≈ 0.01 mm
  const image::Volume<float> grid({24, 22, 20}, Vec3(0.8, 0.9, 1.0), Vec3(-9, -10, -9));
  SignedDistanceOptions so;
  so.band_mm = 2.0;
  const auto sdf = signed_distance(m, grid, so);
  int band = 0;
  for (std::int64_t k = 0; k < 20; ++k)
    for (std::int64_t j = 0; j < 22; ++j)
      for (std::int64_t i = 0; i < 24; ++i) {
        const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
        const double exact = (p - c).norm() - r;
        const double v = sdf(i, j, k);
        if (std::abs(exact) < 1.9) {
          ++band;
          ASSERT_TRUE(test::near(v, exact, 0.03)) << i << " " << j << " " << k;
        } else {
          ASSERT_EQ(v < 0, exact < 0) << i << " " << j << " " << k;
          ASSERT_GE(std::abs(v), 1.9 - 0.03);  // exact up to the band, ±band beyond
        }
      }
  EXPECT_GT(band, 1000);
}

// The sign components (outside, and the inside of each of two spheres, one of which has
// triangles left out of the distance) come from a concurrent union–find whose roots are the
// components' lowest indices: the field must be the serial one bit for bit, and signed right.
TEST(SignedDistance, ThreadedComponentsGiveTheSerialField) {
  geometry::TriangleMesh m = sphere(Vec3(-4, 0, 0), 3.0, 4);
  const auto second = sphere(Vec3(4.5, 0.3, 0), 3.5, 4);
  const auto base = static_cast<std::int32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), second.vertices.begin(), second.vertices.end());
  for (const Tri& t : second.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  const image::Volume<float> grid({40, 24, 22}, Vec3(0.5, 0.6, 0.7), Vec3(-9, -7, -7.5));
  SignedDistanceOptions so;
  so.band_mm = 1.0;
  so.distance_triangles.assign(m.triangles.size(), 1);
  for (std::size_t t = m.triangles.size() - 40; t < m.triangles.size(); ++t) so.distance_triangles[t] = 0;
  so.threaded = false;
  const auto serial = signed_distance(m, grid, so);
  so.threaded = true;
  const auto threaded = signed_distance(m, grid, so);
  ASSERT_EQ(serial.data().size(), threaded.data().size());
  for (std::size_t i = 0; i < serial.data().size(); ++i) ASSERT_EQ(serial.data()[i], threaded.data()[i]) << i;
  auto at = [&](const Vec3& p) {
    const Vec3 idx = grid.world_to_index(p);
    return threaded(std::lround(idx[0]), std::lround(idx[1]), std::lround(idx[2]));
  };
  EXPECT_LT(at(Vec3(-4, 0, 0)), 0.0f);
  EXPECT_LT(at(Vec3(4.5, 0.3, 0)), 0.0f);
  EXPECT_GT(at(Vec3(0.3, 0, 0)), 0.0f);
  EXPECT_GT(at(Vec3(-8.5, -6.5, -7)), 0.0f);
}

TEST(SignedDistance, RejectsBadInput) {
  const image::Volume<float> grid({4, 4, 4});
  EXPECT_THROW((void)signed_distance(geometry::TriangleMesh{}, grid), InvalidInput);
  EXPECT_THROW((void)signed_distance(sphere(Vec3::Zero(), 1, 0), image::Volume<float>{}), InvalidInput);
  SignedDistanceOptions o;
  o.distance_triangles = {1, 0};
  EXPECT_THROW((void)signed_distance(sphere(Vec3::Zero(), 1, 0), grid, o), InvalidInput);
}

}  // namespace
}  // namespace ido::meshing

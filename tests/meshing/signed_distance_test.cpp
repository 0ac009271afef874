// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/signed_distance.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <initializer_list>
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

// distance_grid: isotropic and world-aligned, the vertices' bounding box plus the margin's
// whole cells on every side (no less, and at most one cell more where the box is not a whole
// number of cells).
TEST(DistanceGrid, CoversTheBoundingBoxWithTheMargin) {
  const auto m = test::octahedron_sphere(Vec3(3.0, -2.0, 7.5), 4.3, 2);
  for (const int margin : {0, 3, 5}) {
    const image::Volume<float> g = distance_grid(m, 0.7, margin);
    EXPECT_EQ(g.spacing(), Vec3::Constant(0.7));
    EXPECT_EQ(g.direction(), Mat3::Identity());
    const Vec3 first = g.index_to_world(Vec3::Zero());
    const Vec3 last = g.index_to_world(Vec3(double(g.size(0) - 1), double(g.size(1) - 1), double(g.size(2) - 1)));
    for (int a = 0; a < 3; ++a) {
      double lo = INFINITY, hi = -INFINITY;
      for (const Vec3& v : m.vertices) {
        lo = std::min(lo, v[a]);
        hi = std::max(hi, v[a]);
      }
      EXPECT_NEAR(lo - first[a], margin * 0.7, 1e-9) << a;
      EXPECT_GE(last[a] - hi, margin * 0.7 - 1e-9) << a;
      EXPECT_LT(last[a] - hi, (margin + 1) * 0.7 + 1e-9) << a;
    }
  }
  EXPECT_THROW((void)distance_grid(geometry::TriangleMesh{}, 1.0, 3), InvalidInput);
  EXPECT_THROW((void)distance_grid(m, 0.0, 3), InvalidInput);
  EXPECT_THROW((void)distance_grid(m, 1.0, -1), InvalidInput);
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
  so.sign = SignMethod::winding_number;  // the union–find path (closed meshes take parity by default)
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

geometry::TriangleMesh merged(std::initializer_list<geometry::TriangleMesh> parts) {
  geometry::TriangleMesh m;
  for (const auto& part : parts) {
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), part.vertices.begin(), part.vertices.end());
    for (const Tri& t : part.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return m;
}

geometry::TriangleMesh inverted(geometry::TriangleMesh m) {
  for (Tri& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

// An axis-aligned box whose faces are split into unit squares, every vertex on a grid point:
// rows run through its vertices and along its edges, and its side faces are seen edge-on.
geometry::TriangleMesh grid_box(const Index3& lo, const Index3& hi) {
  geometry::TriangleMesh m;
  std::map<std::array<std::int64_t, 3>, std::int32_t> id;
  auto vertex = [&](std::array<std::int64_t, 3> p) {
    const auto [it, fresh] = id.emplace(p, static_cast<std::int32_t>(m.vertices.size()));
    if (fresh) m.vertices.emplace_back(double(p[0]), double(p[1]), double(p[2]));
    return it->second;
  };
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int side = 0; side < 2; ++side)
      for (std::int64_t u = lo[b]; u < hi[b]; ++u)
        for (std::int64_t w = lo[c]; w < hi[c]; ++w) {
          std::array<std::int64_t, 3> p00{}, p10{}, p01{}, p11{};
          for (auto* p : {&p00, &p10, &p01, &p11}) (*p)[a] = side ? hi[a] : lo[a];
          p00[b] = u, p00[c] = w;
          p10[b] = u + 1, p10[c] = w;
          p01[b] = u, p01[c] = w + 1;
          p11[b] = u + 1, p11[c] = w + 1;
          // (b, c) turn counter-clockwise about +a: outward on the high side.
          const std::int32_t v00 = vertex(p00), v10 = vertex(p10), v01 = vertex(p01), v11 = vertex(p11);
          if (side) {
            m.triangles.push_back({v00, v10, v11});
            m.triangles.push_back({v00, v11, v01});
          } else {
            m.triangles.push_back({v00, v11, v10});
            m.triangles.push_back({v00, v01, v11});
          }
        }
  }
  return m;
}

// Rows through vertices, along edges and over edge-on faces: points strictly inside are
// inside and strictly outside are outside, exactly as the winding number has it.
TEST(SignedDistanceParity, GridAlignedBoxThroughVerticesAndEdges) {
  const Index3 lo{2, 2, 2}, hi{7, 6, 5};
  const auto box = grid_box(lo, hi);
  ASSERT_GT(geometry::WindingNumber(box).exact_at(Vec3(4.5, 4.1, 3.3)), 0.99);  // outward
  const image::Volume<float> grid({10, 9, 8});
  const auto sdf = signed_distance(box, grid, {.band_mm = 1.5, .distance_triangles = {}});
  for (std::int64_t k = 0; k < 8; ++k)
    for (std::int64_t j = 0; j < 9; ++j)
      for (std::int64_t i = 0; i < 10; ++i) {
        const Index3 p{i, j, k};
        bool inside = true, outside = false;
        for (int a = 0; a < 3; ++a) {
          inside = inside && p[a] > lo[a] && p[a] < hi[a];
          outside = outside || p[a] < lo[a] || p[a] > hi[a];
        }
        if (inside) {
          ASSERT_LT(sdf(i, j, k), 0.0f) << i << " " << j << " " << k;
        }
        if (outside) {
          ASSERT_GT(sdf(i, j, k), 0.0f) << i << " " << j << " " << k;
        }
      }
}

// A self-intersecting closed surface (two overlapping spheres) with a cavity (an inverted
// sphere inside), on rotated grids, one of them mirrored: the parity sign is the exact
// winding number's (> 0.5) at every grid point off the surface, and threads do not change it.
TEST(SignedDistanceParity, MatchesExactWindingOnOverlapsCavitiesAndRotatedGrids) {
  const auto m = merged({sphere(Vec3(-1.5, 0, 0), 3.0, 3), sphere(Vec3(2.0, 0.4, 0.2), 3.0, 3),
                         inverted(sphere(Vec3(-1.8, 0.1, 0), 1.2, 2))});
  const geometry::WindingNumber w(m);
  for (const bool mirrored : {false, true}) {
    Mat3 rot = (Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized())).toRotationMatrix();
    if (mirrored) rot.col(1) *= -1.0;
    const Vec3 spacing(0.55, 0.6, 0.65);
    const Vec3 half = 0.5 * Vec3(21, 15, 15).cwiseProduct(spacing);  // the grid centred on the origin
    const image::Volume<float> grid({22, 16, 16}, spacing, -(rot * half), rot);
    SignedDistanceOptions so;
    so.band_mm = 1.0;
    so.threaded = false;
    const auto serial = signed_distance(m, grid, so);
    so.threaded = true;
    const auto sdf = signed_distance(m, grid, so);
    ASSERT_EQ(serial.data(), sdf.data());
    int inside = 0, deep = 0;
    for (std::int64_t k = 0; k < 16; ++k)
      for (std::int64_t j = 0; j < 16; ++j)
        for (std::int64_t i = 0; i < 22; ++i) {
          const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
          if (std::abs(sdf(i, j, k)) < 1e-6f) continue;
          const double wn = w.exact_at(p);
          ASSERT_EQ(sdf(i, j, k) < 0, wn > 0.5) << mirrored << " " << i << " " << j << " " << k << " wn " << wn;
          inside += wn > 0.5 ? 1 : 0;
          deep += wn > 1.5 ? 1 : 0;  // the overlap, counted twice
        }
    EXPECT_GT(inside, 500);
    EXPECT_GT(deep, 20);
  }
}

// An open surface has no parity: the automatic choice falls back to the winding number.
TEST(SignedDistanceParity, OpenSurfaceFallsBackToTheWindingNumber) {
  auto m = sphere(Vec3(0.2, 0.1, -0.3), 4.0, 3);
  m.triangles.erase(m.triangles.begin() + 17);
  const image::Volume<float> grid({16, 16, 16}, Vec3::Constant(0.7), Vec3::Constant(-5.5));
  const auto automatic = signed_distance(m, grid);
  const auto winding = signed_distance(m, grid, {.band_mm = 0, .distance_triangles = {}, .winding_beta = 2, .sign = SignMethod::winding_number});
  EXPECT_EQ(automatic.data(), winding.data());
  EXPECT_LT(automatic(8, 8, 8), 0.0f);
  EXPECT_GT(automatic(0, 0, 0), 0.0f);
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

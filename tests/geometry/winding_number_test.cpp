// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/winding_number.h"

#include <gtest/gtest.h>

#include <random>

#include "ido/geometry/bvh.h"
#include "ido/geometry/primitives.h"
#include "support/test_support.h"
#include "test_meshes.h"

namespace ido::geometry {
namespace {

TEST(WindingNumber, ExactSumIsOneInsideZeroOutside) {
  const TriangleMesh m = torus_surface(Vec3(1, 1, 1), 4, 1.5, 48, 24);
  const WindingNumber w(m, {.beta = 0.0});
  // Inside the tube, and just inside / outside the surface.
  EXPECT_TRUE(test::near(w.at(Vec3(5, 1, 1)), 1.0, 1e-10));
  EXPECT_TRUE(test::near(w.at(Vec3(1, 1, 1)), 0.0, 1e-10));   // the hole
  EXPECT_TRUE(test::near(w.at(Vec3(20, 1, 1)), 0.0, 1e-10));
  const TriangleBvh bvh(m);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-6, 8);
  for (int n = 0; n < 500; ++n) {
    const Vec3 p(u(rng), u(rng), u(rng) * 0.5);
    if (bvh.closest_point(p).distance_mm < 1e-4) continue;
    const double v = w.at(p);
    EXPECT_TRUE(test::near(v, std::round(v), 1e-6)) << v;
    EXPECT_TRUE(v > 0.5 ? true : test::near(v, 0.0, 1e-6));
  }
  // Near the surface, both sides: 1e-3 mm from a face centre along the normal.
  for (std::size_t t = 0; t < m.triangles.size(); t += 17) {
    const Tri& tri = m.triangles[t];
    const Vec3 a = m.vertices[static_cast<std::size_t>(tri[0])], b = m.vertices[static_cast<std::size_t>(tri[1])],
               c = m.vertices[static_cast<std::size_t>(tri[2])];
    const Vec3 nrm = (b - a).cross(c - a).normalized();
    const Vec3 ctr = (a + b + c) / 3.0;
    EXPECT_TRUE(test::near(w.at(ctr - 1e-3 * nrm), 1.0, 1e-6));
    EXPECT_TRUE(test::near(w.at(ctr + 1e-3 * nrm), 0.0, 1e-6));
  }
}

TEST(WindingNumber, FastAgreesWithExactSumAndConvergesInBeta) {
  const TriangleMesh m = test::merged(icosphere(Vec3::Zero(), 3.0, 3), torus_surface(Vec3(8, 0, 0), 3, 1, 48, 24));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5, 13);
  std::vector<Vec3> pts;
  for (int n = 0; n < 400; ++n) pts.emplace_back(u(rng), u(rng) * 0.5, u(rng) * 0.3);
  const WindingNumber exact(m, {.beta = 0.0});
  std::vector<double> ref;
  int inside = 0;
  for (const Vec3& p : pts) {
    ref.push_back(exact.at(p));
    EXPECT_TRUE(test::near(ref.back(), exact.exact_at(p), 1e-12));  // only summation order differs
    inside += ref.back() > 0.5;
  }
  EXPECT_GT(inside, 30);
  // The second-order far field has an error per cluster of order (radius / distance)³, so
  // doubling beta must shrink the worst error by clearly more than 4.
  double previous = 1.0;
  for (const double beta : {2.0, 4.0, 8.0}) {
    const WindingNumber fast(m, {.beta = beta});
    const std::vector<double> w = fast.at(pts);
    double max_err = 0.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      max_err = std::max(max_err, std::abs(w[i] - ref[i]));
      EXPECT_EQ(w[i] > 0.5, ref[i] > 0.5);  // same inside/outside classification
      EXPECT_EQ(w[i], fast.at(pts[i]));      // batch = single queries
    }
    EXPECT_LT(max_err, previous / 4.0) << "beta " << beta;
    previous = max_err;
  }
  EXPECT_LT(previous, 1e-4);  // beta = 8
}

TEST(WindingNumber, OpenAndReversedMeshes) {
  TriangleMesh m = icosphere(Vec3::Zero(), 1.0, 3);
  const WindingNumber full(m);
  // Reversed orientation: −1 inside.
  TriangleMesh r = m;
  for (Tri& t : r.triangles) std::swap(t[1], t[2]);
  EXPECT_TRUE(test::near(WindingNumber(r, {.beta = 0}).at(Vec3(0.1, 0, 0)), -1.0, 1e-10));
  EXPECT_TRUE(test::near(WindingNumber(r).at(Vec3(0.1, 0, 0)), -1.0, 1e-2));
  EXPECT_TRUE(test::near(full.at(Vec3(0.1, 0, 0)), 1.0, 1e-2));
  // A hemisphere seen from its centre covers half the directions: 1/2.
  TriangleMesh hemi;
  hemi.vertices = m.vertices;
  for (const Tri& t : m.triangles) {
    const Vec3 c = (m.vertices[static_cast<std::size_t>(t[0])] + m.vertices[static_cast<std::size_t>(t[1])] +
                    m.vertices[static_cast<std::size_t>(t[2])]) / 3.0;
    if (c.z() > 0) hemi.triangles.push_back(t);
  }
  const double h = WindingNumber(hemi, {.beta = 0}).at(Vec3::Zero());
  EXPECT_TRUE(test::near(h, 0.5, 0.02));  // the cut follows triangle edges, so only about 1/2
  // Single triangle: solid angle of the unit right triangle corner seen from (0,0,-1)...
  // an octant-like corner: from the origin of a tetrahedral corner the solid angle of the
  // opposite face (1,0,0),(0,1,0),(0,0,1) is 4π/8.
  EXPECT_TRUE(test::near(solid_angle(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)), 4 * kPi / 8, 1e-12));
  EXPECT_TRUE(test::near(solid_angle(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0)), -4 * kPi / 8, 1e-12));
  EXPECT_EQ(WindingNumber(TriangleMesh{}).at(Vec3::Zero()), 0.0);
}

}  // namespace
}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/predicates.h"

#include <gtest/gtest.h>

#include <random>

#include "ido/geometry/tet_quality.h"

namespace ido::geometry {
namespace {

__extension__ typedef __int128 Int128;

int sign128(Int128 v) { return (v > 0) - (v < 0); }

/// Exact orient3d for integer coordinates (|x| < 2^40), as a reference.
int exact_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  auto i = [](double x) { return static_cast<Int128>(static_cast<std::int64_t>(x)); };
  const Int128 bx = i(b.x()) - i(a.x()), by = i(b.y()) - i(a.y()), bz = i(b.z()) - i(a.z());
  const Int128 cx = i(c.x()) - i(a.x()), cy = i(c.y()) - i(a.y()), cz = i(c.z()) - i(a.z());
  const Int128 dx = i(d.x()) - i(a.x()), dy = i(d.y()) - i(a.y()), dz = i(d.z()) - i(a.z());
  return sign128(bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx));
}

double naive_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a));
}

TEST(Predicates, SignConventionMatchesTetVolume) {
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  EXPECT_GT(orient3d(o, x, y, z), 0.0);
  EXPECT_GT(tet_signed_volume(o, x, y, z), 0.0);
  EXPECT_LT(orient3d(o, y, x, z), 0.0);
  EXPECT_EQ(orient3d(o, x, y, Vec3(0.3, 0.7, 0)), 0.0);
  EXPECT_GT(orient2d(Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)), 0.0);
  EXPECT_LT(orient2d(Vec2(0, 0), Vec2(0, 1), Vec2(1, 0)), 0.0);
  // Projected orientation: sign of the dropped-axis component of the normal.
  EXPECT_GT(orient2d_projected(o, x, y, 2), 0.0);
  EXPECT_GT(orient2d_projected(o, y, z, 0), 0.0);
  EXPECT_GT(orient2d_projected(o, z, x, 1), 0.0);
}

TEST(Predicates, Orient2dExactOnNearlyCollinearGrid) {
  // p = (0.5 + i·u, 0.5 + j·u), u = 2^-53, against q = (12, 12), r = (24, 24): the exact
  // orientation is 12·(p.y − p.x), so its sign is sign(j − i).
  const double u = 0x1p-53;
  int naive_wrong = 0;
  for (int i = 0; i < 128; ++i) {
    for (int j = 0; j < 128; ++j) {
      const Vec2 p(0.5 + i * u, 0.5 + j * u), q(12, 12), r(24, 24);
      EXPECT_EQ(sign_of(orient2d(p, q, r)), (j > i) - (j < i)) << i << " " << j;
      EXPECT_EQ(sign_of(orient2d(q, r, p)), (j > i) - (j < i));
      const double naive = (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
      if (sign_of(naive) != (j > i) - (j < i)) ++naive_wrong;
    }
  }
  EXPECT_GT(naive_wrong, 100);  // the test really exercises the exact path
}

TEST(Predicates, Orient3dExactOnNearlyCoplanarPoints) {
  // q, r, s lie on the plane z = x; p is within a few ulps of it.
  const Vec3 q(12, 0, 12), r(24, 5, 24), s(7, 13, 7);
  const int k = sign_of(orient3d(q, r, s, Vec3(0, 0, 1)));  // sign for p.z − p.x > 0
  ASSERT_NE(k, 0);
  const double u = 0x1p-53;
  int naive_wrong = 0;
  for (int i = 0; i < 64; ++i) {
    for (int j = 0; j < 64; ++j) {
      const Vec3 p(0.5 + i * u, 0.3, 0.5 + j * u);
      const int expected = k * ((j > i) - (j < i));
      EXPECT_EQ(sign_of(orient3d(q, r, s, p)), expected);
      EXPECT_EQ(sign_of(orient3d(p, q, r, s)), -expected);  // odd permutation
      if (sign_of(naive_orient3d(q, r, s, p)) != expected) ++naive_wrong;
    }
  }
  EXPECT_GT(naive_wrong, 50);
}

TEST(Predicates, Orient3dMatchesIntegerReference) {
  // Long, nearly parallel edge vectors b − a = (L, L+1, k), c − a = (L+1, L+2, k) have the
  // tiny normal (−k, k, −1); d = a + u(b − a) + v(c − a) + w with a small lattice offset w
  // lies within about one unit of that plane, so det = n · w is a small integer while the
  // naive evaluation rounds products of size L³. The reference uses 128-bit integers.
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::int64_t> big(-(1LL << 34), 1LL << 34);
  std::uniform_int_distribution<std::int64_t> len(1LL << 28, 1LL << 34);
  std::uniform_int_distribution<int> k(-1000, 1000);
  std::uniform_int_distribution<int> uv(-3, 3);
  std::uniform_int_distribution<int> small(-1, 1);
  int naive_wrong = 0;
  int zero = 0;
  for (int n = 0; n < 20000; ++n) {
    const auto L = static_cast<double>(len(rng));
    const double kk = k(rng);
    const Vec3 a(static_cast<double>(big(rng)), static_cast<double>(big(rng)), static_cast<double>(big(rng)));
    Vec3 e1(L, L + 1, kk);
    Vec3 e2(L + 1, L + 2, kk);
    // Random axis permutation keeps everything integral.
    const int shift = n % 3;
    e1 = Vec3(e1[shift], e1[(shift + 1) % 3], e1[(shift + 2) % 3]);
    e2 = Vec3(e2[shift], e2[(shift + 1) % 3], e2[(shift + 2) % 3]);
    const Vec3 b = a + e1;
    const Vec3 c = a + e2;
    const Vec3 d = a + uv(rng) * e1 + uv(rng) * e2 + Vec3(small(rng), small(rng), small(rng));
    const int expected = exact_orient3d(a, b, c, d);
    ASSERT_EQ(sign_of(orient3d(a, b, c, d)), expected) << n;
    ASSERT_EQ(sign_of(orient3d(b, c, a, d)), expected);
    ASSERT_EQ(sign_of(orient3d(b, a, c, d)), -expected);
    ASSERT_EQ(sign_of(orient3d(d, b, c, a)), -expected);
    if (sign_of(naive_orient3d(a, b, c, d)) != expected) ++naive_wrong;
    if (expected == 0) ++zero;
  }
  EXPECT_GT(naive_wrong, 1000);  // the naive determinant is often wrong here
  EXPECT_GT(zero, 100);
}

TEST(Predicates, CollinearExact) {
  EXPECT_TRUE(collinear3d(Vec3(0, 0, 0), Vec3(1, 2, 3), Vec3(3, 6, 9)));
  EXPECT_TRUE(collinear3d(Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(5, 1, 2)));
  EXPECT_FALSE(collinear3d(Vec3(0, 0, 0), Vec3(1, 2, 3), Vec3(3, 6, 9 + 0x1p-49)));
}

}  // namespace
}  // namespace ido::geometry

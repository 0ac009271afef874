// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/triangle_intersection.h"

#include <gtest/gtest.h>

#include <random>

#include "ido/geometry/predicates.h"

namespace ido::geometry {
namespace {

/// Separating-axis reference for two non-degenerate triangles. With small integer
/// coordinates every quantity below is an exact integer in double, so the reference is
/// exact. Candidate axes: both normals, the 9 edge–edge cross products and the in-plane
/// edge normals (needed for coplanar triangles); closed sets, so touching is intersecting.
bool sat_reference(const Triangle3& a, const Triangle3& b) {
  std::vector<Vec3> axes;
  const Vec3 na = (a[1] - a[0]).cross(a[2] - a[0]);
  const Vec3 nb = (b[1] - b[0]).cross(b[2] - b[0]);
  axes.push_back(na);
  axes.push_back(nb);
  for (int i = 0; i < 3; ++i) {
    const Vec3 ea = a[static_cast<std::size_t>((i + 1) % 3)] - a[static_cast<std::size_t>(i)];
    const Vec3 eb = b[static_cast<std::size_t>((i + 1) % 3)] - b[static_cast<std::size_t>(i)];
    axes.push_back(na.cross(ea));
    axes.push_back(nb.cross(eb));
    for (int j = 0; j < 3; ++j) {
      axes.push_back(ea.cross(b[static_cast<std::size_t>((j + 1) % 3)] - b[static_cast<std::size_t>(j)]));
    }
  }
  for (const Vec3& ax : axes) {
    if (ax == Vec3::Zero()) continue;
    double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
    for (int k = 0; k < 3; ++k) {
      const double pa = ax.dot(a[static_cast<std::size_t>(k)]);
      const double pb = ax.dot(b[static_cast<std::size_t>(k)]);
      amin = std::min(amin, pa);
      amax = std::max(amax, pa);
      bmin = std::min(bmin, pb);
      bmax = std::max(bmax, pb);
    }
    if (amax < bmin || bmax < amin) return false;
  }
  return true;
}

Triangle3 random_grid_triangle(std::mt19937& rng, int n) {
  std::uniform_int_distribution<int> g(0, n);
  for (;;) {
    Triangle3 t{Vec3(g(rng), g(rng), g(rng)), Vec3(g(rng), g(rng), g(rng)), Vec3(g(rng), g(rng), g(rng))};
    if (!collinear3d(t[0], t[1], t[2])) return t;
  }
}

bool both_orders(const Triangle3& a, const Triangle3& b) {
  const bool r = triangles_intersect(a, b);
  EXPECT_EQ(r, triangles_intersect(b, a));
  EXPECT_EQ(r, triangles_intersect({a[1], a[2], a[0]}, {b[2], b[1], b[0]}));
  return r;
}

TEST(TriangleIntersection, AgreesWithExactSeparatingAxesOnIntegerGrid) {
  // A 4×4×4 grid makes coplanar, touching and edge-on configurations very frequent.
  std::mt19937 rng(1);
  int hits = 0;
  int coplanar = 0;
  for (int n = 0; n < 20000; ++n) {
    Triangle3 a = random_grid_triangle(rng, 3);
    Triangle3 b = random_grid_triangle(rng, 3);
    if (n % 3 == 0) {  // force a coplanar pair in the plane x + y + z = 4 (or a grid plane)
      auto flatten = [](Triangle3& t) {
        for (auto& p : t) p.z() = 4 - p.x() - p.y();
      };
      flatten(a);
      flatten(b);
      if (collinear3d(a[0], a[1], a[2]) || collinear3d(b[0], b[1], b[2])) continue;
    }
    const bool ref = sat_reference(a, b);
    ASSERT_EQ(both_orders(a, b), ref) << "case " << n;
    hits += ref;
    if (orient3d(a[0], a[1], a[2], b[0]) == 0 && orient3d(a[0], a[1], a[2], b[1]) == 0 &&
        orient3d(a[0], a[1], a[2], b[2]) == 0) {
      ++coplanar;
    }
  }
  EXPECT_GT(hits, 2000);
  EXPECT_GT(coplanar, 200);
}

TEST(TriangleIntersection, InvariantUnderExactScaling) {
  std::mt19937 rng(2);
  for (int n = 0; n < 2000; ++n) {
    Triangle3 a = random_grid_triangle(rng, 5);
    Triangle3 b = random_grid_triangle(rng, 5);
    const bool r = triangles_intersect(a, b);
    for (auto& p : a) p *= 0x1p-30;
    for (auto& p : b) p *= 0x1p-30;
    ASSERT_EQ(triangles_intersect(a, b), r);
  }
}

TEST(TriangleIntersection, HandMadeCases) {
  const Triangle3 base{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  // Crossing through the interior.
  EXPECT_TRUE(both_orders(base, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(2, 0.5, 1)}));
  // Above the plane, no contact.
  EXPECT_FALSE(both_orders(base, {Vec3(1, 1, 1e-300), Vec3(1, 2, 1), Vec3(2, 1, 1)}));
  // Touching at a single vertex (vertex of b on the edge of a).
  EXPECT_TRUE(both_orders(base, {Vec3(2, 0, 0), Vec3(2, -1, 1), Vec3(3, -1, -1)}));
  // Vertex of b on the edge of a's plane but 1 ulp outside the edge.
  EXPECT_FALSE(both_orders(base, {Vec3(2, -0x1p-52, 0), Vec3(2, -1, 1), Vec3(3, -1, -1)}));
  // Coplanar overlap and coplanar disjoint, and coplanar touching at a vertex.
  EXPECT_TRUE(both_orders(base, {Vec3(1, 1, 0), Vec3(5, 1, 0), Vec3(1, 5, 0)}));
  EXPECT_FALSE(both_orders(base, {Vec3(3, 3, 0), Vec3(5, 3, 0), Vec3(3, 5, 0)}));
  EXPECT_TRUE(both_orders(base, {Vec3(2, 2, 0), Vec3(5, 3, 0), Vec3(3, 5, 0)}));
  // Coplanar: one inside the other.
  EXPECT_TRUE(both_orders(base, {Vec3(0.5, 0.5, 0), Vec3(1, 0.5, 0), Vec3(0.5, 1, 0)}));
  // Shared edge segment, different planes.
  EXPECT_TRUE(both_orders(base, {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(2, 0, 3)}));
}

TEST(TriangleIntersection, DegenerateTriangles) {
  const Triangle3 base{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  // A segment (collinear triangle) piercing the face.
  EXPECT_TRUE(both_orders(base, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, 1, 0.5)}));
  // A segment lying in the plane, crossing an edge.
  EXPECT_TRUE(both_orders(base, {Vec3(-1, 1, 0), Vec3(1, 1, 0), Vec3(3, 1, 0)}));
  // A segment in the plane outside.
  EXPECT_FALSE(both_orders(base, {Vec3(3, 3, 0), Vec3(5, 5, 0), Vec3(4, 4, 0)}));
  // A point on the face and off it.
  EXPECT_TRUE(both_orders(base, {Vec3(1, 1, 0), Vec3(1, 1, 0), Vec3(1, 1, 0)}));
  EXPECT_FALSE(both_orders(base, {Vec3(1, 1, 1e-20), Vec3(1, 1, 1e-20), Vec3(1, 1, 1e-20)}));
  // Two collinear segments on one line: overlapping and disjoint.
  const Triangle3 s1{Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2)};
  EXPECT_TRUE(both_orders(s1, {Vec3(1.5, 1.5, 1.5), Vec3(3, 3, 3), Vec3(4, 4, 4)}));
  EXPECT_FALSE(both_orders(s1, {Vec3(2.5, 2.5, 2.5), Vec3(3, 3, 3), Vec3(4, 4, 4)}));
  // Skew segments do not meet; crossing segments do.
  EXPECT_FALSE(both_orders(s1, {Vec3(0, 1, 0), Vec3(1, 0, 0.5), Vec3(1, 0, 0.5)}));
  EXPECT_TRUE(both_orders(s1, {Vec3(0, 2, 1), Vec3(2, 0, 1), Vec3(2, 0, 1)}));
}

TEST(TriangleIntersection, SegmentTriangle) {
  const Triangle3 t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_TRUE(segment_intersects_triangle(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), t));
  EXPECT_TRUE(segment_intersects_triangle(Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 1), t));  // endpoint on face
  EXPECT_FALSE(segment_intersects_triangle(Vec3(0.2, 0.2, 0x1p-60), Vec3(0.2, 0.2, 1), t));
  EXPECT_TRUE(segment_intersects_triangle(Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), t));  // through the hypotenuse
  EXPECT_FALSE(segment_intersects_triangle(Vec3(0.5, 0.5 + 0x1p-50, -1), Vec3(0.5, 0.5 + 0x1p-50, 1), t));
}

/// Independent reference for adjacent triangles on a small integer grid: a meets b beyond
/// the shared element iff the part of a at least ε away from that element meets b (ε is far
/// below the smallest feature the grid can produce, and every coordinate stays exact).
bool cut_reference(const Triangle3& a, const Triangle3& b, int shared) {
  const double eps = 0x1p-20;
  if (shared == 2) {  // keep the part of a near its third corner a[2]
    const Triangle3 cut{a[2], a[2] + (1 - eps) * (a[0] - a[2]), a[2] + (1 - eps) * (a[1] - a[2])};
    return triangles_intersect(cut, b);
  }
  // shared == 1: remove a tiny corner at a[0] (a quadrilateral = two triangles).
  const Vec3 p1 = a[0] + eps * (a[1] - a[0]);
  const Vec3 p2 = a[0] + eps * (a[2] - a[0]);
  return triangles_intersect({p1, a[1], a[2]}, b) || triangles_intersect({p1, a[2], p2}, b);
}

TEST(TriangleIntersection, AdjacentTrianglesAgreeWithCutReference) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> g(0, 3);
  int positive[3] = {0, 0, 0};
  int tested[3] = {0, 0, 0};
  for (int n = 0; n < 30000; ++n) {
    const int shared = 1 + (n % 2);
    const Vec3 v0(g(rng), g(rng), g(rng));
    const Vec3 v1(g(rng), g(rng), g(rng));
    const Vec3 a2(g(rng), g(rng), g(rng));
    const Vec3 b1(g(rng), g(rng), g(rng));
    const Vec3 b2(g(rng), g(rng), g(rng));
    const Triangle3 a{v0, v1, a2};
    const Triangle3 b = shared == 2 ? Triangle3{v0, v1, b2} : Triangle3{v0, b1, b2};
    if (collinear3d(a[0], a[1], a[2]) || collinear3d(b[0], b[1], b[2])) continue;
    if (shared == 1 && (b1 == v1 || b1 == a2 || b2 == v1 || b2 == a2)) continue;  // would share more
    if (shared == 2 && a2 == b2) continue;
    const bool ref = cut_reference(a, b, shared) || cut_reference(b, a, shared);
    ASSERT_EQ(adjacent_triangles_intersect(a, b, shared), ref) << "case " << n;
    ASSERT_EQ(adjacent_triangles_intersect(b, a, shared), ref);
    ++tested[shared];
    positive[shared] += ref;
  }
  EXPECT_GT(tested[1], 5000);
  EXPECT_GT(tested[2], 5000);
  EXPECT_GT(positive[1], 200);
  EXPECT_GT(positive[2], 200);
}

TEST(TriangleIntersection, AdjacentHandMadeCases) {
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
  // Flat neighbours across an edge: no intersection; folded onto each other: intersection.
  EXPECT_FALSE(adjacent_triangles_intersect({o, x, y}, {o, x, Vec3(0.5, -1, 0)}, 2));
  EXPECT_TRUE(adjacent_triangles_intersect({o, x, y}, {o, x, Vec3(0.5, 0.2, 0)}, 2));
  // Bent neighbours (dihedral angle) meet only along the edge.
  EXPECT_FALSE(adjacent_triangles_intersect({o, x, y}, {o, x, Vec3(0.5, 0.2, 1e-9)}, 2));
  // Sharing a vertex: a fan of flat triangles touching only at o.
  EXPECT_FALSE(adjacent_triangles_intersect({o, x, y}, {o, Vec3(-1, 0, 0), Vec3(0, -1, 0)}, 1));
  // Sharing a vertex and an edge direction (the edges overlap): intersection.
  EXPECT_TRUE(adjacent_triangles_intersect({o, x, y}, {o, Vec3(2, 0, 0), Vec3(0, -1, 0)}, 1));
  // Sharing a vertex, the other triangle pierces the face.
  EXPECT_TRUE(adjacent_triangles_intersect({o, x, y}, {o, Vec3(0.3, 0.3, 1), Vec3(0.3, 0.3, -1)}, 1));
  // Sharing a vertex, coplanar, one edge of b inside a.
  EXPECT_TRUE(adjacent_triangles_intersect({o, x, y}, {o, Vec3(0.2, 0.2, 0), Vec3(-1, 3, 0)}, 1));
  // Same three vertices.
  EXPECT_TRUE(adjacent_triangles_intersect({o, x, y}, {o, x, y}, 3));
}

}  // namespace
}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
// The TreeTable (Bey's red refinement): the children listed in its header, volumes and
// orientation parity, the barycentric maps, face adjacency, congruence classes and point
// location against brute force.
#include "ido/drill/tree_table.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "ido/drill/tet_hierarchy.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

std::array<Vec3, 4> generic_tet() {
  return {Vec3(0.1, -0.2, 0.05), Vec3(1.3, 0.1, -0.1), Vec3(0.4, 1.1, 0.2), Vec3(0.3, 0.35, 0.9)};
}

std::array<double, 4> barycentric(const std::array<Vec3, 4>& x, const Vec3& p) {
  Mat3 e;
  for (int k = 0; k < 3; ++k) e.col(k) = x[static_cast<std::size_t>(k + 1)] - x[0];
  const Vec3 l = e.inverse() * (p - x[0]);
  return {1.0 - l.sum(), l.x(), l.y(), l.z()};
}

TEST(TreeTable, ChildrenVolumesSumToParentAndParityMatchesOrientation) {
  const auto x = generic_tet();
  const double parent = signed_volume(x[0], x[1], x[2], x[3]);
  ASSERT_GT(parent, 0.0);
  const auto& t = TreeTable::get();
  double sum = 0.0;
  for (std::size_t s = 0; s < 8; ++s) {
    const auto c = red_children(x)[s];
    const double v = signed_volume(c[0], c[1], c[2], c[3]);
    EXPECT_TRUE(test::rel_near(std::abs(v), parent / 8.0, 1e-12)) << "slot " << s;
    EXPECT_EQ(v < 0.0, t.parity[s] == 1) << "slot " << s;
    sum += std::abs(v);
  }
  EXPECT_TRUE(test::rel_near(sum, parent, 1e-12));
  EXPECT_EQ(t.parity[5], 1);
  EXPECT_EQ(t.parity[7], 1);
  EXPECT_EQ(std::count(t.parity.begin(), t.parity.end(), 1), 2);
}

TEST(TreeTable, IntegerMapGivesChildBarycentrics) {
  const auto x = generic_tet();
  const auto& t = TreeTable::get();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(u(rng), u(rng), u(rng));
    const auto lambda = barycentric(x, p);
    for (int s = 0; s < 8; ++s) {
      const auto want = barycentric(red_children(x)[static_cast<std::size_t>(s)], p);
      const auto got = t.to_child_coordinates(s, lambda);
      for (std::size_t k = 0; k < 4; ++k) EXPECT_TRUE(test::near(got[k], want[k], 1e-9));
    }
  }
}

TEST(TreeTable, AdjacencyFacesCoincide) {
  const auto x = generic_tet();
  const auto c = red_children(x);
  const auto& t = TreeTable::get();
  auto face_points = [&](std::size_t s, int f) {
    std::vector<std::array<double, 3>> pts;
    for (int k = 0; k < 4; ++k)
      if (k != f) {
        const Vec3& p = c[s][static_cast<std::size_t>(k)];
        pts.push_back({p.x(), p.y(), p.z()});
      }
    std::sort(pts.begin(), pts.end());
    return pts;
  };
  int inner = 0;
  for (std::size_t s = 0; s < 8; ++s)
    for (int f = 0; f < 4; ++f) {
      const auto link = t.face_link[s][static_cast<std::size_t>(f)];
      if (link.sibling >= 0) {
        ++inner;
        EXPECT_EQ(face_points(s, f), face_points(static_cast<std::size_t>(link.sibling), link.sibling_face));
        // Opposite vertices lie on opposite sides of the shared face.
        const auto& a = c[s];
        const auto& b = c[static_cast<std::size_t>(link.sibling)];
        std::array<Vec3, 3> tri;
        int n = 0;
        for (int k = 0; k < 4; ++k)
          if (k != f) tri[static_cast<std::size_t>(n++)] = a[static_cast<std::size_t>(k)];
        const double sa = signed_volume(tri[0], tri[1], tri[2], a[static_cast<std::size_t>(f)]);
        const double sb = signed_volume(tri[0], tri[1], tri[2], b[static_cast<std::size_t>(link.sibling_face)]);
        EXPECT_LT(sa * sb, 0.0);
      } else {
        // All three vertices have zero weight on the parent vertex opposite the parent face.
        for (int k = 0; k < 4; ++k)
          if (k != f) {
            const auto l = barycentric(x, c[s][static_cast<std::size_t>(k)]);
            EXPECT_TRUE(test::near(l[static_cast<std::size_t>(link.parent_face)], 0.0, 1e-12));
          }
      }
    }
  EXPECT_EQ(inner, 16);  // 4 corner–octahedron faces + 4 octahedron faces... counted from both sides
}

// Ordered edge lengths scaled by 2^depth identify an ordered tetrahedron up to congruence.
std::array<double, 6> shape_key(const std::array<Vec3, 4>& x, int depth) {
  std::array<double, 6> k{};
  int n = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      k[static_cast<std::size_t>(n++)] =
          std::round((x[static_cast<std::size_t>(i)] - x[static_cast<std::size_t>(j)]).norm() * std::ldexp(1.0, depth) * 1e8);
  return k;
}

// Congruence class (mirror images included): the smallest ordered-edge-length key over
// the 24 vertex orders.
std::array<double, 6> congruence_key(const std::array<Vec3, 4>& x, int depth) {
  std::array<int, 4> p{0, 1, 2, 3};
  std::array<double, 6> best{};
  bool first = true;
  do {
    const std::array<Vec3, 4> y{x[static_cast<std::size_t>(p[0])], x[static_cast<std::size_t>(p[1])],
                                x[static_cast<std::size_t>(p[2])], x[static_cast<std::size_t>(p[3])]};
    const auto k = shape_key(y, depth);
    if (first || k < best) best = k;
    first = false;
  } while (std::next_permutation(p.begin(), p.end()));
  return best;
}

TEST(TreeTable, AtMostThreeCongruenceClassesOverEightLevels) {
  // Ordered-congruent parents have congruent children slot by slot, so propagating one
  // representative per ordered class is exact (no sampling).
  std::map<std::array<double, 6>, std::array<Vec3, 4>> ordered{{shape_key(generic_tet(), 0), generic_tet()}};
  std::set<std::array<double, 6>> all_levels;
  for (int depth = 1; depth <= 8; ++depth) {
    std::map<std::array<double, 6>, std::array<Vec3, 4>> next;
    std::set<std::array<double, 6>> classes;
    for (const auto& [key, tet] : ordered)
      for (const auto& c : red_children(tet)) {
        next.emplace(shape_key(c, depth), c);
        classes.insert(congruence_key(c, depth));
      }
    EXPECT_LE(classes.size(), 3U) << "depth " << depth;
    all_levels.insert(classes.begin(), classes.end());
    ordered = std::move(next);
  }
  EXPECT_LE(all_levels.size(), 3U);
}

TEST(TreeTable, PointLocationAgreesWithBruteForceOnAMillionPoints) {
  const auto x = generic_tet();
  // Brute force: the 64 depth-2 nodes, each with its own barycentric inverse.
  struct Leaf { int s1, s2; Mat3 inv; Vec3 x0; };
  std::vector<Leaf> leaves;
  for (int s1 = 0; s1 < 8; ++s1)
    for (int s2 = 0; s2 < 8; ++s2) {
      const auto g = red_children(red_children(x)[static_cast<std::size_t>(s1)])[static_cast<std::size_t>(s2)];
      Mat3 e;
      for (int k = 0; k < 3; ++k) e.col(k) = g[static_cast<std::size_t>(k + 1)] - g[0];
      leaves.push_back({s1, s2, e.inverse(), g[0]});
    }
  const auto& t = TreeTable::get();
  Mat3 e;
  for (int k = 0; k < 3; ++k) e.col(k) = x[static_cast<std::size_t>(k + 1)] - x[0];
  std::mt19937_64 rng(11);
  std::exponential_distribution<double> ex(1.0);
  int checked = 0, ambiguous = 0;
  for (int i = 0; i < 1000000; ++i) {
    // Uniform point in the tetrahedron (normalised exponentials = uniform on the simplex).
    std::array<double, 4> l{ex(rng), ex(rng), ex(rng), ex(rng)};
    const double sum = l[0] + l[1] + l[2] + l[3];
    for (auto& v : l) v /= sum;
    const Vec3 p = l[0] * x[0] + l[1] * x[1] + l[2] * x[2] + l[3] * x[3];
    const int s1 = TreeTable::locate_child(l);
    const auto l1 = t.to_child_coordinates(s1, l);
    const int s2 = TreeTable::locate_child(l1);
    int brute = -1;
    double margin = -1.0;
    for (std::size_t k = 0; k < leaves.size(); ++k) {
      const Vec3 m = leaves[k].inv * (p - leaves[k].x0);
      const double mn = std::min({1.0 - m.sum(), m.x(), m.y(), m.z()});
      if (mn > margin) {
        margin = mn;
        brute = static_cast<int>(k);
      }
    }
    if (margin < 1e-9) {  // on a shared face: both answers are right
      ++ambiguous;
      continue;
    }
    ++checked;
    ASSERT_EQ(leaves[static_cast<std::size_t>(brute)].s1, s1) << "point " << i;
    ASSERT_EQ(leaves[static_cast<std::size_t>(brute)].s2, s2) << "point " << i;
  }
  EXPECT_GT(checked, 999000);
}
TEST(TreeTable, ChildrenAreTheOnesTheHeaderLists) {
  // C0=[x0,x01,x02,x03] C1=[x01,x1,x12,x13] C2=[x02,x12,x2,x23] C3=[x03,x13,x23,x3]
  // C4=[x01,x02,x03,x13] C5=[x01,x02,x12,x13] C6=[x02,x03,x13,x23] C7=[x02,x12,x13,x23]
  using P = std::array<int, 2>;
  const std::array<std::array<P, 4>, 8> want{{{{{0, 0}, {0, 1}, {0, 2}, {0, 3}}},
                                               {{{0, 1}, {1, 1}, {1, 2}, {1, 3}}},
                                               {{{0, 2}, {1, 2}, {2, 2}, {2, 3}}},
                                               {{{0, 3}, {1, 3}, {2, 3}, {3, 3}}},
                                               {{{0, 1}, {0, 2}, {0, 3}, {1, 3}}},
                                               {{{0, 1}, {0, 2}, {1, 2}, {1, 3}}},
                                               {{{0, 2}, {0, 3}, {1, 3}, {2, 3}}},
                                               {{{0, 2}, {1, 2}, {1, 3}, {2, 3}}}}};
  const auto& t = TreeTable::get();
  const auto x = generic_tet();
  const auto children = red_children(x);
  for (std::size_t s = 0; s < 8; ++s)
    for (std::size_t k = 0; k < 4; ++k) {
      const auto& v = t.vertex[s][k];
      const P got{std::min(v[0], v[1]), std::max(v[0], v[1])};
      EXPECT_EQ(got, want[s][k]) << "child " << s << " vertex " << k;
      // red_children follows the table.
      const Vec3 p = 0.5 * (x[std::size_t(want[s][k][0])] + x[std::size_t(want[s][k][1])]);
      EXPECT_TRUE(children[s][k].isApprox(p, 1e-15));
      // The integer map takes the child's vertex to its own unit coordinate.
      std::array<double, 4> lambda{};
      lambda[std::size_t(want[s][k][0])] += 0.5;
      lambda[std::size_t(want[s][k][1])] += 0.5;
      const auto mu = t.to_child_coordinates(int(s), lambda);
      for (std::size_t j = 0; j < 4; ++j) EXPECT_EQ(mu[j], j == k ? 1.0 : 0.0) << s << " " << k << " " << j;
    }
  // One table: the same object from any thread.
  std::vector<const TreeTable*> seen(4, nullptr);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < seen.size(); ++i) threads.emplace_back([&seen, i] { seen[i] = &TreeTable::get(); });
  for (auto& th : threads) th.join();
  for (const TreeTable* p : seen) EXPECT_EQ(p, &t);
}

TEST(TreeTable, FaceLinksAreSymmetricAndTileTheParentFaces) {
  const auto& t = TreeTable::get();
  std::array<int, 4> on_parent_face{};
  for (int s = 0; s < 8; ++s)
    for (int f = 0; f < 4; ++f) {
      const auto& l = t.face_link[std::size_t(s)][std::size_t(f)];
      if (l.sibling >= 0) {
        EXPECT_EQ(l.parent_face, -1);
        const auto& back = t.face_link[std::size_t(l.sibling)][std::size_t(l.sibling_face)];
        EXPECT_EQ(back.sibling, s) << s << " " << f;
        EXPECT_EQ(back.sibling_face, f) << s << " " << f;
      } else {
        ASSERT_GE(l.parent_face, 0);
        ASSERT_LT(l.parent_face, 4);
        ++on_parent_face[std::size_t(l.parent_face)];
      }
    }
  // Each parent face is split into 4 child faces (its red refinement).
  EXPECT_EQ(on_parent_face, (std::array<int, 4>{4, 4, 4, 4}));
}

TEST(TreeTable, LocateChildPutsThePointInsideTheChildItNames) {
  const auto& t = TreeTable::get();
  // Corners and the λk = ½ boundary select corner child k.
  for (int k = 0; k < 4; ++k) {
    std::array<double, 4> corner{};
    corner[std::size_t(k)] = 1.0;
    EXPECT_EQ(TreeTable::locate_child(corner), k);
    std::array<double, 4> half{0.5 / 3, 0.5 / 3, 0.5 / 3, 0.5 / 3};
    half[std::size_t(k)] = 0.5;
    EXPECT_EQ(TreeTable::locate_child(half), k);
  }
  // Random points (inside the parent): the named child's coordinates are all ≥ 0 and sum to 1.
  std::mt19937_64 rng(4);
  std::exponential_distribution<double> ex(1.0);
  std::array<int, 8> hits{};
  for (int i = 0; i < 20000; ++i) {
    std::array<double, 4> l{ex(rng), ex(rng), ex(rng), ex(rng)};
    const double sum = l[0] + l[1] + l[2] + l[3];
    for (auto& v : l) v /= sum;
    const int s = TreeTable::locate_child(l);
    ASSERT_GE(s, 0);
    ASSERT_LT(s, 8);
    ++hits[std::size_t(s)];
    const auto mu = t.to_child_coordinates(s, l);
    EXPECT_TRUE(test::near(mu[0] + mu[1] + mu[2] + mu[3], 1.0, 1e-12));
    for (double m : mu) ASSERT_GE(m, -1e-12) << "point " << i << " not in child " << s;
  }
  // Uniform points fall in each child with probability 1/8.
  for (int h : hits) EXPECT_TRUE(test::near(h / 20000.0, 0.125, 0.015));
}

}  // namespace
}  // namespace ido::drill

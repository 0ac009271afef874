// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/remesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <map>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/octahedron_sphere.h"
#include "support/test_support.h"

namespace ido::meshing {
namespace {

// Subdivided octahedron projected onto a sphere (test-local, independent of the library).
geometry::TriangleMesh sphere(double r, int subdivisions) {
  return test::octahedron_sphere(Vec3::Zero(), r, subdivisions);
}

// Torus of radii R, r sampled on an nu × nv grid (genus 1, outward).
geometry::TriangleMesh torus(double R, double r, int nu, int nv) {
  geometry::TriangleMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.vertices.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

struct Facts {
  bool closed_oriented = true;
  bool vertex_manifold = true;
  long euler = 0;
  double volume = 0;
  double min_edge = INFINITY, max_edge = 0;
};

// Test-local checker: every directed edge once with its reverse present; each vertex's
// fan is one cycle; Euler characteristic over used vertices.
Facts facts(const geometry::TriangleMesh& m) {
  Facts f;
  std::map<std::pair<int, int>, int> directed;
  std::vector<std::map<int, int>> fan(m.vertices.size());
  std::set<int> used;
  for (const Tri& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      directed[{a, b}]++;
      if (fan[a].count(b)) f.vertex_manifold = false;
      fan[a][b] = c;
      used.insert(a);
      const double l = (m.vertices[a] - m.vertices[b]).norm();
      f.min_edge = std::min(f.min_edge, l);
      f.max_edge = std::max(f.max_edge, l);
    }
    f.volume += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
  }
  for (const auto& [e, n] : directed)
    if (n != 1 || !directed.count({e.second, e.first})) f.closed_oriented = false;
  for (int v : used) {
    const auto& fv = fan[v];
    int cur = fv.begin()->first, steps = 0;
    do {
      auto it = fv.find(cur);
      if (it == fv.end()) break;
      cur = it->second;
      ++steps;
    } while (cur != fv.begin()->first && steps <= int(fv.size()));
    if (steps != int(fv.size())) f.vertex_manifold = false;
  }
  f.euler = long(used.size()) - long(directed.size() / 2) + long(m.triangles.size());
  return f;
}

// The topology every remesher operation must keep: a closed, consistently oriented,
// vertex-manifold surface with the input's Euler characteristic.
void expect_closed_manifold(const Facts& f, long euler) {
  EXPECT_TRUE(f.closed_oriented);
  EXPECT_TRUE(f.vertex_manifold);
  EXPECT_EQ(f.euler, euler);
}

// A triangle's corners rotated so that the smallest index comes first.
std::array<int, 3> canonical(std::array<int, 3> t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

// The input's edges (as ordered pairs) and triangles (canonical), to check what a restricted
// remesh left in place.
struct InputTopology {
  std::set<std::pair<int, int>> edges;
  std::set<std::array<int, 3>> triangles;
};

InputTopology input_topology(const geometry::TriangleMesh& m) {
  InputTopology in;
  for (const Tri& t : m.triangles) {
    in.triangles.insert(canonical({t[0], t[1], t[2]}));
    for (int k = 0; k < 3; ++k) in.edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
  }
  return in;
}

// The flat incidence store must behave exactly as one std::vector per list with removal by
// swapping in the last entry: the remesher's order of visits, hence its output, depends on it.
// Random operations on lists that grow well past the inline slot, shrink back and regrow.
TEST(IncidenceLists, BehaveAsVectorsWithSwapRemoval) {
  using detail::IncidenceLists;
  std::mt19937 rng(7);
  IncidenceLists lists;
  std::vector<std::vector<std::int32_t>> model(5);
  lists.assign(model.size());
  std::size_t longest = 0;
  for (int op = 0; op < 200000; ++op) {
    if (op % 50000 == 0) {
      lists.add_list();
      model.emplace_back();
    }
    const std::size_t v = rng() % model.size();
    const unsigned what = rng() % 10;
    auto& m = model[v];
    if (what < 5 || m.empty()) {
      // Lists drift between empty and over three slots' worth.
      const auto t = static_cast<std::int32_t>(rng() % 64);
      if (m.size() < 48) {
        lists.push_back(v, t);
        m.push_back(t);
      }
    } else if (what < 9) {
      const std::int32_t t = rng() % 2 ? m[rng() % m.size()] : static_cast<std::int32_t>(rng() % 64);
      lists.remove(v, t);
      if (auto it = std::find(m.begin(), m.end(), t); it != m.end()) {
        *it = m.back();
        m.pop_back();
      }
    } else if (rng() % 20 == 0) {
      lists.clear(v);
      m.clear();
    }
    longest = std::max(longest, m.size());
    const auto got = lists[v];
    ASSERT_EQ(std::vector<std::int32_t>(got.begin(), got.end()), m) << "after operation " << op << " on list " << v;
  }
  EXPECT_GT(longest, std::size_t(3 * IncidenceLists::kInline));  // the spilled path was exercised
  ASSERT_EQ(lists.lists(), model.size());
  for (std::size_t v = 0; v < model.size(); ++v) {
    const auto got = lists[v];
    EXPECT_EQ(std::vector<std::int32_t>(got.begin(), got.end()), model[v]);
  }
}

TEST(SurfaceRemesher, SplitBoundsEveryEdgeAndKeepsManifold) {
  const auto m = sphere(10.0, 1);  // edges ≈ 7 mm
  SurfaceRemesher r(m);
  const auto n = r.split_long_edges(1.5);
  EXPECT_GT(n, 100);
  const auto out = r.mesh();
  const Facts f = facts(out);
  expect_closed_manifold(f, 2);
  EXPECT_LE(f.max_edge, 1.5);
  // Midpoint splits do not change the enclosed polyhedron.
  EXPECT_TRUE(test::rel_near(f.volume, facts(m).volume, 1e-9));
}

TEST(SurfaceRemesher, CollapseRemovesShortEdgesKeepsTopology) {
  const auto m = sphere(10.0, 5);  // edges ≈ 0.25–0.4 mm
  SurfaceRemesher r(m);
  const auto n = r.collapse_short_edges(1.0, 2.0);
  EXPECT_GT(n, 1000);
  const auto out = r.mesh();
  const Facts f = facts(out);
  expect_closed_manifold(f, 2);
  EXPECT_LE(f.max_edge, 2.0 + 1e-9);
  EXPECT_LT(out.vertices.size(), m.vertices.size() / 4);
  EXPECT_TRUE(test::rel_near(f.volume, 4.0 / 3.0 * kPi * 1000.0, 0.05));
}

// The link condition is what keeps the genus: on a torus whose tube is a triangle (every
// vertex already next to the whole cross-section) collapsing everything short must stop before
// a tube pinches or the hole closes, leaving a closed manifold torus with no vertex below
// valence 3.
TEST(SurfaceRemesher, CollapseStopsAtTheLinkConditionOnAThinTorus) {
  const auto m = torus(10.0, 1.0, 40, 3);
  SurfaceRemesher r(m);
  const auto n = r.collapse_short_edges(100.0, 1000.0);
  EXPECT_GT(n, 0);
  const auto out = r.mesh();
  const Facts f = facts(out);
  expect_closed_manifold(f, 0);
  EXPECT_GE(out.vertices.size(), 7u);  // the smallest triangulated torus
  std::vector<int> valence(out.vertices.size(), 0);
  for (const Tri& t : out.triangles)
    for (int v : t) ++valence[std::size_t(v)];
  EXPECT_GE(*std::min_element(valence.begin(), valence.end()), 3);
}

TEST(SurfaceRemesher, FullRemeshOfTorusKeepsGenusAndVolume) {
  const double R = 10, rr = 3;
  const auto m = torus(R, rr, 24, 10);
  const auto out = remesh(m, {.target_edge_mm = 0.8, .iterations = 4});
  const Facts f = facts(out);
  expect_closed_manifold(f, 0);
  EXPECT_GT(f.min_edge, 0.8 * 0.8 * 0.5);
  EXPECT_LT(f.max_edge, 0.8 * 4.0 / 3.0 + 1e-9);
  // Refined and relaxed: volume within 3 % of the coarse input polyhedron's.
  EXPECT_TRUE(test::rel_near(f.volume, facts(m).volume, 0.03));
}

TEST(SurfaceRemesher, FlipsEvenValences) {
  // Splitting only creates valence-4 vertices; flips must bring the mean deviation from 6 down.
  auto deviation = [](const geometry::TriangleMesh& m) {
    std::vector<int> val(m.vertices.size(), 0);
    for (const Tri& t : m.triangles)
      for (int v : t) val[v]++;
    double s = 0;
    for (int x : val) s += std::abs(x - 6);
    return s / double(val.size());
  };
  SurfaceRemesher r(sphere(10.0, 1));
  r.split_long_edges(2.0);
  const double before = deviation(r.mesh());
  EXPECT_GT(r.flip_edges(), 0);
  const auto out = r.mesh();
  EXPECT_LT(deviation(out), before);
  const Facts f = facts(out);
  expect_closed_manifold(f, 2);
}

TEST(SurfaceRemesher, LockedVerticesStayPut) {
  const auto m = sphere(10.0, 4);
  std::vector<std::uint8_t> locked(m.vertices.size(), 0);
  for (std::size_t i = 0; i < m.vertices.size(); ++i) locked[i] = m.vertices[i].z() > 5.0;
  SurfaceRemesher r(m, locked);
  r.remesh({.target_edge_mm = 1.5, .iterations = 3});
  const auto out = r.mesh();
  const auto lk = r.locked();
  ASSERT_EQ(lk.size(), out.vertices.size());
  // Every original locked vertex survives at its place.
  std::size_t found = 0, expected = 0;
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    if (!locked[i]) continue;
    ++expected;
    for (std::size_t j = 0; j < out.vertices.size(); ++j)
      if (lk[j] && (out.vertices[j] - m.vertices[i]).norm() < 1e-12) {
        ++found;
        break;
      }
  }
  EXPECT_EQ(found, expected);
  EXPECT_TRUE(facts(out).closed_oriented);
}

// Restricted to the active vertices (the upper cap of a sphere whose edges are all out of
// range), the remesher leaves every edge between two inactive vertices as it was; input_index
// names the input vertex of every output vertex left at its input position (bit for bit), and
// every output triangle that is not an input triangle has a touched corner.
TEST(SurfaceRemesher, ActiveVerticesBoundTheChangesAndTheirTraceIsExact) {
  const auto m = sphere(10.0, 3);  // edges ≈ 1.6–2.6 mm
  std::vector<std::uint8_t> active(m.vertices.size());
  for (std::size_t v = 0; v < active.size(); ++v) active[v] = m.vertices[v].z() > 4.0 ? 1 : 0;
  const InputTopology in = input_topology(m);
  const auto& input_edges = in.edges;
  const auto& input_triangles = in.triangles;
  std::size_t kept_restricted = 0, kept_unrestricted = 0;  // inactive input edges left in place
  for (const bool restricted : {true, false}) {
    SurfaceRemesher r(m);
    if (restricted) r.set_active(active);
    const std::int64_t ops = r.split_long_edges(2.0) + r.collapse_short_edges(1.9, 3.0) + r.flip_edges();
    const auto out = r.mesh();
    expect_closed_manifold(facts(out), 2);
    const std::vector<std::int32_t> from = r.input_index();
    const std::vector<std::uint8_t> touched = r.touched();
    ASSERT_EQ(from.size(), out.vertices.size());
    ASSERT_EQ(touched.size(), out.vertices.size());
    std::set<std::pair<int, int>> output_edges;  // in input numbering, between kept vertices
    std::vector<std::uint8_t> kept(m.vertices.size(), 0);
    for (const Tri& t : out.triangles) {
      const std::array<int, 3> src{from[t[0]], from[t[1]], from[t[2]]};
      const bool all_input = src[0] >= 0 && src[1] >= 0 && src[2] >= 0;
      if (!(all_input && input_triangles.count(canonical(src)))) {
        EXPECT_TRUE(touched[t[0]] || touched[t[1]] || touched[t[2]]);
      }
      for (int k = 0; k < 3; ++k) {
        const int a = src[k], b = src[(k + 1) % 3];
        if (a < 0 || b < 0) continue;
        kept[a] = kept[b] = 1;
        output_edges.insert(std::minmax(a, b));
        if (!active[a] && !active[b]) {
          EXPECT_TRUE(input_edges.count(std::minmax(a, b))) << a << "-" << b;
        }
      }
    }
    for (std::size_t v = 0; v < out.vertices.size(); ++v) {
      if (from[v] >= 0) {
        EXPECT_EQ(out.vertices[v], m.vertices[std::size_t(from[v])]);
      }
    }
    // Input edges between two inactive vertices that are both still there: none lost.
    std::size_t inactive_edges = 0, lost = 0;
    for (const auto& [a, b] : input_edges)
      if (!active[a] && !active[b] && kept[a] && kept[b]) {
        ++inactive_edges;
        lost += output_edges.count({a, b}) ? 0 : 1;
      }
    EXPECT_GT(ops, 50);
    EXPECT_EQ(lost, 0u) << restricted;  // (unrestricted: nothing there is left untouched)
    (restricted ? kept_restricted : kept_unrestricted) = inactive_edges;
  }
  EXPECT_GT(kept_restricted, 200u);
  EXPECT_LT(kept_unrestricted, kept_restricted / 4);
  SurfaceRemesher r(m);
  EXPECT_THROW(r.set_active({1, 0}), InvalidInput);
}

// A small active region (under an eighth of the vertices: the passes then visit only the
// triangles with an active corner instead of scanning all of them). After the split every edge
// with an active or new end is within the bound; after collapse and flip the surface is still
// closed and manifold, every input edge between two inactive vertices is still there, and every
// triangle with only inactive corners was in the input.
TEST(SurfaceRemesher, SmallActiveRegionIsRemeshedCompletelyAndAlone) {
  const auto m = sphere(10.0, 3);  // edges ≈ 1.6–2.6 mm
  std::vector<std::uint8_t> active(m.vertices.size());
  std::size_t n_active = 0;
  for (std::size_t v = 0; v < active.size(); ++v) n_active += active[v] = m.vertices[v].z() > 8.0 ? 1 : 0;
  ASSERT_GT(n_active, 20u);
  ASSERT_LT(8 * n_active, m.vertices.size());
  const InputTopology in = input_topology(m);
  const auto& input_edges = in.edges;
  const auto& input_triangles = in.triangles;
  SurfaceRemesher r(m);
  r.set_active(active);
  auto is_active = [&](const std::vector<std::int32_t>& from, int v) { return from[v] < 0 || active[std::size_t(from[v])]; };
  EXPECT_GT(r.split_long_edges(2.0), 0);
  {
    const auto out = r.mesh();
    const auto from = r.input_index();
    for (const Tri& t : out.triangles)
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        if (is_active(from, a) || is_active(from, b)) {
          EXPECT_LE((out.vertices[a] - out.vertices[b]).norm(), 2.0 + 1e-12);
        }
      }
  }
  EXPECT_GT(r.collapse_short_edges(1.9, 3.0) + r.flip_edges(), 0);
  const auto out = r.mesh();
  expect_closed_manifold(facts(out), 2);
  const auto from = r.input_index();
  std::set<std::pair<int, int>> kept_edges;
  std::vector<std::uint8_t> kept(m.vertices.size(), 0);
  for (const Tri& t : out.triangles) {
    const std::array<int, 3> src{from[t[0]], from[t[1]], from[t[2]]};
    if (!is_active(from, t[0]) && !is_active(from, t[1]) && !is_active(from, t[2])) {
      EXPECT_TRUE(input_triangles.count(canonical(src)));
    }
    for (int k = 0; k < 3; ++k)
      if (src[k] >= 0 && src[(k + 1) % 3] >= 0) {
        kept[std::size_t(src[k])] = 1;
        kept_edges.insert(std::minmax(src[k], src[(k + 1) % 3]));
      }
  }
  for (const auto& [a, b] : input_edges)
    if (!active[std::size_t(a)] && !active[std::size_t(b)] && kept[std::size_t(a)] && kept[std::size_t(b)]) {
      EXPECT_TRUE(kept_edges.count({a, b})) << a << "-" << b;
    }
}

// An inactive edge more than twice the split bound, next to active edges being split: every
// triangle on it keeps an edge of at least half its length, so leaving it whole would split
// without end (the remesher once did). The pass ends, with every edge that has an active or a
// new end within the bound, and no runaway: fewer than twice the splits of an unrestricted pass.
TEST(SurfaceRemesher, SplitPassEndsBesideLongInactiveEdges) {
  const auto m = sphere(10.0, 3);  // edges ≈ 1.6–2.6 mm, the bound 1.0
  std::vector<std::uint8_t> active(m.vertices.size());
  for (std::size_t v = 0; v < active.size(); ++v) active[v] = (v % 3 == 0) ? 1 : 0;
  std::int64_t all_splits = 0;
  {
    SurfaceRemesher r(m);
    all_splits = r.split_long_edges(1.0);
  }
  SurfaceRemesher r(m);
  r.set_active(active);
  const std::int64_t splits = r.split_long_edges(1.0);
  EXPECT_GT(splits, 0);
  EXPECT_LT(splits, 2 * all_splits);
  const auto out = r.mesh();
  expect_closed_manifold(facts(out), 2);
  const std::vector<std::int32_t> from = r.input_index();
  std::size_t checked = 0;
  for (const Tri& t : out.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const bool a_active = from[a] < 0 || active[std::size_t(from[a])];
      const bool b_active = from[b] < 0 || active[std::size_t(from[b])];
      if (!a_active && !b_active) continue;
      ++checked;
      EXPECT_LE((out.vertices[a] - out.vertices[b]).norm(), 1.0 + 1e-12) << a << "-" << b;
    }
  EXPECT_GT(checked, 1000u);
}

TEST(SurfaceRemesher, RejectsOpenMesh) {
  auto m = sphere(1.0, 1);
  m.triangles.pop_back();
  EXPECT_THROW(SurfaceRemesher{m}, InvalidInput);
  auto bad = sphere(1.0, 0);
  bad.triangles[0][0] = 99;
  EXPECT_THROW(SurfaceRemesher{bad}, InvalidInput);
  EXPECT_THROW((SurfaceRemesher{sphere(1.0, 0), std::vector<std::uint8_t>(2, 0)}), InvalidInput);
}

// Two closed, outward tetrahedra sharing the edge 0-1 (four triangles on it): every edge runs
// once each way per tetrahedron, so only a count per vertex tells it is not a 2-manifold.
TEST(SurfaceRemesher, RejectsTwoClosedPiecesSharingAnEdge) {
  geometry::TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}, {0, 0, -1}};
  auto tetrahedron = [&](std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
    m.triangles.push_back({a, c, b});
    m.triangles.push_back({a, b, d});
    m.triangles.push_back({a, d, c});
    m.triangles.push_back({b, c, d});
  };
  tetrahedron(0, 1, 2, 3);
  tetrahedron(0, 1, 4, 5);
  EXPECT_FALSE(facts(m).closed_oriented);  // the fixture: 0→1 runs twice
  EXPECT_THROW(SurfaceRemesher{m}, InvalidInput);
}

// The manifold check's message names the defect met first in vertex order (the lowest vertex
// of the two turned-over triangles), so a caller can find it.
TEST(SurfaceRemesher, NonManifoldMessageNamesTheLowestVertex) {
  auto m = sphere(1.0, 5);  // 4 098 vertices: several chunks
  ASSERT_GT(m.vertices.size(), 4096u);
  // Two triangles turned over: their edges run the same way as their neighbours'.
  const std::size_t late = m.triangles.size() - 1, early = m.triangles.size() / 2;
  std::swap(m.triangles[late][1], m.triangles[late][2]);
  std::swap(m.triangles[early][1], m.triangles[early][2]);
  const std::int32_t lowest = std::min({m.triangles[early][0], m.triangles[early][1], m.triangles[early][2],
                                        m.triangles[late][0], m.triangles[late][1], m.triangles[late][2]});
  try {
    SurfaceRemesher r{m};
    FAIL() << "accepted a mesh with turned-over triangles";
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("(edge " + std::to_string(lowest) + "-"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace ido::meshing

// SPDX-License-Identifier: Apache-2.0
// The boundary surface: face records keyed by their points, an intact block's surface is its
// box, and after random drilling the v_lists equal a point-location reference and assemble into
// a closed 2-manifold enclosing the leaf volume. Worker threads rebuilding the lists are tested
// in threads_test (label threads).
#include "ido/drill/boundary_surface.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <unordered_map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/mesh_checks.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

struct SurfaceCheck {
  std::size_t boundary_edges = 0;     // undirected edges used once
  std::size_t unbalanced_edges = 0;   // directed uses differ from reverse uses
  double volume = 0.0;                // divergence theorem (mm³)
};

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

SurfaceCheck check_surface(const geometry::TriangleMesh& m) {
  std::unordered_map<std::uint64_t, int> directed;
  SurfaceCheck c;
  for (const auto& t : m.triangles) {
    for (int e = 0; e < 3; ++e) ++directed[edge_key(t[static_cast<std::size_t>(e)], t[static_cast<std::size_t>((e + 1) % 3)])];
    c.volume += m.vertices[static_cast<std::size_t>(t[0])].dot(
                    m.vertices[static_cast<std::size_t>(t[1])].cross(m.vertices[static_cast<std::size_t>(t[2])])) / 6.0;
  }
  for (const auto& [e, n] : directed) {
    const auto it = directed.find(edge_key(static_cast<std::int32_t>(e & 0xFFFFFFFFU), static_cast<std::int32_t>(e >> 32)));
    const int back = it == directed.end() ? 0 : it->second;
    if (n != back) ++c.unbalanced_edges;
    if (n + back == 1) ++c.boundary_edges;
  }
  return c;
}

double leaf_volume(const TetHierarchy& h) { return h.material_volume(); }

// The 32-byte face record gives back each corner's global key exactly: random barycentric
// keys of every weight from 0 to kBaryScale (corners, edges, faces and the inside of a root),
// packed with the root's vertex ids in increasing order as the v_list walk packs them, read
// back equal to point_key().
TEST(BoundarySurface, FaceRecordKeysArePointKeys) {
  TetHierarchy h(make_block({8, 8, 4}, 2.0));
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> root(0, static_cast<int>(h.root_count()) - 1), weight(0, kBaryScale), zero(0, 3);
  auto random_key = [&] {
    BaryKey k{};
    // Three cut points in [0, kBaryScale], some entries forced to 0 (points on faces, edges, corners).
    std::array<int, 3> cut{weight(rng), weight(rng), weight(rng)};
    std::sort(cut.begin(), cut.end());
    k = {cut[0], cut[1] - cut[0], cut[2] - cut[1], kBaryScale - cut[2]};
    for (int z = zero(rng); z > 0; --z) {
      const auto i = static_cast<std::size_t>(zero(rng));
      k[(i + 1) % 4] += k[i];
      k[i] = 0;
    }
    return k;
  };
  for (int trial = 0; trial < 20000; ++trial) {
    const auto r = static_cast<std::size_t>(root(rng));
    const std::array<BaryKey, 3> corner{random_key(), random_key(), random_key()};
    const Tet& t = h.root_tet(r);
    std::array<std::size_t, 4> order{0, 1, 2, 3};
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return t[a] < t[b]; });
    std::array<std::int32_t, 4> ids{};
    std::array<BaryKey, 3> sorted{};
    for (std::size_t i = 0; i < 4; ++i) {
      ids[i] = t[order[i]];
      for (std::size_t c = 0; c < 3; ++c) sorted[c][i] = corner[c][order[i]];
    }
    const SurfaceFace f(ids, sorted);
    for (std::size_t c = 0; c < 3; ++c) ASSERT_EQ(f.key(c), point_key(h, r, corner[c])) << "trial " << trial << " corner " << c;
  }
}

TEST(BoundarySurface, IntactBlockSurfaceIsItsBox) {
  TetHierarchy h(make_cube12(10.0));
  BoundarySurface s(h);
  const auto mesh = assemble_surface(s.v_lists(), h.vertices());
  EXPECT_EQ(mesh.triangles.size(), 12U);
  const auto c = check_surface(mesh);
  EXPECT_EQ(c.boundary_edges, 0U);
  EXPECT_TRUE(test::rel_near(c.volume, 1000.0, 1e-12));
}

TEST(BoundarySurface, ClosedAndEnclosesTheLeafVolumeAfterRandomDrilling) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    TetHierarchy h(trial % 2 == 0 ? make_cube12(10.0) : make_block({10, 8, 6}, 2.0));
    BoundarySurface surface(h);
    Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 3 + trial % 3});
    for (int step = 0; step < 12; ++step) {
      const Vec3 c(10 * u(rng), 8 * u(rng), 6 * u(rng));
      eroder.erode(h, c, 0.5 + 2.0 * u(rng), 1.0, 0.01);
      surface.update(h, eroder.changed_roots(), eroder.changed_root_faces());
      eroder.clear_changed_roots();
      {
        // Rebuilding only changed roots and the neighbours across touched root faces gives
        // exactly the v_lists of a full rebuild.
        const BoundarySurface fresh(h);
        for (std::size_t r = 0; r < h.root_count(); ++r)
          ASSERT_TRUE(fresh.v_list(r) == surface.v_list(r)) << "trial " << trial << " step " << step << " root " << r;
      }
      if (step % 3 != 2) continue;
      const auto mesh = assemble_surface(surface.v_lists(), h.vertices());
      const auto check = check_surface(mesh);
      ASSERT_EQ(check.boundary_edges, 0U) << "trial " << trial << " step " << step;
      ASSERT_EQ(check.unbalanced_edges, 0U) << "trial " << trial << " step " << step;
      ASSERT_TRUE(test::rel_near(check.volume, leaf_volume(h), 1e-9)) << "trial " << trial << " step " << step;
    }
    // Incremental v_lists equal a full rebuild.
    const BoundarySurface fresh(h);
    for (std::size_t r = 0; r < h.root_count(); ++r) ASSERT_TRUE(fresh.v_list(r) == surface.v_list(r));
  }
}

// Reference v_list by point location, independent of the top-down walk: a face of a full
// leaf at depth d is probed just outside its centroid; outside the mesh or an erased leaf no
// deeper than d → the face is visible; a full leaf no deeper than d → hidden; a deeper leaf
// → the node across is refined: split the face at its edge midpoints and probe the four
// parts at depth d + 1. Faces are oriented outward from their vertex positions.
using FaceKeys = std::array<PointKey, 3>;

bool key_less(const PointKey& a, const PointKey& b) { return std::tie(a.id, a.weight) < std::tie(b.id, b.weight); }

FaceKeys canonical(FaceKeys f) {
  while (key_less(f[1], f[0]) || key_less(f[2], f[0])) std::rotate(f.begin(), f.begin() + 1, f.end());
  return f;
}

bool face_less(const FaceKeys& a, const FaceKeys& b) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (key_less(a[i], b[i])) return true;
    if (key_less(b[i], a[i])) return false;
  }
  return false;
}

void reference_faces(const TetHierarchy& h, std::size_t r, const std::array<BaryKey, 3>& tri, int depth, const Vec3& normal,
                     std::vector<FaceKeys>& out) {
  const Vec3 centroid = (h.world_position(r, tri[0]) + h.world_position(r, tri[1]) + h.world_position(r, tri[2])) / 3.0;
  const Location loc = h.locate(centroid + 1e-7 * normal);
  const bool erased = !loc.inside_mesh || loc.state == NodeState::Erased;
  if (!loc.inside_mesh || loc.leaf.depth <= depth) {
    if (erased) out.push_back(canonical({point_key(h, r, tri[0]), point_key(h, r, tri[1]), point_key(h, r, tri[2])}));
    return;
  }
  auto mid = [](const BaryKey& a, const BaryKey& b) {
    BaryKey m{};
    for (std::size_t j = 0; j < 4; ++j) m[j] = (a[j] + b[j]) / 2;
    return m;
  };
  const BaryKey ab = mid(tri[0], tri[1]), bc = mid(tri[1], tri[2]), ca = mid(tri[2], tri[0]);
  for (const auto& sub : {std::array<BaryKey, 3>{tri[0], ab, ca}, std::array<BaryKey, 3>{ab, tri[1], bc},
                          std::array<BaryKey, 3>{ca, bc, tri[2]}, std::array<BaryKey, 3>{ab, bc, ca}})
    reference_faces(h, r, sub, depth + 1, normal, out);
}

std::vector<FaceKeys> reference_v_list(const TetHierarchy& h, std::size_t r) {
  std::vector<FaceKeys> out;
  h.for_each_leaf(r, [&](const NodeRef& n, NodeState st) {
    if (st != NodeState::Full) return;
    const NodeGeometry g = h.geometry(n);
    for (std::size_t f = 0; f < 4; ++f) {
      std::array<BaryKey, 3> tri{};
      std::size_t k = 0;
      for (std::size_t v = 0; v < 4; ++v)
        if (v != f) tri[k++] = g.vertex[v];
      const Vec3 a = h.world_position(r, tri[0]), b = h.world_position(r, tri[1]), c = h.world_position(r, tri[2]);
      Vec3 normal = (b - a).cross(c - a);
      if (normal.dot(h.world_position(r, g.vertex[f]) - a) > 0.0) {
        std::swap(tri[1], tri[2]);
        normal = -normal;
      }
      reference_faces(h, r, tri, n.depth, normal.normalized(), out);
    }
  });
  std::sort(out.begin(), out.end(), face_less);
  return out;
}

TEST(BoundarySurface, VListsEqualAPointLocationReference) {
  // Random drilling with budgeted erosion and budgeted chunk rebuilds; after flushing, every
  // root's v_list (as a set of outward faces) is the point-location reference.
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    TetHierarchy h(trial == 1 ? make_cube12(10.0) : make_block({10, 8, 6}, 2.0));
    BoundarySurface surface(h, {.chunk_level = trial});
    Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 3 + trial, .max_node_visits = 500});
    std::size_t checked = 0;
    for (int step = 0; step < 10; ++step) {
      const Vec3 c(10 * u(rng), 8 * u(rng), 6 * u(rng));
      eroder.enqueue(c, 0.8 + 1.5 * u(rng), 1.0, 0.01);
      while (eroder.has_pending()) {
        (void)eroder.run(h, 500);
        surface.update(h, eroder.changed_nodes(), 700);
        eroder.clear_changed_roots();
      }
      surface.flush(h);
      if (step % 3 != 2) continue;
      for (std::size_t r = 0; r < h.root_count(); ++r) {
        std::vector<FaceKeys> mine;
        for (const auto& f : surface.v_list(r)) mine.push_back(canonical({f.key(0), f.key(1), f.key(2)}));
        std::sort(mine.begin(), mine.end(), face_less);
        const auto ref = reference_v_list(h, r);
        ASSERT_EQ(mine.size(), ref.size()) << "trial " << trial << " step " << step << " root " << r;
        for (std::size_t i = 0; i < ref.size(); ++i)
          ASSERT_TRUE(mine[i] == ref[i]) << "trial " << trial << " step " << step << " root " << r << " face " << i;
        checked += ref.size();
      }
    }
    EXPECT_GT(checked, 1000U) << "trial " << trial;  // the drilling exposed faces at several depths
  }
}

// Vertices that share their position with another vertex (copies made by the split).
std::size_t coincident_vertices(const geometry::TriangleMesh& m) {
  std::vector<std::array<double, 3>> p;
  for (const auto& v : m.vertices) p.push_back({v.x(), v.y(), v.z()});
  std::sort(p.begin(), p.end());
  std::size_t n = 0;
  for (std::size_t i = 1; i < p.size(); ++i) n += p[i] == p[i - 1] ? 1U : 0U;
  return n;
}

TEST(BoundarySurface, DrilledSurfacesAreClosedTwoManifolds) {
  // Grooves that leave and re-enter a block and holes through a 2 mm plate make leaves that
  // touch along an edge or at a point only; the assembled surface splits those contacts:
  // closed, edge- and vertex-manifold, oriented, and enclosing exactly the leaves' volume.
  std::size_t split = 0;
  for (unsigned seed = 1; seed <= 16; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const bool plate = seed % 2 == 0;
    TetHierarchy h(plate ? make_block({10, 10, 2}, 1.0) : make_block({12, 10, 6}, 2.0));
    const double r = plate ? 0.5 + 0.6 * u(rng) : 0.6 + 0.8 * u(rng);
    Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = plate ? 4 : 4 + static_cast<int>(seed % 3), .max_node_visits = 0});
    std::vector<Vec3> path;
    if (plate) {
      for (int k = 0; k < 4; ++k) {  // vertical holes through the plate, and a slot between two
        const Vec3 top(1.5 + 7 * u(rng), 1.5 + 7 * u(rng), 3.5);
        path.push_back(top);
        path.push_back(top - Vec3(0, 0, 5));
      }
    } else {
      for (int k = 0; k < 7; ++k)  // dipping in and out of the top face
        path.emplace_back(12 * u(rng), 10 * u(rng), k % 2 == 0 ? 6 + r * (0.5 + u(rng)) : 6 - r * (0.2 + 1.2 * u(rng)));
    }
    for (std::size_t k = 1; k < path.size(); ++k) {
      const int n = std::max(1, static_cast<int>(std::ceil((path[k] - path[k - 1]).norm() / (0.25 * r))));
      for (int i = 0; i <= n; ++i) e.erode(h, path[k - 1] + (path[k] - path[k - 1]) * (double(i) / n), r, 1.0, 1e-3);
    }
    const BoundarySurface surface(h);
    const auto mesh = assemble_surface(surface.v_lists(), h.vertices());
    const auto check = geometry::check_mesh(mesh);
    EXPECT_TRUE(check.closed);
    EXPECT_EQ(check.non_manifold_edges, 0U);
    EXPECT_EQ(check.non_manifold_vertices, 0U);
    EXPECT_TRUE(check.oriented);
    EXPECT_TRUE(test::rel_near(check.signed_volume_mm3, h.material_volume(), 1e-9));
    split += coincident_vertices(mesh);
  }
  EXPECT_GT(split, 0U);  // the paths do make edge- or point-only contacts
}

}  // namespace
}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
// Embedding: leaves follow their roots when the root mesh deforms. The deformation here is
// prescribed (a bend growing in time) rather than computed by sim::World.
#include <cmath>
#include <unordered_map>

#include <gtest/gtest.h>

#include "ido/drill/boundary_surface.h"
#include "ido/drill/embedding.h"
#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

double enclosed_volume(const geometry::TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles)
    v += m.vertices[static_cast<std::size_t>(t[0])].dot(
             m.vertices[static_cast<std::size_t>(t[1])].cross(m.vertices[static_cast<std::size_t>(t[2])])) / 6.0;
  return v;
}

std::size_t boundary_edges(const geometry::TriangleMesh& m) {
  std::unordered_map<std::uint64_t, int> count;
  for (const auto& t : m.triangles)
    for (int e = 0; e < 3; ++e) {
      auto a = static_cast<std::uint32_t>(t[static_cast<std::size_t>(e)]);
      auto b = static_cast<std::uint32_t>(t[static_cast<std::size_t>((e + 1) % 3)]);
      if (a > b) std::swap(a, b);
      ++count[(static_cast<std::uint64_t>(a) << 32) | b];
    }
  std::size_t n = 0;
  for (const auto& [k, c] : count) n += c == 1 ? 1 : 0;
  return n;
}

TEST(Embedding, DrilledDetailFollowsAnAffineDeformationExactly) {
  TetHierarchy h(make_block({12, 12, 8}, 3.0));
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 4});
  for (int i = 0; i <= 20; ++i) eroder.erode(h, Vec3(4 + 0.2 * i, 6, 8), 2.0, 1.0, 0.0);
  const BoundarySurface before(h);
  const auto rest = assemble_surface(before.v_lists(), h.vertices());
  const double volume0 = h.material_volume();
  const auto leaves0 = full_leaf_embeddings(h);
  Mat3 a;
  a << 1.1, 0.2, 0.0, -0.1, 0.95, 0.15, 0.05, 0.0, 1.05;
  const Vec3 shift(3, -2, 1);
  std::vector<Vec3> moved;
  for (const auto& v : h.vertices()) moved.push_back(a * v + shift);
  h.set_vertex_positions(moved);
  const BoundarySurface after(h);
  const auto deformed = assemble_surface(after.v_lists(), h.vertices());
  ASSERT_EQ(deformed.vertices.size(), rest.vertices.size());
  for (std::size_t i = 0; i < rest.vertices.size(); ++i)
    ASSERT_LT((deformed.vertices[i] - (a * rest.vertices[i] + shift)).norm(), 1e-10) << "vertex " << i;
  EXPECT_TRUE(test::rel_near(h.material_volume(), volume0 * a.determinant(), 1e-12));
  EXPECT_TRUE(test::rel_near(enclosed_volume(deformed), h.material_volume(), 1e-9));
  // The embeddings themselves do not change; only the world positions do.
  const auto leaves1 = full_leaf_embeddings(h);
  ASSERT_EQ(leaves0.size(), leaves1.size());
  for (std::size_t i = 0; i < leaves0.size(); i += 97) EXPECT_EQ(leaves0[i].barycentric, leaves1[i].barycentric);
}

TEST(Embedding, BlockDrilledWhileItBends) {
  const auto mesh = make_block({16, 8, 8}, 2.0);
  TetHierarchy h(mesh);
  BoundarySurface surface(h);
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 3});
  const double r = 1.5;
  for (int step = 0; step <= 30; ++step) {
    // A slight bend growing in time: z += a(t) · sin(π x / 16), with a small x-compression.
    const double amp = 0.03 * step;
    std::vector<Vec3> moved;
    for (const auto& v : mesh.vertices) moved.emplace_back(v.x() * (1.0 - 0.002 * step), v.y(), v.z() + amp * std::sin(kPi * v.x() / 16.0));
    h.set_vertex_positions(moved);
    // The burr goes down a fixed vertical line in world space.
    const Vec3 c(8.0, 4.0, 9.0 - 0.15 * step);
    eroder.erode(h, c, r, 1.0, 0.0);
    surface.update(h, eroder.changed_roots());
    eroder.clear_changed_roots();
    // Deformation changes every root's geometry but not the v_lists: rebuild only what
    // erosion touched, and compare with a full rebuild.
    if (step % 10 == 0) {
      const BoundarySurface fresh(h);
      const auto m = assemble_surface(surface.v_lists(), h.vertices());
      const auto f = assemble_surface(fresh.v_lists(), h.vertices());
      EXPECT_EQ(m.triangles.size(), f.triangles.size());
      EXPECT_EQ(boundary_edges(m), 0U) << "step " << step;
      EXPECT_TRUE(test::rel_near(enclosed_volume(m), h.material_volume(), 1e-9)) << "step " << step;
    }
    // No finest-level leaf whose centroid lies in the current burr survives.
    for (std::size_t root = 0; root < h.root_count(); ++root)
      h.for_each_leaf(root, [&](const NodeRef& n, NodeState s) {
        if (s != NodeState::Full) return;
        const auto x = h.world_vertices(n);
        const Vec3 centroid = 0.25 * (x[0] + x[1] + x[2] + x[3]);
        EXPECT_GT((centroid - c).norm(), r - 1e-12) << "step " << step;
      });
  }
  // The burr did cut (more than half of one ball of material went).
  EXPECT_LT(h.material_volume(), 16.0 * 8 * 8 * (1.0 - 0.06) * 1.0 - 0.5 * 4.0 / 3.0 * kPi * r * r * r);
}

}  // namespace
}  // namespace ido::drill

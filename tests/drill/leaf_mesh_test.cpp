// SPDX-License-Identifier: Apache-2.0
// The remaining material as a tetrahedral mesh: one positively oriented tetrahedron per full
// leaf, at that leaf's corners, in the walk's leaf order, filling exactly the material left; its
// vertices welded (each used, no two at one place); the held mesh is the walk's, with each
// tetrahedron's leaf depth, root and density.
#include "ido/drill/leaf_mesh.h"

#include <algorithm>
#include <array>
#include <vector>

#include <gtest/gtest.h>

#include "ido/drill/shapes.h"
#include "support/drilled_block.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

TEST(LeafMesh, OneTetrahedronPerFullLeafFillingTheMaterial) {
  const TetHierarchy h = test::drilled_block();
  std::size_t full = 0;
  for (std::size_t r = 0; r < h.root_count(); ++r)
    h.for_each_leaf(r, [&](const NodeRef&, NodeState s) { full += s == NodeState::Full ? 1 : 0; });
  const LeafMeshWalk walk(h);
  ASSERT_EQ(walk.tet_count(), full);
  const geometry::TetMesh mesh = full_leaf_mesh(h);
  ASSERT_EQ(mesh.tets.size(), full);
  ASSERT_EQ(mesh.vertices.size(), walk.vertex_count());
  std::vector<NodeRef> leaves;
  walk.for_each_leaf([&](const NodeRef& n) { leaves.push_back(n); });
  ASSERT_EQ(leaves.size(), full);
  double volume = 0.0;
  for (std::size_t k = 0; k < mesh.tets.size(); ++k) {
    const Tet& t = mesh.tets[k];
    std::array<Vec3, 4> x;
    for (int c = 0; c < 4; ++c) x[std::size_t(c)] = mesh.vertices[std::size_t(t[std::size_t(c)])];
    const double v = signed_volume(x[0], x[1], x[2], x[3]);
    ASSERT_GT(v, 0.0) << "tetrahedron " << k;
    volume += v;
    // Its corners are its leaf's, in some order.
    auto corners = h.world_vertices(leaves[k]);
    auto key = [](const Vec3& a, const Vec3& b) { return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3); };
    std::sort(corners.begin(), corners.end(), key);
    std::sort(x.begin(), x.end(), key);
    for (int c = 0; c < 4; ++c) ASSERT_EQ(x[std::size_t(c)], corners[std::size_t(c)]) << "tetrahedron " << k;
    EXPECT_EQ(mesh.cell_fields.at("depth").values[k], leaves[k].depth);
    EXPECT_EQ(mesh.cell_fields.at("root").values[k], double(leaves[k].root));
    EXPECT_EQ(mesh.cell_fields.at("density").values[k], h.density(leaves[k].root));
  }
  EXPECT_TRUE(test::rel_near(volume, h.material_volume(), 1e-12));
  std::size_t walked = 0;
  walk.for_each_tet([&](const Tet& t) {
    EXPECT_EQ(t, mesh.tets[walked]);
    ++walked;
  });
  EXPECT_EQ(walked, mesh.tets.size());
}

// Welding: every vertex is used, and no two vertices share a position.
TEST(LeafMeshWalk, VerticesAreWeldedAndUsed) {
  const auto h = test::drilled_block();
  const LeafMeshWalk walk(h);
  std::vector<std::array<double, 3>> points;
  walk.for_each_vertex([&](const Vec3& p) { points.push_back({p.x(), p.y(), p.z()}); });
  ASSERT_EQ(points.size(), walk.vertex_count());
  std::vector<int> used(points.size(), 0);
  std::size_t tets = 0;
  walk.for_each_tet([&](const Tet& t) {
    ++tets;
    for (const auto v : t) used.at(std::size_t(v)) = 1;
  });
  EXPECT_EQ(tets, walk.tet_count());
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
  std::sort(points.begin(), points.end());
  EXPECT_EQ(std::adjacent_find(points.begin(), points.end()), points.end());
}

// An intact block: its roots, welded into the block's own vertices.
TEST(LeafMesh, IntactBlockIsItsRootMesh) {
  const geometry::TetMesh block = make_block({4, 4, 2}, 2.0);
  const TetHierarchy h(block);
  const geometry::TetMesh mesh = full_leaf_mesh(h);
  EXPECT_EQ(mesh.tets.size(), block.tets.size());
  EXPECT_EQ(mesh.vertices.size(), block.vertices.size());
  for (double d : mesh.cell_fields.at("depth").values) EXPECT_EQ(d, 0.0);
}

}  // namespace
}  // namespace ido::drill

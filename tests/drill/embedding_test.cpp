// SPDX-License-Identifier: Apache-2.0
// Embedding: leaves follow their roots when the root mesh deforms — under prescribed
// deformations (affine, a growing bend) and under a sim::World (corotational FEM, implicit
// Euler) deforming the block while the drill runs.
#include <cmath>
#include <unordered_map>

#include <gtest/gtest.h>

#include "ido/drill/boundary_surface.h"
#include "ido/drill/embedding.h"
#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/world.h"
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
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 0});
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
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 3, .max_node_visits = 0});
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

TEST(Embedding, BlockDrilledWhileASimWorldStretchesIt) {
  // A soft block (E = 100 kPa, ν = 0, corotational FEM, implicit Euler, 10 ms steps) with its
  // bottom face clamped and its top face pulled up 3 % over the first 30 steps, drilled from
  // the top along a fixed line in world space while it deforms. With ν = 0 the static state
  // is the homogeneous stretch F = diag(1, 1, 1 + ε) (P = 2μ(F − I) is uniform).
  const double sx = 12, sy = 8, sz = 6, eps = 0.03;
  const auto mesh = make_block({sx, sy, sz}, 2.0);
  TetHierarchy h(mesh);
  BoundarySurface surface(h);
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 3, .max_node_visits = 2000});
  sim::World world;
  world.add_tet_body(mesh, 1000.0);
  world.emplace_model<sim::CorotationalFem>(mesh.tets, world.particles().positions(), sim::ElasticMaterial{1e5, 0.0});
  world.set_integrator("implicit_euler");
  world.external().damping.mass_per_s = 5.0;
  std::vector<std::size_t> top;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (mesh.vertices[i].z() < 1e-9) world.particles().set_fixed(i, true);
    if (mesh.vertices[i].z() > sz - 1e-9) {
      world.particles().set_fixed(i, true);
      top.push_back(i);
    }
  }
  const std::vector<Vec3> rest = mesh.vertices;
  // Root affine maps rest → current: x = A X + b.
  auto root_map = [&](std::size_t r) {
    const Tet& t = h.root_tet(r);
    Mat3 dr, dc;
    for (int k = 0; k < 3; ++k) {
      dr.col(k) = rest[static_cast<std::size_t>(t[static_cast<std::size_t>(k + 1)])] - rest[static_cast<std::size_t>(t[0])];
      dc.col(k) = h.vertices()[static_cast<std::size_t>(t[static_cast<std::size_t>(k + 1)])] -
                  h.vertices()[static_cast<std::size_t>(t[0])];
    }
    const Mat3 a = dc * dr.inverse();
    return std::pair<Mat3, Vec3>{a, h.vertices()[static_cast<std::size_t>(t[0])] - a * rest[static_cast<std::size_t>(t[0])]};
  };
  double max_displacement = 0.0;
  const double r = 1.2;
  for (int step = 0; step <= 60; ++step) {
    const double stretch = eps * std::min(1.0, step / 30.0);
    for (const auto i : top) world.particles().positions()[i].z() = sz * (1.0 + stretch);
    world.step(0.01);
    h.set_vertex_positions(world.particles().positions());
    for (std::size_t i = 0; i < rest.size(); ++i) max_displacement = std::max(max_displacement, (h.vertices()[i] - rest[i]).norm());
    // The burr goes down a fixed vertical line in world space, 0.05 mm per step.
    const Vec3 c(6.2, 3.9, sz + 1.0 - 0.05 * step);
    eroder.erode(h, c, r, 1.0, 0.01);
    surface.update(h, eroder.changed_nodes());
    eroder.clear_changed_roots();
    if (step % 10 != 0) continue;
    // Leaf centroids from the embedding (root barycentrics of the leaf vertices) equal the
    // rest centroids mapped by their root's current affine map, and the path-derived world
    // vertices agree.
    for (const auto& leaf : full_leaf_embeddings(h)) {
      std::array<double, 4> lambda{};
      for (const auto& v : leaf.barycentric)
        for (std::size_t k = 0; k < 4; ++k) lambda[k] += 0.25 * v[k];
      const Tet& t = h.root_tet(leaf.root);
      Vec3 rest_centroid = Vec3::Zero();
      for (std::size_t k = 0; k < 4; ++k) rest_centroid += lambda[k] * rest[static_cast<std::size_t>(t[k])];
      const auto [a, b] = root_map(leaf.root);
      const Vec3 embedded = embedded_position(h, leaf.root, lambda);
      ASSERT_LT((embedded - (a * rest_centroid + b)).norm(), 1e-9) << "step " << step;
    }
    for (std::size_t root = 0; root < h.root_count(); root += 5)
      h.for_each_leaf(root, [&](const NodeRef& n, NodeState s) {
        if (s != NodeState::Full) return;
        const auto x = h.world_vertices(n);
        const auto g = h.geometry(n);
        for (std::size_t k = 0; k < 4; ++k)
          ASSERT_LT((x[k] - h.world_position(root, g.vertex[k])).norm(), 1e-9);
      });
    // The drilled surface stays closed and encloses the remaining material.
    const auto m = assemble_surface(surface.v_lists(), h.vertices());
    EXPECT_EQ(boundary_edges(m), 0U) << "step " << step;
    EXPECT_TRUE(test::rel_near(enclosed_volume(m), h.material_volume(), 1e-9)) << "step " << step;
  }
  (void)eroder.finish(h);
  surface.update(h, eroder.changed_nodes());
  eroder.clear_changed_roots();
  EXPECT_GT(max_displacement, 0.1);  // the world did deform the block while it was drilled
  // Settle to static equilibrium: the homogeneous stretch.
  const auto st = sim::solve_static(world);
  ASSERT_TRUE(st.converged);
  h.set_vertex_positions(world.particles().positions());
  const Mat3 f_expected = Vec3(1.0, 1.0, 1.0 + eps).asDiagonal();
  for (std::size_t root = 0; root < h.root_count(); ++root)
    ASSERT_LT((root_map(root).first - f_expected).norm(), 1e-6) << "root " << root;
  const double removed_now = h.total_volume() - h.material_volume();
  EXPECT_TRUE(test::rel_near(h.total_volume(), sx * sy * sz * (1.0 + eps), 1e-6));
  const auto m = assemble_surface(surface.v_lists(), h.vertices());
  EXPECT_EQ(boundary_edges(m), 0U);
  EXPECT_TRUE(test::rel_near(enclosed_volume(m), h.material_volume(), 1e-9));
  // Back to the rest shape: the removed volume scales by 1 / det F.
  h.set_vertex_positions(rest);
  const double removed_rest = h.total_volume() - h.material_volume();
  ASSERT_GT(removed_rest, 1.0);  // the burr did cut (more than 1 mm³)
  EXPECT_TRUE(test::rel_near(removed_now / removed_rest, 1.0 + eps, 1e-5));
  // The cut hole follows the block: a full leaf's centroid never lies within the burr's
  // last position mapped back to the rest shape, i.e. the hole moved with the material.
  const Vec3 last_world(6.2, 3.9, sz + 1.0 - 0.05 * 60);
  const Vec3 last_rest(last_world.x(), last_world.y(), last_world.z() / (1.0 + eps * 1.0));
  for (std::size_t root = 0; root < h.root_count(); ++root)
    h.for_each_leaf(root, [&](const NodeRef& n, NodeState s) {
      if (s != NodeState::Full || n.depth < 3) return;
      const auto x = h.world_vertices(n);
      const Vec3 centroid = 0.25 * (x[0] + x[1] + x[2] + x[3]);
      // Inside the burr's ball shrunk by the stretch (radius ≥ r / (1 + ε), less a margin for the
      // dynamic state at the cut) no finest leaf is left.
      EXPECT_GT((centroid - last_rest).norm(), r * (1.0 - 2.0 * eps));
    });
}

}  // namespace
}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/assembled_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/geometry/mesh_checks.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

// A block with grooves dipping in and out of its top face, at several depths of refinement:
// leaves touching along edges only, so the 2-manifold split makes vertex copies.
TetHierarchy grooved_block(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TetHierarchy h(make_block({12, 10, 6}, 2.0));
  const double r = 0.6 + 0.8 * u(rng);
  Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = 4 + static_cast<int>(seed % 3), .max_node_visits = 0});
  std::vector<Vec3> path;
  for (int k = 0; k < 7; ++k)
    path.emplace_back(12 * u(rng), 10 * u(rng), k % 2 == 0 ? 6 + r * (0.5 + u(rng)) : 6 - r * (0.2 + 1.2 * u(rng)));
  for (std::size_t k = 1; k < path.size(); ++k) {
    const int n = std::max(1, static_cast<int>(std::ceil((path[k] - path[k - 1]).norm() / (0.25 * r))));
    for (int i = 0; i <= n; ++i) e.erode(h, path[k - 1] + (path[k] - path[k - 1]) * (double(i) / n), r, 1.0, 1e-3);
  }
  return h;
}

bool same_mesh(const geometry::TriangleMesh& a, const geometry::TriangleMesh& b) {
  if (a.vertices.size() != b.vertices.size() || a.triangles != b.triangles) return false;
  for (std::size_t i = 0; i < a.vertices.size(); ++i)
    if (a.vertices[i] != b.vertices[i]) return false;  // the same arithmetic: bit for bit
  return a.cell_fields.at("root").values == b.cell_fields.at("root").values;
}

// The surface taken over root by root, and its 2-manifold split worked one vertex at a time,
// are the surface assembled from v_lists kept by the caller in one batch: the same vertices,
// triangles and roots, and a closed 2-manifold that encloses the leaves' volume.
TEST(AssembledSurface, TakingTheListsAndBatchingTheSplitChangeNothing) {
  std::size_t copies = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(seed);
    const auto h = grooved_block(seed);
    const BoundarySurface surface(h);
    const AssembledSurface kept(surface.v_lists(), h.vertices(), {.star_batch_corners = std::size_t(1) << 30});
    const auto reference = kept.to_mesh();
    auto lists = surface.v_lists();
    const AssembledSurface taken(std::move(lists), h.vertices(), {.star_batch_corners = 1});
    EXPECT_TRUE(lists.empty() || lists.front().empty());
    EXPECT_TRUE(same_mesh(taken.to_mesh(), reference));
    EXPECT_EQ(taken.vertex_count(), reference.vertices.size());
    EXPECT_EQ(taken.triangle_count(), reference.triangles.size());
    const auto check = geometry::check_mesh(reference);
    EXPECT_TRUE(check.closed);
    EXPECT_EQ(check.non_manifold_edges, 0U);
    EXPECT_EQ(check.non_manifold_vertices, 0U);
    EXPECT_TRUE(test::rel_near(check.signed_volume_mm3, h.material_volume(), 1e-9));
    // Vertex copies share their original's position: count positions met twice.
    std::vector<std::array<double, 3>> p;
    for (const auto& v : reference.vertices) p.push_back({v.x(), v.y(), v.z()});
    std::sort(p.begin(), p.end());
    for (std::size_t i = 1; i < p.size(); ++i) copies += p[i] == p[i - 1] ? 1U : 0U;
  }
  EXPECT_GT(copies, 0U);  // the grooves do make edge- or point-only contacts
}

}  // namespace
}  // namespace ido::drill

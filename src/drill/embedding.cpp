// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/embedding.h"

#include <algorithm>
#include <unordered_map>

#include "ido/drill/boundary_surface.h"

namespace ido::drill {

std::vector<LeafEmbedding> full_leaf_embeddings(const TetHierarchy& hierarchy) {
  std::vector<LeafEmbedding> out;
  for (std::size_t r = 0; r < hierarchy.root_count(); ++r) {
    hierarchy.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      if (s != NodeState::Full) return;
      const NodeGeometry g = hierarchy.geometry(n);
      LeafEmbedding e;
      e.root = n.root;
      e.depth = n.depth;
      e.flipped = g.flipped;
      for (std::size_t k = 0; k < 4; ++k)
        for (std::size_t i = 0; i < 4; ++i) e.barycentric[k][i] = static_cast<double>(g.vertex[k][i]) / kBaryScale;
      out.push_back(e);
    });
  }
  return out;
}

Vec3 embedded_position(const TetHierarchy& hierarchy, std::size_t r, const std::array<double, 4>& lambda) noexcept {
  const Tet& t = hierarchy.root_tet(r);
  Vec3 p = Vec3::Zero();
  for (std::size_t i = 0; i < 4; ++i) p += lambda[i] * hierarchy.vertices()[static_cast<std::size_t>(t[i])];
  return p;
}

namespace {
struct KeyHash {
  std::size_t operator()(const PointKey& k) const noexcept {
    std::uint64_t h = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      std::uint64_t x = h ^ ((static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.id[i])) << 32) |
                             static_cast<std::uint32_t>(k.weight[i]));
      x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
      x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
      h = x ^ (x >> 31);
    }
    return static_cast<std::size_t>(h);
  }
};
}  // namespace

geometry::TetMesh full_leaf_mesh(const TetHierarchy& hierarchy) {
  geometry::TetMesh mesh;
  // The leaves are counted first, so that the tetrahedra and their fields are allocated once
  // at their size (grown by doubling, each was held twice while it was copied).
  std::size_t leaves = 0;
  for (std::size_t r = 0; r < hierarchy.root_count(); ++r)
    hierarchy.for_each_leaf(r, [&](const NodeRef&, NodeState s) { leaves += s == NodeState::Full ? 1U : 0U; });
  mesh.tets.reserve(leaves);
  auto& depth = mesh.cell_fields["depth"];
  auto& density = mesh.cell_fields["density"];
  auto& root = mesh.cell_fields["root"];
  for (auto* f : {&depth, &density, &root}) f->values.reserve(leaves);
  // Vertices are welded by their exact keys, numbered in order of first use. A point strictly
  // inside root r (four non-zero weights) is a vertex of r's leaves only, so it is looked up
  // in a map of r's points that is emptied after r; points on the roots' faces, edges and
  // corners in a map kept to the end. The numbering is that of a single map.
  std::unordered_map<PointKey, std::int32_t, KeyHash> shared, inner;
  for (std::size_t r = 0; r < hierarchy.root_count(); ++r) {
    inner.clear();
    hierarchy.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      if (s != NodeState::Full) return;
      const NodeGeometry g = hierarchy.geometry(n);
      Tet t{};
      for (std::size_t k = 0; k < 4; ++k) {
        const PointKey key = point_key(hierarchy, r, g.vertex[k]);
        auto& index = key.id[3] >= 0 ? inner : shared;
        const auto [it, inserted] = index.try_emplace(key, static_cast<std::int32_t>(mesh.vertices.size()));
        if (inserted) mesh.vertices.push_back(point_position(key, hierarchy.vertices()));
        t[k] = it->second;
      }
      if (g.flipped) std::swap(t[2], t[3]);
      mesh.tets.push_back(t);
      depth.values.push_back(n.depth);
      density.values.push_back(hierarchy.density(r));
      root.values.push_back(static_cast<double>(r));
    });
  }
  return mesh;
}

float density_from_hu(double hu) noexcept {
  const double d = (hu + 1000.0) / 1000.0;
  return static_cast<float>(std::clamp(std::isfinite(d) ? d : 1.0, 0.05, 4.0));
}

void assign_density_from_ct(TetHierarchy& hierarchy, const image::Volume<float>& ct) {
  for (std::size_t r = 0; r < hierarchy.root_count(); ++r) {
    const Tet& t = hierarchy.root_tet(r);
    Vec3 c = Vec3::Zero();
    for (auto v : t) c += hierarchy.vertices()[static_cast<std::size_t>(v)];
    hierarchy.set_density(r, density_from_hu(ct.sample(0.25 * c)));
  }
}

}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/embedding.h"

#include <algorithm>
#include <cmath>

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

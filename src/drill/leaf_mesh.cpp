// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/leaf_mesh.h"

#include <array>
#include <utility>

#include "ido/drill/tree_table.h"
#include "point_index.h"

namespace ido::drill {

struct LeafMeshWalk::Maps {
  detail::PointMap shared;  // points on the roots' faces, edges and corners
  detail::PointMap inner;   // one root's inner points (emptied per root; reused by every walk)
  // Per full leaf in mesh order, bit k: corner k (in the leaf's geometry order) is a vertex's
  // first use. Lets for_each_vertex() run without looking a point up.
  detail::BlockArray<std::uint8_t, 16> first_use;
};

namespace {

// Calls f(leaf, geometry) for every full leaf of root r, in for_each_leaf's order, deriving
// each child's geometry from its parent's as TetHierarchy::geometry() does along the path
// (the same integer midpoints and parity), instead of from the root for every leaf.
template <class F>
void for_each_full_leaf(const TetHierarchy& h, std::size_t r, F&& f) {
  const TreeTable& table = TreeTable::get();
  struct Item {
    NodeRef node;
    std::uint32_t word;
    NodeGeometry g;
  };
  std::array<Item, 8 * (kMaxDepth + 1)> stack{};
  int top = 0;
  Item& root = stack[0];
  root.node = NodeRef{static_cast<std::uint32_t>(r), 0, 0};
  root.word = h.root_word(r);
  for (std::size_t i = 0; i < 4; ++i) {
    root.g.vertex[i] = {0, 0, 0, 0};
    root.g.vertex[i][i] = kBaryScale;
  }
  root.g.flipped = false;
  ++top;
  while (top > 0) {
    const Item it = stack[static_cast<std::size_t>(--top)];
    const NodeState state = TetHierarchy::state_of_word(it.word);
    if (state == NodeState::Full) {
      f(it.node, it.g);
    } else if (state == NodeState::Internal) {
      const auto words = h.child_words(it.word);
      for (int s = 7; s >= 0; --s) {
        const auto su = static_cast<std::size_t>(s);
        if (TetHierarchy::state_of_word(words[su]) == NodeState::Erased) continue;
        Item& c = stack[static_cast<std::size_t>(top++)];
        c.node = it.node.child(s);
        c.word = words[su];
        for (std::size_t k = 0; k < 4; ++k) {
          const auto& a = it.g.vertex[table.vertex[su][k][0]];
          const auto& b = it.g.vertex[table.vertex[su][k][1]];
          for (std::size_t j = 0; j < 4; ++j) c.g.vertex[k][j] = (a[j] + b[j]) / 2;
        }
        c.g.flipped = it.g.flipped != (table.parity[su] != 0);
      }
    }
  }
}

}  // namespace

// Vertices are numbered in order of first use. A point strictly inside root r (four non-zero
// weights) is a vertex of r's leaves only: it is numbered in a map of r's points emptied after
// r. Points on the roots' faces, edges and corners are in the shared map, which the
// constructor's walk fills and later walks only read: there a shared point is new when its
// number is the next one (numbers are handed out in order of first use, whichever map holds
// them).
template <class OnNew, class OnTet>
void LeafMeshWalk::walk(bool fill, OnNew&& on_new, OnTet&& on_tet) const {
  auto& inner = m_maps->inner;
  auto& shared = m_maps->shared;
  std::int32_t next = 0;
  for (std::size_t r = 0; r < m_hierarchy.root_count(); ++r) {
    inner.clear();
    for_each_full_leaf(m_hierarchy, r, [&](const NodeRef& n, const NodeGeometry& g) {
      Tet t{};
      std::uint8_t first = 0;
      for (std::size_t k = 0; k < 4; ++k) {
        const PointKey key = point_key(m_hierarchy, r, g.vertex[k]);
        std::int32_t index = 0;
        if (key.id[3] >= 0) index = inner.try_emplace(key, next);
        else if (fill) index = shared.try_emplace(key, next);
        else index = shared.find(key);
        if (index == next) {
          on_new(key);
          first |= static_cast<std::uint8_t>(1U << k);
          ++next;
        }
        t[k] = index;
      }
      if (g.flipped) std::swap(t[2], t[3]);
      on_tet(t, n, first);
    });
  }
  inner.clear();
}

LeafMeshWalk::LeafMeshWalk(const TetHierarchy& hierarchy) : m_hierarchy(hierarchy), m_maps(std::make_unique<Maps>()) {
  walk(
      true, [this](const PointKey&) { ++m_vertices; },
      [this](const Tet&, const NodeRef&, std::uint8_t first) {
        m_maps->first_use.push_back(first);
        ++m_tets;
      });
}

LeafMeshWalk::~LeafMeshWalk() = default;

void LeafMeshWalk::for_each_leaf(const std::function<void(const NodeRef&)>& f) const {
  for (std::size_t r = 0; r < m_hierarchy.root_count(); ++r)
    m_hierarchy.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      if (s == NodeState::Full) f(n);
    });
}

void LeafMeshWalk::for_each_vertex(const std::function<void(const Vec3&)>& f) const {
  // The first uses recorded by the constructor's walk give the vertices in index order.
  std::size_t leaf = 0;
  for (std::size_t r = 0; r < m_hierarchy.root_count(); ++r)
    for_each_full_leaf(m_hierarchy, r, [&](const NodeRef&, const NodeGeometry& g) {
      const std::uint8_t first = m_maps->first_use[leaf++];
      for (std::size_t k = 0; k < 4; ++k)
        if ((first >> k) & 1U) f(point_position(point_key(m_hierarchy, r, g.vertex[k]), m_hierarchy.vertices()));
    });
}

void LeafMeshWalk::for_each_tet(const std::function<void(const Tet&)>& f) const {
  walk(
      false, [](const PointKey&) {}, [&](const Tet& t, const NodeRef&, std::uint8_t) { f(t); });
}

std::size_t LeafMeshWalk::memory_bytes() const noexcept {
  return m_maps->shared.memory_bytes() + m_maps->inner.memory_bytes() + m_maps->first_use.memory_bytes();
}

geometry::TetMesh full_leaf_mesh(const TetHierarchy& hierarchy) {
  const LeafMeshWalk walk(hierarchy);
  geometry::TetMesh mesh;
  mesh.vertices.reserve(walk.vertex_count());
  mesh.tets.reserve(walk.tet_count());
  walk.for_each_vertex([&](const Vec3& p) { mesh.vertices.push_back(p); });
  walk.for_each_tet([&](const Tet& t) { mesh.tets.push_back(t); });
  auto& depth = mesh.cell_fields["depth"];
  auto& density = mesh.cell_fields["density"];
  auto& root = mesh.cell_fields["root"];
  for (auto* f : {&depth, &density, &root}) f->values.reserve(walk.tet_count());
  walk.for_each_leaf([&](const NodeRef& n) {
    depth.values.push_back(n.depth);
    density.values.push_back(hierarchy.density(n.root));
    root.values.push_back(static_cast<double>(n.root));
  });
  return mesh;
}

}  // namespace ido::drill

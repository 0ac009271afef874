// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <functional>
#include <memory>

#include "ido/core/math.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/tet_mesh.h"

namespace ido::drill {

/// The remaining material as a tetrahedral mesh (mm), walked from the hierarchy instead of
/// stored, so that a writer can stream it: one positively oriented tetrahedron per full leaf,
/// in depth-first order root by root, vertices welded by their exact keys and numbered in
/// order of first use. full_leaf_mesh() is this mesh held whole.
///
/// What it keeps: the numbers of the points on the roots' faces, edges and corners (shared by
/// roots), and 1 byte per leaf saying which of its corners are first uses of a vertex (so the
/// vertices are listed without looking points up). A point strictly inside a root belongs to
/// that root's leaves only, so a walk that numbers them does it in a map of one root at a time.
/// Every walk derives the leaves' geometry again, parent to child.
/// The hierarchy must not change while the walk exists; walks of one LeafMeshWalk share its
/// maps, so they are not run concurrently.
class LeafMeshWalk {
 public:
  /// Counts the full leaves and their welded vertices (one walk of the hierarchy).
  explicit LeafMeshWalk(const TetHierarchy& hierarchy);
  ~LeafMeshWalk();
  LeafMeshWalk(const LeafMeshWalk&) = delete;
  LeafMeshWalk& operator=(const LeafMeshWalk&) = delete;

  /// Tetrahedra (full leaves).
  [[nodiscard]] std::size_t tet_count() const noexcept { return m_tets; }
  /// Welded vertices.
  [[nodiscard]] std::size_t vertex_count() const noexcept { return m_vertices; }
  /// Calls @p f(leaf) for every full leaf, in mesh order (no vertex numbering: cheap).
  void for_each_leaf(const std::function<void(const NodeRef&)>& f) const;
  /// Calls @p f(position_mm) for every vertex, in index order.
  void for_each_vertex(const std::function<void(const Vec3&)>& f) const;
  /// Calls @p f(tet) with every tetrahedron's vertex indices, in mesh order.
  void for_each_tet(const std::function<void(const Tet&)>& f) const;
  /// Bytes the walk holds: the map of shared points and the (reused) map of one root's inner
  /// points, in flat tables of 36-byte slots, and the first-use byte per leaf.
  [[nodiscard]] std::size_t memory_bytes() const noexcept;

 private:
  struct Maps;
  // The numbering walk: on_new(key) at each vertex's first use, on_tet(tet, leaf, first) per
  // leaf (bit k of first: corner k, in the leaf's geometry order, is a first use).
  // With @p fill it fills the map of shared points (the constructor's walk); later walks only
  // read it.
  template <class OnNew, class OnTet>
  void walk(bool fill, OnNew&& on_new, OnTet&& on_tet) const;

  const TetHierarchy& m_hierarchy;
  std::unique_ptr<Maps> m_maps;  // points on root faces, edges, corners → index; one root's inner points
  std::size_t m_tets = 0;
  std::size_t m_vertices = 0;
};

/// The remaining material as a tetrahedral mesh (mm), held whole: LeafMeshWalk's mesh, with
/// cell fields "depth", "density" (relative) and "root".
[[nodiscard]] geometry::TetMesh full_leaf_mesh(const TetHierarchy& hierarchy);

}  // namespace ido::drill

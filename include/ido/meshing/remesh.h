// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::meshing {

/// Tunables of isotropic surface remeshing (Botsch & Kobbelt, "A remeshing approach to
/// multiresolution modeling", SGP 2004): edges longer than split_ratio · target are split,
/// shorter than collapse_ratio · target are collapsed, edges are flipped towards valence 6.
struct RemeshOptions {
  double target_edge_mm = 1.0;        ///< wanted edge length (mm), > 0
  double split_ratio = 4.0 / 3.0;     ///< split edges longer than this × target
  double collapse_ratio = 4.0 / 5.0;  ///< collapse edges shorter than this × target
  int iterations = 3;                 ///< split / collapse / flip / relax rounds
  bool flip = true;                   ///< flip edges to even valences
  bool relax = true;                  ///< tangential relaxation after each round
  double relax_weight = 0.5;          ///< fraction of the step to the neighbours' centroid
};

/// Counts of the local operations one call performed.
struct RemeshStats {
  std::int64_t splits = 0;
  std::int64_t collapses = 0;
  std::int64_t flips = 0;
};

namespace detail {
/// Vertex → triangle incidence lists for the remesher, in one flat array of fixed slots: a
/// list of up to kInline entries (valences on a remeshed surface are 4–8, on a marching-cubes
/// level rarely above 12) lives in its slot, a longer one in a block of its own. Building the
/// lists of a 20k-vertex surface then costs no allocation per vertex, and a vertex's list
/// shares its cache line with nothing else. A list behaves as a std::vector with removal by
/// swapping in the last entry: the entries' order after any sequence of operations is the
/// one a vector would have. Written by hand (no packaged small-vector fits a flat array).
class IncidenceLists {
 public:
  static constexpr int kInline = 14;
  /// @p n empty lists.
  void assign(std::size_t n) {
    m_slots.assign(n, Slot{});
    m_spill.clear();
  }
  /// Appends an empty list.
  void add_list() { m_slots.emplace_back(); }
  [[nodiscard]] std::size_t lists() const { return m_slots.size(); }
  /// The entries of list @p v; valid until the list is next changed.
  [[nodiscard]] std::span<const std::int32_t> operator[](std::size_t v) const {
    const Slot& s = m_slots[v];
    return {s.spill < 0 ? s.item : m_spill[std::size_t(s.spill)].data(), std::size_t(s.size)};
  }
  void push_back(std::size_t v, std::int32_t t) {
    Slot& s = m_slots[v];
    if (s.spill < 0 && s.size < kInline) {
      s.item[s.size++] = t;
      return;
    }
    if (s.spill < 0) {
      s.spill = static_cast<std::int32_t>(m_spill.size());
      m_spill.emplace_back(s.item, s.item + s.size);
    }
    auto& block = m_spill[std::size_t(s.spill)];
    block.push_back(t);
    s.size = static_cast<std::int32_t>(block.size());
  }
  /// Removes the first entry equal to @p t (if any) by moving the last entry into its place.
  void remove(std::size_t v, std::int32_t t) {
    Slot& s = m_slots[v];
    std::int32_t* d = s.spill < 0 ? s.item : m_spill[std::size_t(s.spill)].data();
    for (std::int32_t k = 0; k < s.size; ++k)
      if (d[k] == t) {
        d[k] = d[s.size - 1];
        --s.size;
        if (s.spill >= 0) m_spill[std::size_t(s.spill)].pop_back();
        return;
      }
  }
  void clear(std::size_t v) {
    Slot& s = m_slots[v];
    s.size = 0;
    if (s.spill >= 0) m_spill[std::size_t(s.spill)].clear();
  }

 private:
  struct alignas(64) Slot {
    std::int32_t size = 0;
    std::int32_t spill = -1;  // index into m_spill once the list outgrew its slot
    std::int32_t item[kInline];
  };
  std::vector<Slot> m_slots;
  std::vector<std::vector<std::int32_t>> m_spill;
};
}  // namespace detail

/// A stateful remesher for repeated use on a closed, oriented, 2-manifold triangle mesh
/// (the balloon calls it every few steps). Every operation keeps the mesh closed, edge- and
/// vertex-manifold and consistently oriented: a split replaces the two triangles of an edge
/// by four; a collapse is done only when the link condition holds (the endpoints share
/// exactly the two opposite vertices) and no incident triangle turns over; a flip only when
/// the new edge does not exist yet and the two new triangles face the old way. Each vertex
/// carries a `locked` flag: locked vertices never move and are never collapsed away (the
/// balloon locks frozen vertices); a vertex created by splitting an edge is locked when both
/// ends are. Written by hand (the operations are the project's own).
class SurfaceRemesher {
 public:
  /// Takes a closed 2-manifold oriented mesh. @p locked is empty or one flag per vertex.
  /// @throws ido::InvalidInput if an edge has other than two triangles, an index is out of
  /// range, a triangle is degenerate in its indices, or locked has the wrong size.
  explicit SurfaceRemesher(const geometry::TriangleMesh& mesh, std::vector<std::uint8_t> locked = {});

  /// Splits every edge longer than @p max_length_mm at its midpoint, longest first (edges
  /// created by a split are considered again in the same call). Returns the split count.
  std::int64_t split_long_edges(double max_length_mm);
  /// Collapses edges shorter than @p min_length_mm to their midpoint (or onto a locked
  /// end), shortest first, refusing collapses that would create an edge longer than
  /// @p max_length_mm. Returns the collapse count.
  std::int64_t collapse_short_edges(double min_length_mm, double max_length_mm);
  /// Flips edges when that brings the four vertices' valences closer to 6. Returns the count.
  std::int64_t flip_edges();
  /// Moves every unlocked vertex by @p weight towards the centroid of its neighbours,
  /// within its tangent plane (area-uniform relaxation).
  void relax_tangentially(double weight);
  /// Restricts the following split, collapse and flip calls to edges with at least one
  /// active end (one flag per vertex, in the numbering of the input mesh; empty = every edge),
  /// and relaxation to active vertices. Vertices created by a split, and the vertex a collapse
  /// keeps, are active. For a caller that knows which part of the surface moved since the
  /// last remesh (the balloon's sleeping vertices): edges between two vertices that did not
  /// move keep the length they had then. One exception keeps a split pass finite: an edge
  /// between two inactive vertices that is longer than the split bound is split when a split
  /// next to it (one of its triangles) meets it; left whole, each split near it would leave
  /// an edge from its far corner about as long as itself, without end.
  /// @throws ido::InvalidInput on a wrong size.
  void set_active(std::vector<std::uint8_t> active);
  /// Runs the full schedule of @p options.
  RemeshStats remesh(const RemeshOptions& options);

  /// Current mesh, renumbered without deleted vertices and triangles.
  [[nodiscard]] geometry::TriangleMesh mesh() const;
  /// For each vertex of mesh(): the index it had in the input mesh when it is an input vertex
  /// at its input position (bit for bit), else −1 (created by a split, or moved by a collapse
  /// or relaxation). Lets a caller carry per-vertex state through a remesh.
  [[nodiscard]] std::vector<std::int32_t> input_index() const;
  /// For each vertex of mesh(): 1 when a split, collapse or flip changed one of its triangles
  /// (the ends and opposite corners of the edge, the new vertex of a split) or it moved; every
  /// triangle of mesh() that was not in the input has such a corner.
  [[nodiscard]] std::vector<std::uint8_t> touched() const;
  /// Locked flags in the numbering of mesh().
  [[nodiscard]] std::vector<std::uint8_t> locked() const;

 private:
  struct Impl;
  std::vector<Vec3> m_vertices;
  std::vector<Tri> m_triangles;
  std::vector<std::uint8_t> m_vertex_alive;
  std::vector<std::uint8_t> m_triangle_alive;
  std::vector<std::uint8_t> m_locked;
  std::vector<std::uint8_t> m_active;  // empty = every vertex (see set_active)
  std::vector<std::uint8_t> m_moved;   // 1 = no longer at its input position (see input_index)
  std::vector<std::uint8_t> m_touched;  // see touched()
  std::size_t m_input_vertices = 0;
  detail::IncidenceLists m_vertex_triangles;
  std::int64_t m_alive_vertices = 0;
};

/// One-call isotropic remeshing: returns a closed 2-manifold mesh with edges near
/// options.target_edge_mm. @throws ido::InvalidInput as SurfaceRemesher.
[[nodiscard]] geometry::TriangleMesh remesh(const geometry::TriangleMesh& mesh,
                                            const RemeshOptions& options = {});

}  // namespace ido::meshing

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <compare>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::drill {

/// Exact global identity of a point of the hierarchy: up to 4 (mesh vertex, weight) pairs
/// sorted by vertex, weights scaled by kBaryScale (summing to it), unused slots id = −1 at
/// the end. A point on a face shared by two roots has the same key from both sides.
struct PointKey {
  std::array<std::int32_t, 4> id{-1, -1, -1, -1};
  std::array<std::int32_t, 4> weight{0, 0, 0, 0};
  friend bool operator==(const PointKey&, const PointKey&) = default;
};

/// Global key of a root barycentric key of root @p r.
[[nodiscard]] PointKey point_key(const TetHierarchy& hierarchy, std::size_t r, const BaryKey& key) noexcept;
/// World position (mm) of a point key on the mesh vertices @p vertices_mm.
[[nodiscard]] Vec3 point_position(const PointKey& key, std::span<const Vec3> vertices_mm) noexcept;

/// A visible face, counter-clockwise seen from outside the material: the point keys of its
/// three corners in 32 bytes (three PointKeys take 96). It holds the mesh vertex ids of its
/// root in increasing order and, per corner, the weights on them (root barycentric keys in
/// that order); 12 bits each, the fourth being kBaryScale less the other three, as in every
/// BaryKey. A face is stored once per v_list entry, so this is most of a session's memory.
class SurfaceFace {
 public:
  SurfaceFace() = default;
  /// The face with corners @p corner (root barycentric keys whose entries are weights on
  /// @p vertex_ids, each summing to kBaryScale) on the root's mesh vertex ids @p vertex_ids
  /// (increasing).
  SurfaceFace(const std::array<std::int32_t, 4>& vertex_ids, const std::array<BaryKey, 3>& corner) noexcept;
  /// Global key of corner @p c (0–2): the (vertex, weight) pairs of non-zero weight, as
  /// point_key() gives for the same point.
  [[nodiscard]] PointKey key(std::size_t c) const noexcept;
  friend bool operator==(const SurfaceFace&, const SurfaceFace&) = default;

 private:
  std::array<std::int32_t, 4> m_vertex{-1, -1, -1, -1};
  // Weights 0–2 of corners 0–2 (9 values of 12 bits): value i of corner c is entry 3c + i,
  // entries 0–4 in m_weight[0], 5–8 in m_weight[1], 12 bits apart.
  std::array<std::uint64_t, 2> m_weight{0, 0};
};
static_assert(sizeof(SurfaceFace) == 32, "a v_list face record is 32 bytes");

/// Options of BoundarySurface.
struct BoundarySurfaceOptions {
  /// Level of the sub-trees ("chunks") whose face lists are kept and rebuilt separately:
  /// a refined root holds 8^chunk_level lists in depth-first order, and an update rebuilds
  /// only the chunks holding a changed node or lying across one of its faces. 0 = whole
  /// roots. Range 0–4; default 3.
  int chunk_level = 3;
  /// Worker threads of an update's chunk rebuilds (oneTBB): 0 = the task arena's
  /// concurrency, 1 = the calling thread only. The chunks are independent (each reads the
  /// tree and writes its own list), so the lists equal a serial rebuild's; only which
  /// chunks a budgeted update leaves for the next one can differ. Default 0.
  int threads = 0;
};

/// Names one chunk's face list: root and chunk index (depth-first order of the sub-trees at
/// BoundarySurfaceOptions::chunk_level; 0 for a root kept whole).
struct ChunkId {
  std::uint32_t root = 0;
  std::uint32_t chunk = 0;
  friend bool operator==(const ChunkId&, const ChunkId&) = default;
  friend auto operator<=>(const ChunkId&, const ChunkId&) = default;
};

/// The boundary surface of the remaining material (the paper's per-root v_list): for each
/// root, the faces of its full leaves that border erased material or the outside of the
/// mesh. Where the leaf across a face is refined deeper, the face is split (recursively,
/// following the neighbour's red refinement) and only the parts bordering erased material
/// are kept, so the surface has no cracks. assemble_surface() then splits edges at the
/// vertices of finer neighbours, so it has no T-junctions either.
///
/// Storage: a root that was never refined keeps one list; a refined root keeps one list per
/// chunk (sub-tree at chunk_level; the faces of a leaf shallower than that go to the first
/// chunk it covers). Concatenated in chunk order they are exactly the v_list of a full
/// depth-first walk. v_list() and v_lists() concatenate on request (cached until the next
/// update), so they cost O(faces) after a change; the chunk accessors cost nothing.
class BoundarySurface {
 public:
  /// Builds every root's v_list. @throws ido::InvalidInput for chunk_level outside 0–4.
  explicit BoundarySurface(const TetHierarchy& hierarchy, const BoundarySurfaceOptions& options = {});
  ~BoundarySurface();
  BoundarySurface(BoundarySurface&&) noexcept;
  BoundarySurface& operator=(BoundarySurface&&) noexcept;

  /// Rebuilds the v_lists of @p changed_roots and of their face neighbours (a change can
  /// expose a neighbour's face); the rebuilt roots are then in last_rebuilt().
  void update(const TetHierarchy& hierarchy, std::span<const std::uint32_t> changed_roots);
  /// As above, but the neighbour across root face f of changed_roots[i] is rebuilt only
  /// when bit f of @p changed_faces[i] is set (Eroder::changed_root_faces(): a changed node
  /// had a face on that root face), so untouched neighbours are not rebuilt.
  void update(const TetHierarchy& hierarchy, std::span<const std::uint32_t> changed_roots,
              std::span<const std::uint8_t> changed_faces);
  /// Rebuilds only the chunks affected by the nodes in @p changed_nodes (Eroder::changed_nodes):
  /// each node's chunk(s) and the chunks across its faces (in this or a neighbouring root).
  /// The result equals a full rebuild. last_rebuilt() lists the roots touched and
  /// last_rebuilt_chunks() the chunk lists rewritten.
  void update(const TetHierarchy& hierarchy, std::span<const NodeRef> changed_nodes);
  /// As above, but stops once @p max_node_visits nodes were walked (after the chunk in
  /// progress; 0 = unlimited): the chunks not rebuilt yet stay queued for the next update or
  /// flush(), so until then the v_lists lag the tree.
  void update(const TetHierarchy& hierarchy, std::span<const NodeRef> changed_nodes, std::size_t max_node_visits);
  /// True when chunks wait to be rebuilt (a budgeted update stopped early).
  [[nodiscard]] bool has_pending() const noexcept { return !m_dirty.empty(); }
  /// Rebuilds every waiting chunk.
  void flush(const TetHierarchy& hierarchy) { update(hierarchy, std::span<const NodeRef>{}, 0); }
  /// Rebuilds every v_list.
  void rebuild_all(const TetHierarchy& hierarchy);

  [[nodiscard]] std::size_t root_count() const noexcept { return m_chunks.size(); }
  /// The v_list of root @p r (its chunk lists concatenated; valid until the next update).
  [[nodiscard]] const std::vector<SurfaceFace>& v_list(std::size_t r) const;
  /// Every root's v_list (valid until the next update).
  [[nodiscard]] const std::vector<std::vector<SurfaceFace>>& v_lists() const;
  /// Moves every root's v_list out, freeing each root's chunk lists as its list is made (so
  /// the faces are never held twice; a list handed out by shared_chunk() is freed by its last
  /// holder). Afterwards every v_list is empty and the surface no longer matches the tree:
  /// rebuild_all() before using it again.
  [[nodiscard]] std::vector<std::vector<SurfaceFace>> take_v_lists();
  [[nodiscard]] const std::vector<std::uint32_t>& last_rebuilt() const noexcept { return m_rebuilt; }
  /// Chunk lists rewritten by the last update (sorted, each once).
  [[nodiscard]] const std::vector<ChunkId>& last_rebuilt_chunks() const noexcept { return m_rebuilt_chunks; }
  /// Chunk lists of root @p r: 1 (a root never refined) or 8^chunk_level.
  [[nodiscard]] std::size_t chunk_count(std::size_t r) const noexcept { return m_chunks[r].size(); }
  /// Faces of chunk @p c of root @p r.
  [[nodiscard]] const std::vector<SurfaceFace>& chunk(std::size_t r, std::size_t c) const noexcept {
    return m_chunks[r][c] ? *m_chunks[r][c] : kNoFaces;
  }
  /// The same list, shared: a rebuild never changes a list it has handed out, it replaces it
  /// with a new one, so a consumer (the simulator's render thread) can keep this one while
  /// the surface moves on, without copying it. Null for an empty list.
  [[nodiscard]] std::shared_ptr<const std::vector<SurfaceFace>> shared_chunk(std::size_t r, std::size_t c) const noexcept {
    return m_chunks[r][c];
  }
  /// Node visits of the last update or rebuild (work done).
  [[nodiscard]] std::size_t last_visits() const noexcept { return m_visits; }
  /// Faces over all v_lists.
  [[nodiscard]] std::size_t face_count() const noexcept;
  /// Bytes held by the face lists: the chunk lists and the concatenated v_lists cached by
  /// v_list() / v_lists() (capacities, so what is allocated).
  [[nodiscard]] std::size_t memory_bytes() const noexcept;
  [[nodiscard]] const BoundarySurfaceOptions& options() const noexcept { return m_options; }

 private:
  struct Range {
    std::uint32_t root = 0;
    std::uint32_t lo = 0, hi = 0;  // chunk indices at the full chunk level
  };
  struct Budget;
  void rebuild_ranges(const TetHierarchy& hierarchy, std::size_t max_node_visits = 0);
  std::uint32_t rebuild_range(const TetHierarchy& hierarchy, std::uint32_t r, std::uint32_t lo, std::uint32_t hi,
                              Budget& budget, std::vector<ChunkId>& rebuilt);
  void mark_node(const TetHierarchy& hierarchy, const NodeRef& node);
  void mark_faces(const TetHierarchy& hierarchy);
  void mark_root(std::uint32_t r);

  using ChunkList = std::shared_ptr<const std::vector<SurfaceFace>>;
  static inline const std::vector<SurfaceFace> kNoFaces{};

  BoundarySurfaceOptions m_options;
  std::uint32_t m_full_chunks = 1;  // 8^chunk_level
  // Per root, its chunk lists (null when empty). Shared with the render consumer, which keeps
  // the lists it was given (shared_chunk) until newer ones replace them: immutable once made.
  std::vector<std::vector<ChunkList>> m_chunks;
  mutable std::vector<std::vector<SurfaceFace>> m_flat;
  mutable std::vector<std::uint8_t> m_flat_stale;
  mutable std::vector<std::uint32_t> m_stale_roots;
  std::vector<std::uint32_t> m_rebuilt;
  std::vector<ChunkId> m_rebuilt_chunks;
  std::vector<Range> m_dirty;
  struct FaceMark {
    NodeRef node;
    std::uint8_t faces = 0;
  };
  std::vector<FaceMark> m_face_marks;
  std::vector<std::uint8_t> m_mark;
  std::vector<Range> m_pieces;                     // this update's rebuild units of work
  std::vector<std::uint32_t> m_groups;              // pieces [m_groups[g], m_groups[g + 1]) form group g
  std::vector<std::uint32_t> m_stop;                // per piece: first chunk not rebuilt
  std::vector<std::vector<ChunkId>> m_worker_chunks;  // per worker: chunk lists it rewrote
  std::size_t m_visits = 0;
};

/// The welded, crack-free triangle mesh (mm) of the faces in @p v_lists on mesh vertices
/// @p vertices_mm: a face edge holding vertices of finer faces is split at them and the
/// face is fanned from its centroid. Cell field "root" gives each triangle's root.
/// The result is a closed 2-manifold (edge- and vertex-manifold), outward-oriented: where
/// two parts of the material touch along an edge or at a point only, the edge's or the
/// point's vertices are duplicated, one copy per part (same position, so the enclosed
/// volume is unchanged; a format that welds by position, such as STL, joins them again).
[[nodiscard]] geometry::TriangleMesh assemble_surface(std::span<const std::vector<SurfaceFace>> v_lists,
                                                      std::span<const Vec3> vertices_mm);
/// The same, taking the v_lists over and freeing each root's faces once they are made into
/// triangles (for large surfaces: the faces are not held during the split).
[[nodiscard]] geometry::TriangleMesh assemble_surface(std::vector<std::vector<SurfaceFace>>&& v_lists,
                                                      std::span<const Vec3> vertices_mm);

}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/tree_table.h"
#include "ido/geometry/spatial_hash.h"
#include "ido/geometry/tet_mesh.h"

namespace ido::drill {

/// Deepest refinement level a node can reach (the path of a node is 3 bits per level).
inline constexpr int kMaxDepth = 10;
/// Node vertices are stored as root barycentric coordinates scaled by this power of two,
/// so every vertex at depth ≤ kMaxDepth (and every edge midpoint of a leaf) is an exact
/// integer.
inline constexpr std::int32_t kBaryScale = 1 << 11;

/// A point given by integer barycentric coordinates in its root tetrahedron, scaled by
/// kBaryScale (the four entries sum to kBaryScale).
using BaryKey = std::array<std::int32_t, 4>;

/// State of a node of the hierarchy.
enum class NodeState : std::uint8_t {
  Full,      ///< a leaf holding material
  Erased,    ///< a leaf whose material is gone
  Internal,  ///< refined: its 8 children hold the state
};

/// Names a node: its root, its depth and the child slots taken from the root (3 bits per
/// level, level 1 in the lowest bits). Geometry is derived from it, never stored.
struct NodeRef {
  std::uint32_t root = 0;
  std::uint32_t path = 0;
  std::uint8_t depth = 0;

  /// Child slot taken at level @p level (1 ≤ level ≤ depth).
  [[nodiscard]] int slot(int level) const noexcept { return static_cast<int>((path >> (3 * (level - 1))) & 7U); }
  /// The child in slot @p s.
  [[nodiscard]] NodeRef child(int s) const noexcept {
    return {root, path | (static_cast<std::uint32_t>(s) << (3 * depth)), static_cast<std::uint8_t>(depth + 1)};
  }
  /// The parent (precondition: depth > 0).
  [[nodiscard]] NodeRef parent() const noexcept {
    const std::uint32_t keep = depth > 1 ? ((1U << (3 * (depth - 1))) - 1U) : 0U;
    return {root, path & keep, static_cast<std::uint8_t>(depth - 1)};
  }
  friend bool operator==(const NodeRef&, const NodeRef&) = default;
};

/// A node's vertices as root barycentric keys, and whether its orientation is opposite to
/// the root's (product of the TreeTable parity bits along its path).
struct NodeGeometry {
  std::array<BaryKey, 4> vertex{};
  bool flipped = false;
};

/// Where a point lies.
struct Location {
  bool inside_mesh = false;  ///< false: outside every root tetrahedron
  NodeRef leaf;              ///< the leaf holding the point (when inside_mesh)
  NodeState state = NodeState::Erased;
};

/// What lies across a root face.
struct RootFaceNeighbor {
  std::int32_t root = -1;  ///< -1: the face is on the mesh boundary
  std::int32_t face = -1;  ///< the neighbour's face index
};

/// Options of TetHierarchy.
struct HierarchyOptions {
  /// Choose each root's vertex order (among the 12 orientation-preserving ones) to
  /// maximise the worst mean-ratio quality of its descendants (depths 1–2 hold every
  /// congruence class). Off: keep the mesh order.
  bool reorder_roots = true;
  /// Spatial hash cell size (mm); 0 = mean edge length of the mesh.
  double hash_cell_mm = 0.0;
};

/// Adaptive tetrahedral hierarchy for material removal: every tetrahedron of the input mesh
/// is the root of a tree of Bey red refinements (TreeTable). Geometry is never stored: it
/// is computed from the root and the node's path.
///
/// Node storage (what a node's 32-bit storage word means):
/// - kFull / kErased: a full / erased leaf;
/// - a mask word (kMaskBase | m, 8 bits): an internal node whose 8 children are all leaves,
///   bit s of m set when child s is full; it costs 1 byte in its parent's group (nothing
///   when it is a root);
/// - otherwise the id of a child group: an internal node with at least one internal child.
///   The group holds the 8 children's 2-bit codes (erased, full, mask, group; 2 bytes) and,
///   in slot order, 1 byte (the mask) per mask child and 4 bytes (the group id) per group
///   child: 3–34 bytes (4 allocated at least). Groups live in fixed pages of kPageBytes (growing never moves
///   them) with a free list per size; a group is re-allocated at its new size when a child
///   changes kind.
/// Fully erased siblings merge into their parent. A word read by root_word()/child_word()
/// stays valid until the next refine/erase/coarsen (which may move groups and rewrite
/// masks): a caller holding words re-reads them after each change.
///
/// Not thread-safe: one thread (the collision/erosion thread) owns it.
class TetHierarchy {
 public:
  /// Builds the roots from @p mesh (mm). Negatively oriented tetrahedra are reordered
  /// to positive orientation. @throws ido::InvalidInput for an empty mesh, indices out of
  /// range, non-finite vertices or a degenerate tetrahedron (naming it).
  explicit TetHierarchy(const geometry::TetMesh& mesh, const HierarchyOptions& options = {});

  [[nodiscard]] std::size_t root_count() const noexcept { return m_roots.size(); }
  /// Mesh vertex indices of root @p r in the order chosen at load.
  [[nodiscard]] const Tet& root_tet(std::size_t r) const noexcept { return m_roots[r]; }
  /// Mesh vertex positions (mm).
  [[nodiscard]] const std::vector<Vec3>& vertices() const noexcept { return m_vertices; }
  /// Root across face @p f of root @p r.
  [[nodiscard]] RootFaceNeighbor root_neighbor(std::size_t r, int f) const noexcept {
    return m_root_neighbors[r][static_cast<std::size_t>(f)];
  }
  /// Moves the mesh vertices (embedding: every node follows its root's vertices through
  /// its barycentric coordinates). Rebuilds the spatial hash.
  /// @throws ido::InvalidInput if the count differs, a position is non-finite, or a root
  /// becomes degenerate or inverted.
  void set_vertex_positions(std::span<const Vec3> positions_mm);

  /// Relative material density of root @p r (1 = reference bone); sets the erosion cost.
  [[nodiscard]] float density(std::size_t r) const noexcept { return m_density[r]; }
  void set_density(std::size_t r, float relative_density) noexcept { m_density[r] = relative_density; }

  /// State of a node; Erased for a node below an erased or full leaf is not meaningful:
  /// the caller walks from the root (see for_each_leaf).
  [[nodiscard]] NodeState state(const NodeRef& node) const noexcept;
  /// Storage word of root @p r (see the class comment). With child_word() it lets a
  /// top-down walk read states in O(1) per node; valid until the next change of the tree.
  [[nodiscard]] std::uint32_t root_word(std::size_t r) const noexcept { return m_root_word[r]; }
  /// Word of child slot @p s of the node whose word is @p word; a leaf's word for a leaf
  /// (below a leaf every node inherits its state).
  [[nodiscard]] std::uint32_t child_word(std::uint32_t word, int s) const noexcept {
    if (word >= kMaskBase) {
      if (word >= kErased) return word;
      return ((word >> s) & 1U) != 0 ? kFull : kErased;
    }
    const std::uint8_t* g = group(word);
    const unsigned codes = static_cast<unsigned>(g[0]) | (static_cast<unsigned>(g[1]) << 8);
    const unsigned code = (codes >> (2 * s)) & 3U;
    return word_of_code(code, g + payload_offset(codes & ((1U << (2 * s)) - 1U)));
  }
  /// The words of the 8 children of the internal node of word @p word (child_word(word, s)
  /// for s = 0…7), decoded in one pass over its group without a branch per child.
  [[nodiscard]] std::array<std::uint32_t, 8> child_words(std::uint32_t word) const noexcept {
    std::array<std::uint32_t, 8> c{};
    if (word >= kMaskBase) {
      for (unsigned s = 0; s < 8; ++s) c[s] = word >= kErased ? word : ((word >> s) & 1U) != 0 ? kFull : kErased;
      return c;
    }
    const std::uint8_t* g = group(word);
    const unsigned codes = static_cast<unsigned>(g[0]) | (static_cast<unsigned>(g[1]) << 8);
    std::size_t off = 2;
    for (unsigned s = 0; s < 8; ++s) {
      const unsigned code = (codes >> (2 * s)) & 3U;
      c[s] = word_of_code(code, g + off);
      off += ((code >> 1) & 1U) * (1U + 3U * (code & 1U));  // payload bytes: 0, 0, 1, 4
    }
    return c;
  }
  /// The state a storage word stands for.
  [[nodiscard]] static NodeState state_of_word(std::uint32_t word) noexcept {
    return word == kFull ? NodeState::Full : word == kErased ? NodeState::Erased : NodeState::Internal;
  }
  /// Splits a full leaf into 8 full children. Returns false (and does nothing) if the node
  /// is not a full leaf or is at kMaxDepth.
  bool refine(const NodeRef& node);
  /// Removes the node's material: the node becomes an erased leaf, its subtree's storage is
  /// freed, and ancestors whose 8 children are all erased merge into erased leaves. Returns
  /// the topmost node that became an erased leaf (@p node itself when nothing merged, or
  /// when it lies below a leaf and nothing was done).
  NodeRef erase(const NodeRef& node);
  /// As erase(node) for a node below internal ancestors whose storage words the caller
  /// holds (a top-down traversal): @p ancestor_words[d] is the word of the node's ancestor
  /// at depth d, for every d < node.depth (precondition: each is that ancestor's current
  /// word, internal — words read before the last change of the tree are not), so the path
  /// is not walked down from the root. Falls back to erase(node) when a given word is not
  /// internal or the root's word differs.
  NodeRef erase(const NodeRef& node, std::span<const std::uint32_t> ancestor_words);
  /// Undoes a refinement that removed nothing: an internal node whose 8 children are all
  /// full leaves becomes a full leaf again. Returns true if it did.
  bool coarsen(const NodeRef& node);

  /// Storage words of a node's path: [d] is the word of its ancestor at depth d (d < depth)
  /// and [depth] its own, as a top-down traversal holds them.
  using PathWords = std::array<std::uint32_t, kMaxDepth + 1>;
  /// As refine(node), erase(node) and coarsen(node) for a caller that holds the node's path
  /// words in @p w (precondition, not checked: w[d] is the current word for every d ≤
  /// node.depth, each ancestor's internal — a top-down traversal that keeps them up to
  /// date), so nothing is walked down from the root. On return w holds the path's new words
  /// (kErased from the topmost merged node down); the words of the path's other children are
  /// unchanged by any change, so a caller holding them need re-read only w.
  bool refine_on_path(const NodeRef& node, PathWords& w);
  NodeRef erase_on_path(const NodeRef& node, PathWords& w);
  bool coarsen_on_path(const NodeRef& node, PathWords& w);

  /// The node's vertices as root barycentric keys.
  [[nodiscard]] NodeGeometry geometry(const NodeRef& node) const noexcept;
  /// World position (mm) of a root barycentric key in root @p r.
  [[nodiscard]] Vec3 world_position(std::size_t r, const BaryKey& key) const noexcept;
  /// The node's vertex positions (mm), in its TreeTable order.
  [[nodiscard]] std::array<Vec3, 4> world_vertices(const NodeRef& node) const noexcept;
  /// Volume (mm³, positive) of root @p r divided by 8^depth.
  [[nodiscard]] double node_volume(const NodeRef& node) const noexcept {
    return m_root_volume[node.root] / static_cast<double>(1ULL << (3 * node.depth));
  }
  /// Root volume (mm³).
  [[nodiscard]] double root_volume(std::size_t r) const noexcept { return m_root_volume[r]; }
  /// Longest edge of root @p r (mm).
  [[nodiscard]] double root_diameter(std::size_t r) const noexcept { return m_root_diameter[r]; }

  /// Barycentric coordinates of @p p_mm in root @p r.
  [[nodiscard]] std::array<double, 4> root_barycentric(std::size_t r, const Vec3& p_mm) const noexcept;
  /// The leaf holding @p p_mm: spatial hash → root → descent by TreeTable point location.
  /// Allocates nothing.
  [[nodiscard]] Location locate(const Vec3& p_mm) const noexcept;
  /// As locate(p_mm), trying root @p hint_root first (e.g. the root of the previous,
  /// nearby sample; −1: none): when the point lies strictly inside it the hash look-up is
  /// skipped. Same result as locate(p_mm) for points not on a root face.
  [[nodiscard]] Location locate(const Vec3& p_mm, std::int32_t hint_root) const noexcept;
  /// As locate(p_mm), trying the roots in @p hint_roots first, in order (entries < 0 are
  /// skipped): the first that holds the point strictly inside is taken without a hash
  /// look-up. Same result as locate(p_mm) for points not on a root face.
  [[nodiscard]] Location locate(const Vec3& p_mm, std::span<const std::int32_t> hint_roots) const noexcept;

  /// Calls f(NodeRef, NodeState) for every leaf of root @p r (depth-first).
  template <class F>
  void for_each_leaf(std::size_t r, F&& f) const {
    struct Item { NodeRef node; std::uint32_t word; };
    std::array<Item, 8 * (kMaxDepth + 1)> stack{};
    int top = 0;
    stack[0] = {NodeRef{static_cast<std::uint32_t>(r), 0, 0}, m_root_word[r]};
    ++top;
    while (top > 0) {
      const Item it = stack[static_cast<std::size_t>(--top)];
      if (it.word == kFull) {
        f(it.node, NodeState::Full);
      } else if (it.word == kErased) {
        f(it.node, NodeState::Erased);
      } else {
        for (int s = 7; s >= 0; --s) stack[static_cast<std::size_t>(top++)] = {it.node.child(s), child_word(it.word, s)};
      }
    }
  }

  /// Spatial hash of the root tetrahedra.
  [[nodiscard]] const geometry::SpatialHash& root_hash() const noexcept { return m_hash; }
  /// Bounding box of root @p r (mm).
  [[nodiscard]] const geometry::Aabb& root_box(std::size_t r) const noexcept { return m_root_box[r]; }

  /// Live nodes: every root plus 8 per internal node.
  [[nodiscard]] std::size_t node_count() const noexcept { return m_roots.size() + 8 * m_internal; }
  /// Internal nodes (each stands for a block of 8 live children).
  [[nodiscard]] std::size_t internal_nodes() const noexcept { return m_internal; }
  /// Child groups in use (internal nodes with an internal child) and their bytes.
  [[nodiscard]] std::size_t live_groups() const noexcept { return m_live_groups; }
  [[nodiscard]] std::size_t live_group_bytes() const noexcept { return m_live_group_bytes; }
  /// Pages of kPageBytes allocated.
  [[nodiscard]] std::size_t page_count() const noexcept { return m_pages.size(); }
  /// Bytes on the free lists (freed groups and page tails too short for the next group).
  [[nodiscard]] std::size_t free_bytes() const noexcept { return m_free_bytes; }
  /// Bytes of node storage: one word per root plus every page byte handed out — groups in
  /// use, groups on the free lists, page tails too short for any group — and the page
  /// table; not the never-used rest of the last page.
  [[nodiscard]] std::size_t node_storage_bytes() const noexcept {
    return m_root_word.size() * sizeof(std::uint32_t) + page_table_bytes() + handed_out_bytes();
  }
  /// As node_storage_bytes() with the whole of every page allocated, kPagePad included (the
  /// memory reserved).
  [[nodiscard]] std::size_t node_storage_capacity_bytes() const noexcept {
    return m_root_word.size() * sizeof(std::uint32_t) + page_table_bytes() + m_pages.size() * (kPageBytes + kPagePad);
  }
  /// node_storage_bytes() / node_count(): free lists and allocator slack included.
  [[nodiscard]] double bytes_per_node() const noexcept {
    return static_cast<double>(node_storage_bytes()) / static_cast<double>(node_count());
  }
  /// node_storage_capacity_bytes() / node_count(): the last page's unused rest included.
  [[nodiscard]] double storage_bytes_per_node() const noexcept {
    return static_cast<double>(node_storage_capacity_bytes()) / static_cast<double>(node_count());
  }
  /// Sum of the volumes of full leaves (mm³).
  [[nodiscard]] double material_volume() const;
  /// Sum of the root volumes (mm³).
  [[nodiscard]] double total_volume() const noexcept { return m_total_volume; }
  /// Mean edge length of the input mesh (mm).
  [[nodiscard]] double mean_edge_length() const noexcept { return m_mean_edge; }

  static constexpr std::uint32_t kFull = 0xFFFFFFFFU;
  static constexpr std::uint32_t kErased = 0xFFFFFFFEU;
  /// Mask words are kMaskBase | m (m: the 8 children's full bits); group ids are below.
  static constexpr std::uint32_t kMaskBase = 0xFFFFFE00U;
  /// Bytes per page of child groups.
  static constexpr std::uint32_t kPageBytes = 1U << 14;
  /// Bytes allocated beyond each page's kPageBytes, never handed out: a group's decoding reads
  /// 4 bytes at every child's payload offset, which may be the group's end (so bytes
  /// end … end + 3 are read).
  static constexpr std::uint32_t kPagePad = 4;

 private:
  static constexpr unsigned kCodeErased = 0, kCodeFull = 1, kCodeMask = 2, kCodeGroup = 3;
  static constexpr int kPageShift = 14;
  static constexpr std::uint32_t kNone = 0xFFFFFFFFU;  // end of a free list
  // Groups take 3–34 bytes; at least 4 are allocated (a free group holds a 4-byte link).
  static constexpr std::size_t kMinGroup = 4, kMaxGroup = 34;

  // Payload bytes of the children whose 2-bit codes are @p codes (1 per mask, 4 per group)
  // plus the 2 code bytes: the offset of the next child's payload.
  // (Two look-ups in a 256-entry table of the payload bytes of 4 codes: no popcount, which
  // the baseline x86-64 target lacks.)
  [[nodiscard]] static std::size_t payload_offset(unsigned codes) noexcept {
    return 2U + kPayload4[codes & 0xFFU] + kPayload4[(codes >> 8) & 0xFFU];
  }
  static constexpr std::array<std::uint8_t, 256> kPayload4 = [] {
    std::array<std::uint8_t, 256> t{};
    for (unsigned c = 0; c < 256; ++c) {
      unsigned n = 0;
      for (unsigned k = 0; k < 4; ++k) {
        const unsigned code = (c >> (2 * k)) & 3U;
        n += code == kCodeMask ? 1U : code == kCodeGroup ? 4U : 0U;
      }
      t[c] = static_cast<std::uint8_t>(n);
    }
    return t;
  }();
  // The word a child of code @p code stands for, its payload at @p p: the 4 bytes at p are
  // read whatever the code (a page has kPagePad bytes beyond its last group), and the word
  // is selected, not branched on (the codes of a group are not predictable).
  [[nodiscard]] static std::uint32_t word_of_code(unsigned code, const std::uint8_t* p) noexcept {
    const std::uint32_t v = static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
                            (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
    const std::uint32_t leaf = kErased | (code & 1U);  // kCodeErased → kErased, kCodeFull → kFull
    const std::uint32_t inner = code == kCodeMask ? (kMaskBase | (v & 0xFFU)) : v;
    return code < kCodeMask ? leaf : inner;
  }
  [[nodiscard]] const std::uint8_t* group(std::uint32_t id) const noexcept {
    return m_pages[id >> kPageShift].data() + (id & (kPageBytes - 1U));
  }
  [[nodiscard]] std::uint8_t* group(std::uint32_t id) noexcept {
    return m_pages[id >> kPageShift].data() + (id & (kPageBytes - 1U));
  }
  [[nodiscard]] std::size_t handed_out_bytes() const noexcept {
    return m_pages.empty() ? 0 : (m_pages.size() - 1) * kPageBytes + m_page_used;
  }
  [[nodiscard]] std::size_t page_table_bytes() const noexcept {
    return m_pages.capacity() * sizeof(std::vector<std::uint8_t>);
  }
  [[nodiscard]] static bool is_group(std::uint32_t w) noexcept { return w < kMaskBase; }
  [[nodiscard]] std::size_t group_size(std::uint32_t id) const noexcept;  // bytes allocated

  [[nodiscard]] Location descend(std::uint32_t root, const std::array<double, 4>& root_lambda) const noexcept;
  [[nodiscard]] bool outside_root_box(std::size_t r, const Vec3& p_mm) const noexcept;
  bool walk(const NodeRef& node, PathWords& w) const noexcept;
  void set_word(const NodeRef& node, int depth, PathWords& w, std::uint32_t word);
  std::uint32_t encode(const std::array<std::uint32_t, 8>& children);
  void write_group(std::uint8_t* g, const std::array<std::uint32_t, 8>& children) const noexcept;
  NodeRef erase_path(const NodeRef& node, PathWords& w);
  std::uint32_t allocate_group(std::size_t size);
  void free_group(std::uint32_t id);
  void free_subtree(std::uint32_t word);
  void update_root_geometry();

  std::vector<Vec3> m_vertices;
  std::vector<Tet> m_roots;
  std::vector<std::array<RootFaceNeighbor, 4>> m_root_neighbors;
  std::vector<Mat3> m_root_inverse;   // barycentric map: (λ1, λ2, λ3) = M (p − x0)
  std::vector<double> m_root_volume;
  std::vector<double> m_root_diameter;
  std::vector<geometry::Aabb> m_root_box;
  geometry::Aabb m_mesh_box;  // union of the root boxes, grown by kBoxSlack × its diagonal
  std::vector<float> m_density;
  double m_total_volume = 0.0;
  double m_mean_edge = 0.0;
  double m_hash_cell = 0.0;
  geometry::SpatialHash m_hash;

  std::vector<std::uint32_t> m_root_word;
  std::vector<std::vector<std::uint8_t>> m_pages;  // each kPageBytes + kPagePad, never resized
  std::size_t m_page_used = 0;                     // bytes handed out from the last page
  std::array<std::uint32_t, kMaxGroup + 1> m_free{};  // free list head per group size (kNone: empty)
  std::size_t m_free_bytes = 0;
  std::size_t m_internal = 0;
  std::size_t m_live_groups = 0;
  std::size_t m_live_group_bytes = 0;
};

/// Mean-ratio quality 12·(3V)^(2/3) / Σ l² of a tetrahedron (1 for the regular one, 0 when
/// degenerate); V is the absolute volume.
[[nodiscard]] double tet_mean_ratio(const std::array<Vec3, 4>& x) noexcept;

/// Signed volume (mm³) of the tetrahedron (a, b, c, d).
[[nodiscard]] inline double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

/// The 8 children of an ordered tetrahedron by the TreeTable (child vertex order kept).
[[nodiscard]] std::array<std::array<Vec3, 4>, 8> red_children(const std::array<Vec3, 4>& x) noexcept;

}  // namespace ido::drill

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
/// is the root of a tree of Bey red refinements (TreeTable). Node storage is one 32-bit
/// word per node: kFull, kErased, or the index of the block of its 8 children's words.
/// Blocks of erased siblings merge back into their parent and return to a free list.
/// Blocks live in fixed pages of kBlocksPerPage, so growing the storage never moves (copies)
/// the blocks already in use: a refinement costs O(1) even when the storage grows.
/// Geometry is never stored: it is computed from the root and the node's path.
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
  /// Storage word of root @p r: kFull, kErased, or (internal) the index of its children's
  /// block. With child_word() it lets a top-down walk read states in O(1) per node.
  [[nodiscard]] std::uint32_t root_word(std::size_t r) const noexcept { return m_root_word[r]; }
  /// Word of child slot @p s of an internal node whose word is @p word.
  [[nodiscard]] std::uint32_t child_word(std::uint32_t word, int s) const noexcept {
    return block(word)[static_cast<std::size_t>(s)];
  }
  /// The state a storage word stands for.
  [[nodiscard]] static NodeState state_of_word(std::uint32_t word) noexcept {
    return word == kFull ? NodeState::Full : word == kErased ? NodeState::Erased : NodeState::Internal;
  }
  /// Splits a full leaf into 8 full children. Returns false (and does nothing) if the node
  /// is not a full leaf or is at kMaxDepth.
  bool refine(const NodeRef& node);
  /// Removes the node's material: the node becomes an erased leaf, its subtree's blocks are
  /// freed, and ancestors whose 8 children are all erased merge into erased leaves. Returns
  /// the topmost node that became an erased leaf (@p node itself when nothing merged, or
  /// when it lies below a leaf and nothing was done).
  NodeRef erase(const NodeRef& node);
  /// As erase(node) for a node below internal ancestors whose storage words the caller
  /// holds (a top-down traversal): @p ancestor_words[d] is the word of the node's ancestor
  /// at depth d, for every d < node.depth (precondition: each is that ancestor's current
  /// word, internal), so the path is not walked down from the root. Falls back to
  /// erase(node) when a given word is not a block index (full, erased or out of range).
  NodeRef erase(const NodeRef& node, std::span<const std::uint32_t> ancestor_words);
  /// Undoes a refinement that removed nothing: an internal node whose 8 children are all
  /// full leaves becomes a full leaf again. Returns true if it did.
  bool coarsen(const NodeRef& node);

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
        for (int s = 7; s >= 0; --s) {
          stack[static_cast<std::size_t>(top++)] = {it.node.child(s), block(it.word)[static_cast<std::size_t>(s)]};
        }
      }
    }
  }

  /// Spatial hash of the root tetrahedra.
  [[nodiscard]] const geometry::SpatialHash& root_hash() const noexcept { return m_hash; }
  /// Bounding box of root @p r (mm).
  [[nodiscard]] const geometry::Box3& root_box(std::size_t r) const noexcept { return m_root_box[r]; }

  /// Live nodes: every root plus 8 per child block in use.
  [[nodiscard]] std::size_t node_count() const noexcept { return m_roots.size() + 8 * m_live_blocks; }
  /// Bytes of node storage: one word per root plus every block handed out (free ones too;
  /// not the unused rest of the last page).
  [[nodiscard]] std::size_t node_storage_bytes() const noexcept {
    return m_root_word.size() * sizeof(std::uint32_t) + m_block_count * sizeof(Block);
  }
  /// Bytes per live node: (root words + blocks in use) / node_count() — 4 by construction.
  [[nodiscard]] double bytes_per_node() const noexcept {
    return static_cast<double>(m_root_word.size() * sizeof(std::uint32_t) + m_live_blocks * sizeof(Block)) /
           static_cast<double>(node_count());
  }
  /// node_storage_bytes() / node_count(): includes blocks waiting on the free list.
  [[nodiscard]] double storage_bytes_per_node() const noexcept {
    return static_cast<double>(node_storage_bytes()) / static_cast<double>(node_count());
  }
  /// Child blocks in use / on the free list.
  [[nodiscard]] std::size_t live_blocks() const noexcept { return m_live_blocks; }
  [[nodiscard]] std::size_t free_blocks() const noexcept { return m_block_count - m_live_blocks; }
  /// Sum of the volumes of full leaves (mm³).
  [[nodiscard]] double material_volume() const;
  /// Sum of the root volumes (mm³).
  [[nodiscard]] double total_volume() const noexcept { return m_total_volume; }
  /// Mean edge length of the input mesh (mm).
  [[nodiscard]] double mean_edge_length() const noexcept { return m_mean_edge; }

  static constexpr std::uint32_t kFull = 0xFFFFFFFFU;
  static constexpr std::uint32_t kErased = 0xFFFFFFFEU;

 private:
  using Block = std::array<std::uint32_t, 8>;
  static constexpr std::uint32_t kNoBlock = 0xFFFFFFFDU;
  static constexpr int kPageShift = 12;
  static constexpr std::uint32_t kBlocksPerPage = 1U << kPageShift;  // 128 KiB pages

  [[nodiscard]] const Block& block(std::uint32_t b) const noexcept {
    return m_pages[b >> kPageShift][b & (kBlocksPerPage - 1U)];
  }
  [[nodiscard]] Block& block(std::uint32_t b) noexcept { return m_pages[b >> kPageShift][b & (kBlocksPerPage - 1U)]; }

  [[nodiscard]] Location descend(std::uint32_t root, const std::array<double, 4>& root_lambda) const noexcept;
  [[nodiscard]] bool outside_root_box(std::size_t r, const Vec3& p_mm) const noexcept;
  std::uint32_t* word_of(const NodeRef& node) noexcept;
  [[nodiscard]] std::uint32_t word_at(const NodeRef& node) const noexcept;
  std::uint32_t allocate_block(std::uint32_t fill);
  NodeRef erase_path(const NodeRef& node, std::array<std::uint32_t*, kMaxDepth + 1>& path);
  void free_subtree(std::uint32_t word);
  void free_block(std::uint32_t b);
  void update_root_geometry();

  std::vector<Vec3> m_vertices;
  std::vector<Tet> m_roots;
  std::vector<std::array<RootFaceNeighbor, 4>> m_root_neighbors;
  std::vector<Mat3> m_root_inverse;   // barycentric map: (λ1, λ2, λ3) = M (p − x0)
  std::vector<double> m_root_volume;
  std::vector<double> m_root_diameter;
  std::vector<geometry::Box3> m_root_box;
  geometry::Box3 m_mesh_box;  // union of the root boxes, grown by kBoxSlack × its diagonal
  std::vector<float> m_density;
  double m_total_volume = 0.0;
  double m_mean_edge = 0.0;
  double m_hash_cell = 0.0;
  geometry::SpatialHash m_hash;

  std::vector<std::uint32_t> m_root_word;
  std::vector<std::vector<Block>> m_pages;  // each of kBlocksPerPage blocks, never resized
  std::size_t m_block_count = 0;            // blocks handed out so far (live + free)
  std::uint32_t m_free = kNoBlock;
  std::size_t m_live_blocks = 0;
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

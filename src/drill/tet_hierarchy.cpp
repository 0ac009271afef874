// SPDX-License-Identifier: Apache-2.0
// Hand-written: the project's adaptive tetrahedral hierarchy (Bey red refinement; node words
// that are leaf states, inline child masks or ids of variable-size child groups with a free
// list per size), after Turini et al. 2007 (IdoLib).
#include "ido/drill/tet_hierarchy.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include <Eigen/Dense>

#include "ido/core/error.h"

namespace ido::drill {

double tet_mean_ratio(const std::array<Vec3, 4>& x) noexcept {
  const double v = std::abs(signed_volume(x[0], x[1], x[2], x[3]));
  double l2 = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) l2 += (x[static_cast<std::size_t>(i)] - x[static_cast<std::size_t>(j)]).squaredNorm();
  if (l2 <= 0.0) return 0.0;
  return 12.0 * std::pow(3.0 * v, 2.0 / 3.0) / l2;
}

std::array<std::array<Vec3, 4>, 8> red_children(const std::array<Vec3, 4>& x) noexcept {
  const TreeTable& t = TreeTable::get();
  std::array<std::array<Vec3, 4>, 8> c;
  for (std::size_t s = 0; s < 8; ++s)
    for (std::size_t k = 0; k < 4; ++k) c[s][k] = 0.5 * (x[t.vertex[s][k][0]] + x[t.vertex[s][k][1]]);
  return c;
}

namespace {

// Cube of the mean ratio up to a constant, V² / (Σ l²)³ (monotone in the mean ratio, no pow).
double quality_cubed(const std::array<Vec3, 4>& x) noexcept {
  const double v = signed_volume(x[0], x[1], x[2], x[3]);
  double l2 = 0.0;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j) l2 += (x[i] - x[j]).squaredNorm();
  return v * v / (l2 * l2 * l2);
}

// Worst quality over the descendants of an ordered tetrahedron: corner children are
// similar to their parent, so the inner children (slots 4–7) and their children hold
// every class.
double worst_descendant_quality(const std::array<Vec3, 4>& x) {
  double worst = quality_cubed(x);
  const auto c = red_children(x);
  for (std::size_t s = 4; s < 8; ++s) {
    worst = std::min(worst, quality_cubed(c[s]));
    const auto g = red_children(c[s]);
    for (std::size_t k = 4; k < 8; ++k) worst = std::min(worst, quality_cubed(g[k]));
  }
  return worst;
}

// Boxes are grown by this fraction of the root's longest edge (the mesh box: of its
// diagonal) before a point is rejected by them. A point beyond a root's box by δ has a
// barycentric coordinate below −δ / (4 · longest edge) = −2.5e-10 here, far below the −1e-12
// slack locate() accepts, so a box rejection never drops a root the barycentric test takes.
constexpr double kBoxSlack = 1e-9;

constexpr int kEvenPermutations[12][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 0, 3, 2},
                                          {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 0, 1, 3}, {2, 1, 3, 0},
                                          {2, 3, 0, 1}, {3, 0, 2, 1}, {3, 1, 0, 2}, {3, 2, 1, 0}};

}  // namespace

TetHierarchy::TetHierarchy(const geometry::TetMesh& mesh, const HierarchyOptions& options) {
  if (mesh.tets.empty()) throw InvalidInput("drill: the tetrahedral mesh has no tetrahedra");
  const auto nv = static_cast<std::int32_t>(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) throw InvalidInput("drill: vertex " + std::to_string(i) + " is not finite");
  }
  m_vertices = mesh.vertices;
  m_roots.reserve(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    Tet tet = mesh.tets[t];
    for (auto v : tet) {
      if (v < 0 || v >= nv) throw InvalidInput("drill: tetrahedron " + std::to_string(t) + " has a vertex index out of range");
    }
    auto pos = [&](const Tet& q) {
      return std::array<Vec3, 4>{m_vertices[static_cast<std::size_t>(q[0])], m_vertices[static_cast<std::size_t>(q[1])],
                                 m_vertices[static_cast<std::size_t>(q[2])], m_vertices[static_cast<std::size_t>(q[3])]};
    };
    auto x = pos(tet);
    const double vol = signed_volume(x[0], x[1], x[2], x[3]);
    double l2max = 0.0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) l2max = std::max(l2max, (x[static_cast<std::size_t>(i)] - x[static_cast<std::size_t>(j)]).squaredNorm());
    if (!(std::abs(vol) > 1e-12 * std::pow(l2max, 1.5))) {
      throw InvalidInput("drill: tetrahedron " + std::to_string(t) + " is degenerate (zero volume)");
    }
    if (vol < 0.0) std::swap(tet[2], tet[3]);
    if (options.reorder_roots) {
      Tet best = tet;
      double best_q = -1.0;
      for (const auto& p : kEvenPermutations) {
        const Tet cand{tet[static_cast<std::size_t>(p[0])], tet[static_cast<std::size_t>(p[1])],
                       tet[static_cast<std::size_t>(p[2])], tet[static_cast<std::size_t>(p[3])]};
        const double q = worst_descendant_quality(pos(cand));
        if (q > best_q + 1e-12) {
          best_q = q;
          best = cand;
        }
      }
      tet = best;
    }
    m_roots.push_back(tet);
  }
  // Root face adjacency through sorted vertex triples.
  m_root_neighbors.assign(m_roots.size(), {});
  std::map<std::array<std::int32_t, 3>, std::pair<std::int32_t, std::int32_t>> open;
  for (std::size_t r = 0; r < m_roots.size(); ++r) {
    for (int f = 0; f < 4; ++f) {
      std::array<std::int32_t, 3> key{};
      int n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != f) key[static_cast<std::size_t>(n++)] = m_roots[r][static_cast<std::size_t>(k)];
      std::sort(key.begin(), key.end());
      auto it = open.find(key);
      if (it == open.end()) {
        open.emplace(key, std::make_pair(static_cast<std::int32_t>(r), f));
      } else {
        const auto [r2, f2] = it->second;
        m_root_neighbors[r][static_cast<std::size_t>(f)] = {r2, f2};
        m_root_neighbors[static_cast<std::size_t>(r2)][static_cast<std::size_t>(f2)] = {static_cast<std::int32_t>(r), f};
        open.erase(it);
      }
    }
  }
  double edge_sum = 0.0;
  for (const auto& t : m_roots)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        edge_sum += (m_vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(i)])] -
                     m_vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(j)])]).norm();
  m_mean_edge = edge_sum / (6.0 * static_cast<double>(m_roots.size()));
  m_hash_cell = options.hash_cell_mm > 0.0 ? options.hash_cell_mm : m_mean_edge;
  m_density.assign(m_roots.size(), 1.0F);
  m_root_word.assign(m_roots.size(), kFull);
  m_free.fill(kNone);
  update_root_geometry();
}

void TetHierarchy::update_root_geometry() {
  const std::size_t n = m_roots.size();
  m_root_inverse.resize(n);
  m_root_volume.resize(n);
  m_root_diameter.resize(n);
  m_root_box.resize(n);
  m_total_volume = 0.0;
  for (std::size_t r = 0; r < n; ++r) {
    const auto& t = m_roots[r];
    const Vec3& x0 = m_vertices[static_cast<std::size_t>(t[0])];
    Mat3 e;
    for (int k = 0; k < 3; ++k) e.col(k) = m_vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k + 1)])] - x0;
    const double vol = e.determinant() / 6.0;
    double diam = 0.0;
    geometry::Aabb box{x0, x0};
    for (int i = 0; i < 4; ++i) {
      const Vec3& xi = m_vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(i)])];
      box.extend(xi);
      for (int j = i + 1; j < 4; ++j) diam = std::max(diam, (xi - m_vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(j)])]).norm());
    }
    if (!(vol > 1e-12 * diam * diam * diam)) {
      throw InvalidInput("drill: root tetrahedron " + std::to_string(r) + " is degenerate or inverted");
    }
    m_root_inverse[r] = e.inverse();
    m_root_volume[r] = vol;
    m_root_diameter[r] = diam;
    m_root_box[r] = box;
    m_total_volume += vol;
    m_mesh_box.extend(box);
  }
  m_mesh_box = m_mesh_box.inflated(kBoxSlack * m_mesh_box.diagonal());
  m_hash = geometry::SpatialHash(m_root_box, m_hash_cell);
}

void TetHierarchy::set_vertex_positions(std::span<const Vec3> positions_mm) {
  if (positions_mm.size() != m_vertices.size()) {
    throw InvalidInput("drill: set_vertex_positions needs " + std::to_string(m_vertices.size()) + " positions, got " +
                       std::to_string(positions_mm.size()));
  }
  for (std::size_t i = 0; i < positions_mm.size(); ++i) {
    if (!positions_mm[i].allFinite()) throw InvalidInput("drill: position " + std::to_string(i) + " is not finite");
  }
  const std::vector<Vec3> old = m_vertices;
  m_vertices.assign(positions_mm.begin(), positions_mm.end());
  try {
    update_root_geometry();
  } catch (...) {
    m_vertices = old;
    update_root_geometry();
    throw;
  }
}

// Words of the node's ancestors and its own, w[0..depth], read top-down. False when it lies
// below a leaf (w[d] for d beyond that leaf is not written).
bool TetHierarchy::walk(const NodeRef& node, PathWords& w) const noexcept {
  w[0] = m_root_word[node.root];
  for (int level = 1; level <= node.depth; ++level) {
    const std::uint32_t p = w[static_cast<std::size_t>(level - 1)];
    if (p >= kErased) return false;
    w[static_cast<std::size_t>(level)] = child_word(p, node.slot(level));
  }
  return true;
}

NodeState TetHierarchy::state(const NodeRef& node) const noexcept {
  std::uint32_t w = m_root_word[node.root];
  for (int level = 1; level <= node.depth && w < kErased; ++level) w = child_word(w, node.slot(level));
  return state_of_word(w);
}

std::size_t TetHierarchy::group_size(std::uint32_t id) const noexcept {
  const std::uint8_t* g = group(id);
  return std::max(kMinGroup, payload_offset(static_cast<unsigned>(g[0]) | (static_cast<unsigned>(g[1]) << 8)));
}

std::uint32_t TetHierarchy::allocate_group(std::size_t size) {
  std::uint32_t id = m_free[size];
  if (id != kNone) {
    const std::uint8_t* g = group(id);
    m_free[size] = static_cast<std::uint32_t>(g[0]) | (static_cast<std::uint32_t>(g[1]) << 8) |
                   (static_cast<std::uint32_t>(g[2]) << 16) | (static_cast<std::uint32_t>(g[3]) << 24);
    m_free_bytes -= size;
  } else {
    if (m_pages.empty() || m_page_used + size > kPageBytes) {
      if (m_pages.size() + 1 >= (kMaskBase >> kPageShift)) throw Error("drill: node storage exhausted");
      // The rest of the full page goes to the free list of its size (a group of exactly that
      // size may take it); too short for any group, it is slack (counted with the free bytes).
      if (!m_pages.empty()) {
        const std::size_t tail = kPageBytes - m_page_used;
        m_free_bytes += tail;
        if (tail >= kMinGroup) {
          const auto tid = static_cast<std::uint32_t>(((m_pages.size() - 1) << kPageShift) | m_page_used);
          std::uint8_t* g = group(tid);
          const std::uint32_t next = m_free[tail];
          for (int k = 0; k < 4; ++k) g[k] = static_cast<std::uint8_t>(next >> (8 * k));
          m_free[tail] = tid;
        }
      }
      m_pages.emplace_back(kPageBytes + kPagePad);  // a new page; none moves
      m_page_used = 0;
    }
    id = static_cast<std::uint32_t>(((m_pages.size() - 1) << kPageShift) | m_page_used);
    m_page_used += size;
  }
  ++m_live_groups;
  m_live_group_bytes += size;
  return id;
}

void TetHierarchy::free_group(std::uint32_t id) {
  const std::size_t size = group_size(id);
  std::uint8_t* g = group(id);
  const std::uint32_t next = m_free[size];
  for (int k = 0; k < 4; ++k) g[k] = static_cast<std::uint8_t>(next >> (8 * k));
  m_free[size] = id;
  m_free_bytes += size;
  --m_live_groups;
  m_live_group_bytes -= size;
}

// Writes the codes and payloads of @p children (their words) into group bytes @p g.
void TetHierarchy::write_group(std::uint8_t* g, const std::array<std::uint32_t, 8>& children) const noexcept {
  unsigned codes = 0;
  std::size_t off = 2;
  for (std::size_t s = 0; s < 8; ++s) {
    const std::uint32_t c = children[s];
    unsigned code = kCodeErased;
    if (c == kFull) {
      code = kCodeFull;
    } else if (c == kErased) {
      code = kCodeErased;
    } else if (c >= kMaskBase) {
      code = kCodeMask;
      g[off++] = static_cast<std::uint8_t>(c & 0xFFU);
    } else {
      code = kCodeGroup;
      for (int k = 0; k < 4; ++k) g[off++] = static_cast<std::uint8_t>(c >> (8 * k));
    }
    codes |= code << (2 * s);
  }
  g[0] = static_cast<std::uint8_t>(codes & 0xFFU);
  g[1] = static_cast<std::uint8_t>(codes >> 8);
}

// The word of an internal node with children words @p children: a mask word when all are
// leaves, else a newly allocated group.
std::uint32_t TetHierarchy::encode(const std::array<std::uint32_t, 8>& children) {
  std::size_t size = 2;
  unsigned full = 0;
  for (std::size_t s = 0; s < 8; ++s) {
    const std::uint32_t c = children[s];
    if (c == kFull) full |= 1U << s;
    if (c < kErased) size += c >= kMaskBase ? 1 : 4;
  }
  if (size == 2) return kMaskBase | full;
  const std::uint32_t id = allocate_group(std::max(size, kMinGroup));
  write_group(group(id), children);
  return id;
}

// Sets the word of the ancestor at depth @p depth of @p node (its current word is w[depth];
// w holds the current words of the path) to @p word, and rewrites the ancestors' storage up
// the path as far as it changes: a mask parent takes the bit (or becomes a group when the
// child becomes internal), a group parent is rewritten in place when the child's payload
// keeps its size (its code and payload bytes only), else re-encoded at its new size (a mask
// when no internal child is left), which changes the parent's own word in the grandparent,
// and so on. The old word's own storage is the caller's (free_subtree before, when it goes).
// w is updated.
void TetHierarchy::set_word(const NodeRef& node, int depth, PathWords& w, std::uint32_t word) {
  auto code_of = [](std::uint32_t x) {
    return x == kFull ? kCodeFull : x == kErased ? kCodeErased : x >= kMaskBase ? kCodeMask : kCodeGroup;
  };
  for (int d = depth;; --d) {
    const auto du = static_cast<std::size_t>(d);
    w[du] = word;
    if (d == 0) {
      m_root_word[node.root] = word;
      return;
    }
    const std::uint32_t pw = w[du - 1];
    const auto s = static_cast<unsigned>(node.slot(d));
    if (!is_group(pw) && word >= kErased) {
      // A mask parent whose child stays a leaf: the child's bit (the encoding of its 8 leaves).
      word = word == kFull ? (pw | (1U << s)) : (pw & ~(1U << s));
      continue;
    }
    if (is_group(pw)) {
      std::uint8_t* g = group(pw);
      const unsigned codes = static_cast<unsigned>(g[0]) | (static_cast<unsigned>(g[1]) << 8);
      const unsigned old_code = (codes >> (2 * s)) & 3U, code = code_of(word);
      static_assert(kCodeErased < kCodeMask && kCodeFull < kCodeMask && kCodeMask < kCodeGroup);
      const bool same_size = old_code == code || (old_code < kCodeMask && code < kCodeMask);
      if (same_size) {
        // In place (the bytes write_group would write): the parent's word stays.
        const unsigned nc = (codes & ~(3U << (2 * s))) | (code << (2 * s));
        g[0] = static_cast<std::uint8_t>(nc & 0xFFU);
        g[1] = static_cast<std::uint8_t>(nc >> 8);
        const std::size_t off = payload_offset(codes & ((1U << (2 * s)) - 1U));
        if (code == kCodeMask) {
          g[off] = static_cast<std::uint8_t>(word & 0xFFU);
        } else if (code == kCodeGroup) {
          for (std::size_t k = 0; k < 4; ++k) g[off + k] = static_cast<std::uint8_t>(word >> (8 * k));
        }
        return;
      }
    }
    std::array<std::uint32_t, 8> children = child_words(pw);
    children[s] = word;
    const std::uint32_t parent_word = encode(children);
    if (is_group(pw)) free_group(pw);
    word = parent_word;
  }
}

void TetHierarchy::free_subtree(std::uint32_t word) {
  if (word >= kErased) return;
  --m_internal;
  if (!is_group(word)) return;
  for (int s = 0; s < 8; ++s) free_subtree(child_word(word, s));
  free_group(word);
}

bool TetHierarchy::refine(const NodeRef& node) {
  if (node.depth >= kMaxDepth) return false;
  PathWords w{};
  if (!walk(node, w) || w[node.depth] != kFull) return false;
  set_word(node, node.depth, w, kMaskBase | 0xFFU);
  ++m_internal;
  return true;
}

NodeRef TetHierarchy::erase(const NodeRef& node) {
  PathWords w{};
  if (!walk(node, w)) return node;  // below a leaf: nothing to do for erased, refine first for full
  return erase_path(node, w);
}

NodeRef TetHierarchy::erase(const NodeRef& node, std::span<const std::uint32_t> ancestor_words) {
  if (ancestor_words.size() < node.depth) return erase(node);
  if (node.depth > 0 && ancestor_words[0] != m_root_word[node.root]) return erase(node);
  PathWords w{};
  for (std::size_t d = 0; d < node.depth; ++d) {
    const std::uint32_t a = ancestor_words[d];
    if (a >= kErased || (is_group(a) && (a >> kPageShift) >= m_pages.size())) return erase(node);  // not internal
    w[d] = a;
  }
  w[node.depth] = node.depth == 0 ? m_root_word[node.root] : child_word(w[node.depth - 1U], node.slot(node.depth));
  return erase_path(node, w);
}

// Erases the node (w: the current words of its path) and merges erased sibling blocks upward.
NodeRef TetHierarchy::erase_path(const NodeRef& node, PathWords& w) {
  free_subtree(w[node.depth]);
  set_word(node, node.depth, w, kErased);
  // Merge fully erased siblings upward: a parent whose children are all erased holds the
  // empty mask (a group always has an internal child).
  NodeRef n = node;
  while (n.depth > 0 && w[n.depth - 1U] == kMaskBase) {
    --m_internal;
    n = n.parent();
    set_word(node, n.depth, w, kErased);
  }
  return n;
}

bool TetHierarchy::refine_on_path(const NodeRef& node, PathWords& w) {
  if (node.depth >= kMaxDepth || w[node.depth] != kFull) return false;
  set_word(node, node.depth, w, kMaskBase | 0xFFU);
  ++m_internal;
  return true;
}

NodeRef TetHierarchy::erase_on_path(const NodeRef& node, PathWords& w) { return erase_path(node, w); }

bool TetHierarchy::coarsen_on_path(const NodeRef& node, PathWords& w) {
  if (w[node.depth] != (kMaskBase | 0xFFU)) return false;
  set_word(node, node.depth, w, kFull);
  --m_internal;
  return true;
}

bool TetHierarchy::coarsen(const NodeRef& node) {
  PathWords w{};
  if (!walk(node, w) || w[node.depth] != (kMaskBase | 0xFFU)) return false;
  set_word(node, node.depth, w, kFull);
  --m_internal;
  return true;
}

NodeGeometry TetHierarchy::geometry(const NodeRef& node) const noexcept {
  const TreeTable& t = TreeTable::get();
  NodeGeometry g;
  for (std::size_t i = 0; i < 4; ++i) {
    g.vertex[i] = {0, 0, 0, 0};
    g.vertex[i][i] = kBaryScale;
  }
  for (int level = 1; level <= node.depth; ++level) {
    const auto s = static_cast<std::size_t>(node.slot(level));
    std::array<BaryKey, 4> c{};
    for (std::size_t k = 0; k < 4; ++k) {
      const auto& a = g.vertex[t.vertex[s][k][0]];
      const auto& b = g.vertex[t.vertex[s][k][1]];
      for (std::size_t j = 0; j < 4; ++j) c[k][j] = (a[j] + b[j]) / 2;
    }
    g.vertex = c;
    g.flipped = g.flipped != (t.parity[s] != 0);
  }
  return g;
}

Vec3 TetHierarchy::world_position(std::size_t r, const BaryKey& key) const noexcept {
  const auto& t = m_roots[r];
  Vec3 p = Vec3::Zero();
  for (std::size_t i = 0; i < 4; ++i) p += static_cast<double>(key[i]) * m_vertices[static_cast<std::size_t>(t[i])];
  return p / static_cast<double>(kBaryScale);
}

std::array<Vec3, 4> TetHierarchy::world_vertices(const NodeRef& node) const noexcept {
  const TreeTable& t = TreeTable::get();
  const auto& rt = m_roots[node.root];
  std::array<Vec3, 4> x{m_vertices[static_cast<std::size_t>(rt[0])], m_vertices[static_cast<std::size_t>(rt[1])],
                        m_vertices[static_cast<std::size_t>(rt[2])], m_vertices[static_cast<std::size_t>(rt[3])]};
  for (int level = 1; level <= node.depth; ++level) {
    const auto s = static_cast<std::size_t>(node.slot(level));
    std::array<Vec3, 4> c;
    for (std::size_t k = 0; k < 4; ++k) c[k] = 0.5 * (x[t.vertex[s][k][0]] + x[t.vertex[s][k][1]]);
    x = c;
  }
  return x;
}

std::array<double, 4> TetHierarchy::root_barycentric(std::size_t r, const Vec3& p_mm) const noexcept {
  const Vec3 l = m_root_inverse[r] * (p_mm - m_vertices[static_cast<std::size_t>(m_roots[r][0])]);
  return {1.0 - l.x() - l.y() - l.z(), l.x(), l.y(), l.z()};
}

bool TetHierarchy::outside_root_box(std::size_t r, const Vec3& p_mm) const noexcept {
  const geometry::Aabb& b = m_root_box[r];
  const double slack = kBoxSlack * m_root_diameter[r];
  return p_mm.x() < b.min.x() - slack || p_mm.y() < b.min.y() - slack || p_mm.z() < b.min.z() - slack ||
         p_mm.x() > b.max.x() + slack || p_mm.y() > b.max.y() + slack || p_mm.z() > b.max.z() + slack;
}

Location TetHierarchy::locate(const Vec3& p_mm) const noexcept {
  Location loc;
  // Cheap rejections before any barycentric test: a point outside the mesh's box (air
  // beyond the block) needs no hash look-up, and a candidate root whose box does not hold
  // the point cannot hold it.
  if (!m_mesh_box.contains(p_mm)) return loc;
  std::int32_t best_root = -1;
  double best_min = -1e-12;
  std::array<double, 4> best_lambda{};
  for (const std::int32_t r : m_hash.candidates(p_mm)) {
    if (outside_root_box(static_cast<std::size_t>(r), p_mm)) continue;
    const auto lambda = root_barycentric(static_cast<std::size_t>(r), p_mm);
    const double m = std::min(std::min(lambda[0], lambda[1]), std::min(lambda[2], lambda[3]));
    if (m >= best_min) {
      best_min = m;
      best_root = r;
      best_lambda = lambda;
      if (m >= 0.0) break;
    }
  }
  if (best_root < 0) return loc;
  return descend(static_cast<std::uint32_t>(best_root), best_lambda);
}

Location TetHierarchy::locate(const Vec3& p_mm, std::int32_t hint_root) const noexcept {
  if (hint_root >= 0 && static_cast<std::size_t>(hint_root) < m_roots.size()) {
    const auto lambda = root_barycentric(static_cast<std::size_t>(hint_root), p_mm);
    // Strictly inside: no other root of a conforming mesh holds the point, so the hash
    // look-up would find this root too.
    if (std::min(std::min(lambda[0], lambda[1]), std::min(lambda[2], lambda[3])) > 0.0)
      return descend(static_cast<std::uint32_t>(hint_root), lambda);
  }
  return locate(p_mm);
}

Location TetHierarchy::locate(const Vec3& p_mm, std::span<const std::int32_t> hint_roots) const noexcept {
  for (std::size_t i = 0; i < hint_roots.size(); ++i) {
    const std::int32_t r = hint_roots[i];
    if (r < 0 || static_cast<std::size_t>(r) >= m_roots.size()) continue;
    bool seen = false;  // a root repeated among the hints is tested once
    for (std::size_t j = 0; j < i && !seen; ++j) seen = hint_roots[j] == r;
    if (seen) continue;
    const auto lambda = root_barycentric(static_cast<std::size_t>(r), p_mm);
    if (std::min(std::min(lambda[0], lambda[1]), std::min(lambda[2], lambda[3])) > 0.0)
      return descend(static_cast<std::uint32_t>(r), lambda);
  }
  return locate(p_mm);
}

Location TetHierarchy::descend(std::uint32_t root, const std::array<double, 4>& root_lambda) const noexcept {
  const TreeTable& t = TreeTable::get();
  Location loc;
  loc.inside_mesh = true;
  loc.leaf = NodeRef{root, 0, 0};
  std::uint32_t w = m_root_word[root];
  auto lambda = root_lambda;
  while (w < kErased) {
    const int s = TreeTable::locate_child(lambda);
    lambda = t.to_child_coordinates(s, lambda);
    loc.leaf = loc.leaf.child(s);
    w = child_word(w, s);
  }
  loc.state = w == kFull ? NodeState::Full : NodeState::Erased;
  return loc;
}

double TetHierarchy::material_volume() const {
  double v = 0.0;
  for (std::size_t r = 0; r < m_roots.size(); ++r) {
    for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      if (s == NodeState::Full) v += node_volume(n);
    });
  }
  return v;
}

}  // namespace ido::drill

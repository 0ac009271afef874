// SPDX-License-Identifier: Apache-2.0
// Hand-written: the project's adaptive tetrahedral hierarchy (Bey red refinement, node words
// with a free list of child blocks), after Turini et al. 2007 (IdoLib).
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
    geometry::Box3 box{x0, x0};
    for (int i = 0; i < 4; ++i) {
      const Vec3& xi = m_vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(i)])];
      box.lo = box.lo.cwiseMin(xi);
      box.hi = box.hi.cwiseMax(xi);
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
    if (r == 0) m_mesh_box = box;
    m_mesh_box.lo = m_mesh_box.lo.cwiseMin(box.lo);
    m_mesh_box.hi = m_mesh_box.hi.cwiseMax(box.hi);
  }
  const Vec3 slack = Vec3::Constant(kBoxSlack * (m_mesh_box.hi - m_mesh_box.lo).norm());
  m_mesh_box.lo -= slack;
  m_mesh_box.hi += slack;
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

std::uint32_t TetHierarchy::word_at(const NodeRef& node) const noexcept {
  std::uint32_t w = m_root_word[node.root];
  for (int level = 1; level <= node.depth; ++level) {
    if (w == kFull || w == kErased) return w;  // below a leaf: inherit its state
    w = block(w)[static_cast<std::size_t>(node.slot(level))];
  }
  return w;
}

std::uint32_t* TetHierarchy::word_of(const NodeRef& node) noexcept {
  std::uint32_t* w = &m_root_word[node.root];
  for (int level = 1; level <= node.depth; ++level) {
    if (*w == kFull || *w == kErased) return nullptr;
    w = &block(*w)[static_cast<std::size_t>(node.slot(level))];
  }
  return w;
}

NodeState TetHierarchy::state(const NodeRef& node) const noexcept {
  const std::uint32_t w = word_at(node);
  if (w == kFull) return NodeState::Full;
  if (w == kErased) return NodeState::Erased;
  return NodeState::Internal;
}

std::uint32_t TetHierarchy::allocate_block(std::uint32_t fill) {
  std::uint32_t b;
  if (m_free != kNoBlock) {
    b = m_free;
    m_free = block(b)[0];
  } else {
    if (m_block_count >= kNoBlock) throw Error("drill: node storage exhausted");
    b = static_cast<std::uint32_t>(m_block_count);
    if ((b & (kBlocksPerPage - 1U)) == 0) m_pages.emplace_back(kBlocksPerPage);  // a new page; none moves
    ++m_block_count;
  }
  block(b).fill(fill);
  ++m_live_blocks;
  return b;
}

void TetHierarchy::free_block(std::uint32_t b) {
  block(b)[0] = m_free;
  m_free = b;
  --m_live_blocks;
}

void TetHierarchy::free_subtree(std::uint32_t word) {
  if (word == kFull || word == kErased) return;
  for (std::uint32_t c : block(word)) free_subtree(c);
  free_block(word);
}

bool TetHierarchy::refine(const NodeRef& node) {
  if (node.depth >= kMaxDepth) return false;
  std::uint32_t* w = word_of(node);
  if (w == nullptr || *w != kFull) return false;
  *w = allocate_block(kFull);  // pages never move, so w stays valid
  return true;
}

NodeRef TetHierarchy::erase(const NodeRef& node) {
  // The words on the path from the root, found in one descent (pages never move).
  std::array<std::uint32_t*, kMaxDepth + 1> path{};
  std::uint32_t* w = &m_root_word[node.root];
  path[0] = w;
  for (int level = 1; level <= node.depth; ++level) {
    if (*w == kFull || *w == kErased) return node;  // below a leaf: nothing to do for erased, refine first for full
    w = &block(*w)[static_cast<std::size_t>(node.slot(level))];
    path[static_cast<std::size_t>(level)] = w;
  }
  return erase_path(node, path);
}

NodeRef TetHierarchy::erase(const NodeRef& node, std::span<const std::uint32_t> ancestor_words) {
  if (ancestor_words.size() < node.depth) return erase(node);
  for (std::size_t d = 0; d < node.depth; ++d)
    if (ancestor_words[d] == kFull || ancestor_words[d] == kErased || ancestor_words[d] >= m_block_count)
      return erase(node);  // not internal words: walk from the root instead
  std::array<std::uint32_t*, kMaxDepth + 1> path{};
  path[0] = &m_root_word[node.root];
  for (int level = 1; level <= node.depth; ++level)
    path[static_cast<std::size_t>(level)] =
        &block(ancestor_words[static_cast<std::size_t>(level - 1)])[static_cast<std::size_t>(node.slot(level))];
  return erase_path(node, path);
}

// Erases the node whose word path[node.depth] points to (path[d]: the word of its ancestor at
// depth d) and merges erased sibling blocks upward.
NodeRef TetHierarchy::erase_path(const NodeRef& node, std::array<std::uint32_t*, kMaxDepth + 1>& path) {
  std::uint32_t* w = path[node.depth];
  free_subtree(*w);
  *w = kErased;
  // Merge fully erased sibling blocks upward.
  NodeRef n = node;
  while (n.depth > 0) {
    std::uint32_t* pw = path[static_cast<std::size_t>(n.depth - 1)];
    const std::uint32_t b = *pw;
    const Block& blk = block(b);
    if (!std::all_of(blk.begin(), blk.end(), [](std::uint32_t c) { return c == kErased; })) break;
    free_block(b);
    *pw = kErased;
    n = n.parent();
  }
  return n;
}

bool TetHierarchy::coarsen(const NodeRef& node) {
  std::uint32_t* w = word_of(node);
  if (w == nullptr || *w == kFull || *w == kErased) return false;
  const Block& blk = block(*w);
  if (!std::all_of(blk.begin(), blk.end(), [](std::uint32_t c) { return c == kFull; })) return false;
  free_block(*w);
  *w = kFull;
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
  const geometry::Box3& b = m_root_box[r];
  const double slack = kBoxSlack * m_root_diameter[r];
  return p_mm.x() < b.lo.x() - slack || p_mm.y() < b.lo.y() - slack || p_mm.z() < b.lo.z() - slack ||
         p_mm.x() > b.hi.x() + slack || p_mm.y() > b.hi.y() + slack || p_mm.z() > b.hi.z() + slack;
}

Location TetHierarchy::locate(const Vec3& p_mm) const noexcept {
  Location loc;
  // Cheap rejections before any barycentric test: a point outside the mesh's box (air
  // beyond the block) needs no hash look-up, and a candidate root whose box does not hold
  // the point cannot hold it.
  if ((p_mm.array() < m_mesh_box.lo.array()).any() || (p_mm.array() > m_mesh_box.hi.array()).any()) return loc;
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
  while (w != kFull && w != kErased) {
    const int s = TreeTable::locate_child(lambda);
    lambda = t.to_child_coordinates(s, lambda);
    loc.leaf = loc.leaf.child(s);
    w = block(w)[static_cast<std::size_t>(s)];
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

// SPDX-License-Identifier: Apache-2.0
// Hand-written: the project's burr erosion on the tetrahedral hierarchy.
#include "ido/drill/erosion.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ido/core/error.h"

namespace ido::drill {
namespace {

// True when the sphere (c, r) cannot touch the tetrahedron x: outside the bounding sphere
// of the vertices or entirely beyond one face plane. The plane test compares squares
// (n·(c − a))² > r² |n|² on the outer side, so no square root or division per face.
bool sphere_misses_tet(const std::array<Vec3, 4>& x, const Vec3& c, double r) {
  const Vec3 centroid = 0.25 * (x[0] + x[1] + x[2] + x[3]);
  double rad2 = 0.0;
  for (const auto& v : x) rad2 = std::max(rad2, (v - centroid).squaredNorm());
  const double reach = r + std::sqrt(rad2);
  const double d2 = (c - centroid).squaredNorm();
  if (d2 > reach * reach) return true;
  const double r2 = r * r;
  if (d2 <= r2) return false;  // the centroid is inside the sphere
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int f = 0; f < 4; ++f) {
    const Vec3& a = x[static_cast<std::size_t>(kFace[f][0])];
    const Vec3 n = (x[static_cast<std::size_t>(kFace[f][1])] - a).cross(x[static_cast<std::size_t>(kFace[f][2])] - a);
    const double len2 = n.squaredNorm();
    if (len2 <= 0.0) continue;
    const double dc = n.dot(c - a);
    // The centre is on the side away from the opposite vertex, farther than r.
    if (dc * n.dot(x[static_cast<std::size_t>(f)] - a) < 0.0 && dc * dc > r2 * len2) return true;
  }
  return false;
}

// True when erosion would remove anything from a full node of geometry x at depth `depth`
// (finest level `finest`) without touching the tree: the same decisions as
// Eroder::enter on a full leaf, evaluated on derived geometry only, so a partly covered
// leaf is refined only when a descendant will actually go (no refine-then-undo). Adds the
// nodes it tests to `visits`.
bool would_remove(const std::array<Vec3, 4>& x, int depth, int finest, const Vec3& c, double r, std::size_t& visits) {
  ++visits;
  if (sphere_misses_tet(x, c, r)) return false;
  const double r2 = r * r;
  bool all_inside = true;
  for (const auto& v : x) all_inside = all_inside && (v - c).squaredNorm() <= r2;
  if (all_inside) return true;
  if (depth >= finest) return (0.25 * (x[0] + x[1] + x[2] + x[3]) - c).squaredNorm() <= r2;
  const TreeTable& t = TreeTable::get();
  for (std::size_t s = 0; s < 8; ++s) {
    std::array<Vec3, 4> ch;
    for (std::size_t k = 0; k < 4; ++k) ch[k] = 0.5 * (x[t.vertex[s][k][0]] + x[t.vertex[s][k][1]]);
    if (would_remove(ch, depth + 1, finest, c, r, visits)) return true;
  }
  return false;
}

// Storage word of @p n, walked down from its root (the word of the leaf above it when it
// lies below a leaf).
std::uint32_t node_word(const TetHierarchy& h, const NodeRef& n) noexcept {
  std::uint32_t w = h.root_word(n.root);
  for (int level = 1; level <= n.depth && TetHierarchy::state_of_word(w) == NodeState::Internal; ++level)
    w = h.child_word(w, n.slot(level));
  return w;
}

}  // namespace

Eroder::Eroder(const ErosionOptions& options) : m_options(options) {
  if (options.max_depth < 0 || options.max_depth > kMaxDepth) {
    throw InvalidInput("erosion: max depth must be between 0 and " + std::to_string(kMaxDepth));
  }
  if (!(options.min_size_mm >= 0.0)) throw InvalidInput("erosion: minimum size must not be negative");
  m_unlimited = !(options.removal_rate_mm3_per_s > 0.0);
}

int Eroder::finest_level(const TetHierarchy& hierarchy, std::size_t r) const noexcept {
  if (m_options.min_size_mm <= 0.0) return m_options.max_depth;
  const double ratio = hierarchy.root_diameter(r) / m_options.min_size_mm;
  if (ratio <= 1.0) return 0;
  return std::min(kMaxDepth, static_cast<int>(std::ceil(std::log2(ratio) - 1e-12)));
}

void Eroder::clear_changed_roots() noexcept {
  for (auto r : m_changed) m_is_changed[r] = 0;
  m_changed.clear();
  m_changed_faces.clear();
  m_changed_nodes.clear();
}

bool Eroder::pay(double cost) noexcept {
  if (m_unlimited) return true;
  if (cost > m_budget) return false;
  m_budget -= cost;
  return true;
}

void Eroder::mark(const NodeRef& node, std::uint8_t faces) {
  if (!m_is_changed[node.root]) {
    m_is_changed[node.root] = 1;
    m_slot[node.root] = static_cast<std::uint32_t>(m_changed.size());
    m_changed.push_back(node.root);
    m_changed_faces.push_back(0);
  }
  auto& m = m_changed_faces[m_slot[node.root]];
  m = static_cast<std::uint8_t>(m | faces);
  m_changed_nodes.push_back(node);
}

// Steps 1–5 of processing a node for the current sphere: returns Done when the node needs
// nothing more (missed, erased, removed, or left whole), Pushed when it is partly covered and
// its children are to be processed (a frame was pushed), Abort when the volume budget ran out.
// @p word is the node's storage word, read from its parent's frame (no walk from the root).
Eroder::Enter Eroder::enter(TetHierarchy& h, const NodeRef& node, std::uint32_t word, const std::array<Vec3, 4>& x,
                            int finest, const std::array<std::int8_t, 4>& root_face, ErosionStats& stats) {
  ++m_visits;
  const NodeState st = TetHierarchy::state_of_word(word);
  if (st == NodeState::Erased) return Enter::Done;
  if (sphere_misses_tet(x, m_centre, m_radius)) return Enter::Done;
  const double r2 = m_radius * m_radius;
  bool all_inside = true;
  for (const auto& v : x) all_inside = all_inside && (v - m_centre).squaredNorm() <= r2;
  std::uint8_t face_mask = 0;
  for (const auto f : root_face)
    if (f >= 0) face_mask = static_cast<std::uint8_t>(face_mask | (1U << f));
  m_face_mask[node.depth] = face_mask;
  if (all_inside || node.depth >= finest) {
    if (!all_inside) {
      const Vec3 centroid = 0.25 * (x[0] + x[1] + x[2] + x[3]);
      if ((centroid - m_centre).squaredNorm() > r2) return Enter::Done;
    }
    double material = 0.0;
    if (st == NodeState::Full) {
      material = h.node_volume(node);
    } else {
      // Internal node entirely inside: its full descendants' volume.
      struct Item {
        NodeRef node;
        std::uint32_t word;
      };
      std::array<Item, 8 * (kMaxDepth + 1)> stack{};
      int top = 0;
      stack[static_cast<std::size_t>(top++)] = {node, word};
      while (top > 0) {
        const Item it = stack[static_cast<std::size_t>(--top)];
        const NodeState s = TetHierarchy::state_of_word(it.word);
        if (s == NodeState::Full) material += h.node_volume(it.node);
        if (s == NodeState::Internal)
          for (int c = 0; c < 8; ++c) stack[static_cast<std::size_t>(top++)] = {it.node.child(c), h.child_word(it.word, c)};
      }
    }
    if (!pay(material * h.density(node.root))) {
      stats.rate_limited = true;
      return Enter::Abort;
    }
    const NodeRef top = h.erase(node);  // the topmost ancestor merged into an erased leaf
    stats.removed_volume_mm3 += material;
    ++stats.nodes_removed;
    // Ancestors merged into erased leaves change what lies across their faces too.
    std::uint8_t faces = face_mask;
    for (int d = node.depth; d > top.depth; --d) faces = static_cast<std::uint8_t>(faces | m_face_mask[d - 1]);
    mark(top, faces);
    return Enter::Done;
  }
  // Partly covered, above the finest level: descend.
  bool refined_here = false;
  if (st == NodeState::Full) {
    // Decide before refining: a partly covered full leaf none of whose descendants would
    // go stays a leaf.
    if (node.depth >= kMaxDepth || !would_remove(x, node.depth, finest, m_centre, m_radius, m_visits)) return Enter::Done;
    if (!h.refine(node)) return Enter::Done;
    word = node_word(h, node);  // its new children's block
    refined_here = true;
    ++stats.nodes_refined;
    mark(node, face_mask);
  }
  m_stack.push_back(Frame{node, word, x, root_face, static_cast<std::int8_t>(finest), 0, refined_here, face_mask});
  return Enter::Pushed;
}

// Step 7, after the children: a refinement that removed nothing is undone.
void Eroder::leave(TetHierarchy& h, const Frame& f, ErosionStats& stats) {
  if (h.state(f.node) == NodeState::Internal && h.coarsen(f.node)) {
    if (f.refined_here) --stats.nodes_refined;
    mark(f.node, f.face_mask);
  }
}

void Eroder::start_sphere(const TetHierarchy& hierarchy, const Sphere& sphere) {
  m_centre = sphere.centre;
  m_radius = sphere.radius;
  const std::size_t n = hierarchy.root_count();
  if (++m_epoch == 0) {
    std::fill(m_stamp.begin(), m_stamp.end(), 0);
    m_epoch = 1;
  }
  m_candidates.clear();
  const geometry::Box3 box{m_centre - Vec3::Constant(m_radius), m_centre + Vec3::Constant(m_radius)};
  hierarchy.root_hash().for_each_in_box(box, [&](std::int32_t r) {
    if (static_cast<std::size_t>(r) >= n) return;
    auto& s = m_stamp[static_cast<std::size_t>(r)];
    if (s == m_epoch) return;
    s = m_epoch;
    const auto& rb = hierarchy.root_box(static_cast<std::size_t>(r));
    if ((rb.lo.array() > box.hi.array()).any() || (rb.hi.array() < box.lo.array()).any()) return;
    m_candidates.push_back(static_cast<std::uint32_t>(r));
  });
  std::sort(m_candidates.begin(), m_candidates.end());
  m_next_candidate = 0;
  m_stack.clear();
  m_active = true;
}

// The volume budget ran out: finish the frames on the stack (undoing idle refinements) and
// drop the current and queued positions.
void Eroder::drop_all(TetHierarchy& h, ErosionStats& stats) {
  while (!m_stack.empty()) {
    const Frame f = m_stack.back();
    m_stack.pop_back();
    leave(h, f, stats);
  }
  m_active = false;
  m_queue.clear();
  m_queue_head = 0;
}

void Eroder::enqueue(const Vec3& centre_mm, double radius_mm, double pressing_force_n, double dt_s) {
  if (!(pressing_force_n >= m_options.force_threshold_n) || !(radius_mm > 0.0) || !centre_mm.allFinite()) return;
  if (!m_unlimited) {
    const double rate = m_options.removal_rate_mm3_per_s;
    m_budget = std::min(m_budget + rate * std::max(dt_s, 0.0), 0.1 * rate);
  }
  if (m_queue_head == m_queue.size()) {
    m_queue.clear();
    m_queue_head = 0;
  }
  const Sphere s{centre_mm, radius_mm};
  const std::size_t waiting = m_queue.size() - m_queue_head;
  if (m_options.backlog_spacing > 0.0 && waiting >= 1) {
    // The position before the last queued one: the one queued before it, or the one in
    // progress.
    const Sphere current{m_centre, m_radius};
    const Sphere* before = waiting >= 2 ? &m_queue[m_queue.size() - 2] : (m_active ? &current : nullptr);
    if (before != nullptr && before->radius == radius_mm &&
        (before->centre - centre_mm).norm() <= m_options.backlog_spacing * radius_mm) {
      m_queue.back() = s;
      return;
    }
  }
  m_queue.push_back(s);
}

ErosionStats Eroder::run(TetHierarchy& hierarchy, std::size_t max_node_visits) {
  ErosionStats stats;
  const std::size_t n = hierarchy.root_count();
  if (m_stamp.size() != n) {
    m_stamp.assign(n, 0);
    m_is_changed.assign(n, 0);
    m_slot.assign(n, 0);
    m_changed.clear();
    m_changed_faces.clear();
    m_changed_nodes.clear();
  }
  m_visits = 0;
  if (m_active && !m_stack.empty()) {
    // Resuming: geometry may have moved (set_vertex_positions) and is derived again; frames
    // whose node is no longer internal are dropped.
    // Each frame's node is a child of the one below it: words are re-read top-down.
    std::size_t keep = 0;
    for (; keep < m_stack.size(); ++keep) {
      Frame& f = m_stack[keep];
      const std::uint32_t w =
          keep == 0 ? node_word(hierarchy, f.node) : hierarchy.child_word(m_stack[keep - 1].word, f.node.slot(f.node.depth));
      if (TetHierarchy::state_of_word(w) != NodeState::Internal) break;
      f.word = w;
    }
    m_stack.resize(keep);
    for (auto& f : m_stack) {
      f.x = hierarchy.world_vertices(f.node);
      m_face_mask[f.node.depth] = f.face_mask;
    }
  }
  const TreeTable& t = TreeTable::get();
  auto exhausted = [&] { return max_node_visits > 0 && m_visits >= max_node_visits; };
  for (;;) {
    if (!m_active) {
      if (m_queue_head == m_queue.size()) break;
      start_sphere(hierarchy, m_queue[m_queue_head++]);
    }
    bool aborted = false;
    for (;;) {
      if (exhausted()) {
        stats.nodes_visited = m_visits;
        stats.work_pending = true;
        return stats;
      }
      Enter e = Enter::Done;
      if (!m_stack.empty()) {
        Frame& f = m_stack.back();
        if (f.next_child == 8) {
          const Frame done = f;
          m_stack.pop_back();
          leave(hierarchy, done, stats);
          continue;
        }
        const auto s = static_cast<std::size_t>(f.next_child++);
        std::array<Vec3, 4> c;
        for (std::size_t k = 0; k < 4; ++k) {
          const auto& ev = t.vertex[s][k];
          c[k] = 0.5 * (f.x[ev[0]] + f.x[ev[1]]);
        }
        std::array<std::int8_t, 4> crf{-1, -1, -1, -1};
        for (std::size_t k = 0; k < 4; ++k) {
          const int pf = t.face_link[s][k].parent_face;
          if (pf >= 0) crf[k] = f.root_face[static_cast<std::size_t>(pf)];
        }
        const NodeRef child = f.node.child(static_cast<int>(s));
        const int finest = f.finest;
        // f.word stays readable for the rest of its children: its block is freed only when all
        // 8 children are erased (merge), which leaves the slots after the current one reading
        // kErased, and nothing is refined (no block reused) until the frame is done.
        const std::uint32_t cw = hierarchy.child_word(f.word, static_cast<int>(s));
        e = enter(hierarchy, child, cw, c, finest, crf, stats);  // may push (invalidates f)
      } else if (m_next_candidate < m_candidates.size()) {
        const std::uint32_t r = m_candidates[m_next_candidate++];
        const NodeRef root{r, 0, 0};
        e = enter(hierarchy, root, hierarchy.root_word(r), hierarchy.world_vertices(root), finest_level(hierarchy, r),
                  {0, 1, 2, 3}, stats);
      } else {
        break;  // this sphere is done
      }
      if (e == Enter::Abort) {
        aborted = true;
        break;
      }
    }
    if (aborted) {
      drop_all(hierarchy, stats);
      break;
    }
    m_active = false;
  }
  stats.nodes_visited = m_visits;
  return stats;
}

ErosionStats Eroder::erode(TetHierarchy& hierarchy, const Vec3& centre_mm, double radius_mm, double pressing_force_n,
                           double dt_s) {
  enqueue(centre_mm, radius_mm, pressing_force_n, dt_s);
  return run(hierarchy, m_options.max_node_visits);
}

}  // namespace ido::drill

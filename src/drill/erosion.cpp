// SPDX-License-Identifier: Apache-2.0
// Hand-written: the project's burr erosion on the tetrahedral hierarchy.
#include "ido/drill/erosion.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ido/core/error.h"

namespace ido::drill {
namespace {

// The face-plane part of sphere_misses_tet, for a tetrahedron whose bounding sphere the
// sphere reaches and whose centroid lies at squared distance d2 from c: true when c lies
// beyond one face plane by more than r. Compares squares (n·(c − a))² > r² |n|² on the
// outer side, so no square root or division per face.
bool beyond_a_face(const std::array<Vec3, 4>& x, const Vec3& c, double r2, double d2) {
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

// The bounding-sphere test of one sphere (c, r) on the tetrahedron with vertices a, b, e, f:
// the squared distance from c to the centroid and whether the sphere misses the vertices'
// bounding sphere about the centroid.
struct BoundingTest {
  double d2;
  bool beyond;
};
inline BoundingTest bounding_test(const Vec3& a, const Vec3& b, const Vec3& e, const Vec3& f, const Vec3& c, double r) {
  const Vec3 centroid = 0.25 * (a + b + e + f);
  double rad2 = 0.0;
  rad2 = std::max(rad2, (a - centroid).squaredNorm());
  rad2 = std::max(rad2, (b - centroid).squaredNorm());
  rad2 = std::max(rad2, (e - centroid).squaredNorm());
  rad2 = std::max(rad2, (f - centroid).squaredNorm());
  const double reach = r + std::sqrt(rad2);
  const double d2 = (c - centroid).squaredNorm();
  return {d2, d2 > reach * reach};
}

// The per-node tests of one sphere (c, r) on tetrahedron x, without the face planes:
// bounding_test() and which vertices lie in the sphere (`inside`, bit k for vertex k).
void node_tests(const std::array<Vec3, 4>& x, const Vec3& c, double r, bool& beyond, double& d2,
                std::uint8_t& inside) {
  const BoundingTest b = bounding_test(x[0], x[1], x[2], x[3], c, r);
  beyond = b.beyond;
  d2 = b.d2;
  const double r2 = r * r;
  inside = 0;
  for (std::size_t k = 0; k < 4; ++k)
    if ((x[k] - c).squaredNorm() <= r2) inside = static_cast<std::uint8_t>(inside | (1U << k));
}

// True when the sphere cannot touch the tetrahedron x, from its node_tests(): outside the
// vertices' bounding sphere, or (no vertex inside the sphere) beyond one face plane. A vertex
// inside the sphere lies on the inner side of every face plane, so the centre cannot be
// farther than r beyond any of them: the face planes are tested only without one.
bool sphere_misses(const std::array<Vec3, 4>& x, const Vec3& c, double r2, bool beyond, double d2,
                   std::uint8_t inside) {
  return beyond || (inside == 0 && beyond_a_face(x, c, r2, d2));
}

// The 10 points the children of a tetrahedron are made of, the vertices and edge midpoints
// (point pair_code(a, b) = 0.5 (x_a + x_b), so x_a itself for a = b), and for each child
// vertex the point it is. Tabulated once.
struct ChildPoints {
  std::array<std::array<std::uint8_t, 2>, 10> ends{};   // the point's parent vertices
  std::array<std::array<std::uint8_t, 4>, 8> point{};   // child slot, vertex → point
  ChildPoints() {
    const TreeTable& t = TreeTable::get();
    std::array<int, 16> index{};
    index.fill(-1);
    int n = 0;
    for (std::size_t s = 0; s < 8; ++s)
      for (std::size_t v = 0; v < 4; ++v) {
        const int a = t.vertex[s][v][0], b = t.vertex[s][v][1];
        const int code = a < b ? a * 4 + b : b * 4 + a;
        if (index[static_cast<std::size_t>(code)] < 0) {
          ends[static_cast<std::size_t>(n)] = {static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b)};
          index[static_cast<std::size_t>(code)] = n++;
        }
        point[s][v] = static_cast<std::uint8_t>(index[static_cast<std::size_t>(code)]);
      }
  }
};

const ChildPoints& child_points() {
  static const ChildPoints kPoints;
  return kPoints;
}

// The 8 children of a tetrahedron p and their node_tests() for the sphere (c, r), with the
// same arithmetic in the same order per child, but each of the 10 distinct child vertices
// (and its distance to c) computed once. Slots whose bit is set in @p skip (erased children)
// are left untested.
void make_children(const std::array<Vec3, 4>& p, const Vec3& c, double r, std::uint8_t skip,
                   detail::ErosionChildren& k) {
  const ChildPoints& cp = child_points();
  const double r2 = r * r;
  auto& q = k.point;
  unsigned in = 0;  // bit i: point i lies in the sphere
  for (std::size_t i = 0; i < 10; ++i) {
    q[i] = 0.5 * (p[cp.ends[i][0]] + p[cp.ends[i][1]]);
    if ((q[i] - c).squaredNorm() <= r2) in |= 1U << i;
  }
  for (std::size_t s = 0; s < 8; ++s) {
    if (((skip >> s) & 1U) != 0) continue;
    const auto& pt = cp.point[s];
    std::uint8_t inside = 0;
    for (std::size_t v = 0; v < 4; ++v) inside = static_cast<std::uint8_t>(inside | (((in >> pt[v]) & 1U) << v));
    const BoundingTest b = bounding_test(q[pt[0]], q[pt[1]], q[pt[2]], q[pt[3]], c, r);
    k.d2[s] = b.d2;
    k.beyond[s] = b.beyond;
    k.inside[s] = inside;
  }
}

// Vertices of child slot s of detail::ErosionChildren k.
std::array<Vec3, 4> child_vertices(const detail::ErosionChildren& k, std::size_t s) {
  const auto& pt = child_points().point[s];
  return {k.point[pt[0]], k.point[pt[1]], k.point[pt[2]], k.point[pt[3]]};
}

// True when erosion would remove anything below a partly covered full node of geometry x at
// depth `depth` < `finest` (finest level) without touching the tree: the same decisions as
// Eroder::enter on its children as full leaves, evaluated on derived geometry only, so a
// partly covered leaf is refined only when a descendant will actually go (no
// refine-then-undo). Adds the nodes it tests to `visits`. @p k receives x's children and
// their tests (make_children with nothing skipped): after the refinement they are the new
// frame's, all full.
// NOLINTNEXTLINE(misc-no-recursion): depth ≤ kMaxDepth
bool would_remove_below(const std::array<Vec3, 4>& x, int depth, int finest, const Vec3& c, double r,
                        std::size_t& visits, detail::ErosionChildren& k) {
  make_children(x, c, r, 0, k);
  const double r2 = r * r;
  for (std::size_t s = 0; s < 8; ++s) {
    ++visits;
    if (k.beyond[s]) continue;
    const std::array<Vec3, 4> ch = child_vertices(k, s);
    if (sphere_misses(ch, c, r2, false, k.d2[s], k.inside[s])) continue;
    if (k.inside[s] == 0xF) return true;  // entirely inside
    if (depth + 1 >= finest) {
      if (k.d2[s] <= r2) return true;  // the centroid is inside
      continue;
    }
    detail::ErosionChildren below;
    if (would_remove_below(ch, depth + 1, finest, c, r, visits, below)) return true;
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

// Bit s set when child word s is an erased leaf.
std::uint8_t erased_mask(const std::array<std::uint32_t, 8>& child) noexcept {
  unsigned m = 0;
  for (unsigned s = 0; s < 8; ++s) m |= (child[s] == TetHierarchy::kErased ? 1U : 0U) << s;
  return static_cast<std::uint8_t>(m);
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
                            bool beyond, double d2, std::uint8_t inside, int finest,
                            const std::array<std::int8_t, 4>& root_face, ErosionStats& stats) {
  ++m_visits;
  const NodeState st = TetHierarchy::state_of_word(word);
  if (st == NodeState::Erased) return Enter::Done;
  const double r2 = m_radius * m_radius;
  if (sphere_misses(x, m_centre, r2, beyond, d2, inside)) return Enter::Done;
  const bool all_inside = inside == 0xF;
  std::uint8_t face_mask = 0;
  for (const auto f : root_face)
    if (f >= 0) face_mask = static_cast<std::uint8_t>(face_mask | (1U << f));
  m_face_mask[node.depth] = face_mask;
  if (all_inside || node.depth >= finest) {
    if (!all_inside && d2 > r2) return Enter::Done;  // the centroid is outside
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
    // The frames below are the node's ancestors: their words give the path.
    m_frame_word[node.depth] = word;
    const NodeRef top = h.erase_on_path(node, m_frame_word);
    take_path_words(node);  // the erase rewrote the ancestors' words (masks, moved groups, merges)
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
    if (node.depth >= kMaxDepth) return Enter::Done;
    ++m_visits;  // the dry run's visit of the node itself (its tests are the ones above)
    // Its children's tests go where the frame pushed below keeps them (m_children at the
    // node's depth is free: the frame of the node's parent keeps its own one level up).
    if (!would_remove_below(x, node.depth, finest, m_centre, m_radius, m_visits, m_children[node.depth]))
      return Enter::Done;
    if (m_options.max_nodes > 0 && h.node_count() + 8 > m_options.max_nodes) {
      stats.node_limit_reached = true;  // the leaf stays whole (coarser than asked)
      return Enter::Done;
    }
    m_frame_word[node.depth] = word;
    if (!h.refine_on_path(node, m_frame_word)) return Enter::Done;
    take_path_words(node);  // the parent's word (mask → group) and its ancestors' may change
    word = m_frame_word[node.depth];
    refined_here = true;
    ++stats.nodes_refined;
    mark(node, face_mask);
  }
  m_stack.push_back(Frame{node, word, h.child_words(word), x, root_face, static_cast<std::int8_t>(finest), 0,
                          refined_here, face_mask});
  m_frame_word[node.depth] = word;
  // A node refined here has 8 full children, whose tests the dry run made.
  if (!refined_here) make_children(x, m_centre, m_radius, erased_mask(m_stack.back().child), m_children[node.depth]);
  return Enter::Pushed;
}

// Step 7, after the children (the frame is popped; the stack holds its ancestors): a
// refinement that removed nothing — 8 full leaf children — is undone.
void Eroder::leave(TetHierarchy& h, const Frame& f, ErosionStats& stats) {
  if (f.word != (TetHierarchy::kMaskBase | 0xFFU)) return;  // what coarsen() requires
  m_frame_word[f.node.depth] = f.word;
  if (h.coarsen_on_path(f.node, m_frame_word)) {
    if (f.refined_here) --stats.nodes_refined;
    mark(f.node, f.face_mask);
    take_path_words(f.node);
  }
}

// After a change of the tree at the node below the top frame (or the top frame's own node
// after its pop), m_frame_word holds the path's new words (TetHierarchy::*_on_path): a change
// rewrites only the words of the changed node and its ancestors (a mask bit, a group moved
// to its new size, a merge into an erased leaf), never another child's. Frame k is at depth
// k; its word and its child on the path are taken from m_frame_word. A frame whose node
// merged reads kErased, and so do all its children (they were erased: it merged).
void Eroder::take_path_words(const NodeRef& changed) noexcept {
  for (std::size_t k = 0; k < m_stack.size(); ++k) {
    Frame& f = m_stack[k];
    f.word = m_frame_word[k];
    if (f.word == TetHierarchy::kErased) {
      f.child.fill(TetHierarchy::kErased);
    } else {
      f.child[static_cast<std::size_t>(changed.slot(static_cast<int>(k) + 1))] = m_frame_word[k + 1];
    }
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
  const geometry::Aabb box{m_centre - Vec3::Constant(m_radius), m_centre + Vec3::Constant(m_radius)};
  hierarchy.root_hash().for_each_in_box(box, [&](std::int32_t r) {
    if (static_cast<std::size_t>(r) >= n) return;
    auto& s = m_stamp[static_cast<std::size_t>(r)];
    if (s == m_epoch) return;
    s = m_epoch;
    const auto& rb = hierarchy.root_box(static_cast<std::size_t>(r));
    if (!rb.overlaps(box)) return;
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
  m_have_last = false;  // the positions were not finished: a repeat is new work
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
  // A resting burr: the same sphere again removes nothing once the last one is processed.
  if (m_have_last && m_last.radius == radius_mm &&
      (m_last.centre - centre_mm).norm() <= kRepeatTolerance * radius_mm)
    return;
  m_last = s;
  m_have_last = true;
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
      f.child = hierarchy.child_words(w);
    }
    m_stack.resize(keep);
    for (auto& f : m_stack) {
      f.x = hierarchy.world_vertices(f.node);
      m_face_mask[f.node.depth] = f.face_mask;
      m_frame_word[f.node.depth] = f.word;
      make_children(f.x, m_centre, m_radius, erased_mask(f.child), m_children[f.node.depth]);
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
        const detail::ErosionChildren& kids = m_children[f.node.depth];
        // f.child is current: every change of the tree updates the frames' words
        // (take_path_words); after a merge of f's node they read kErased, as in the tree.
        const std::uint32_t cw = f.child[s];
        if (cw == TetHierarchy::kErased || kids.beyond[s]) {
          ++m_visits;  // what enter() does for an erased child or one the sphere misses
          continue;
        }
        std::array<std::int8_t, 4> crf{-1, -1, -1, -1};
        for (std::size_t k = 0; k < 4; ++k) {
          const int pf = t.face_link[s][k].parent_face;
          if (pf >= 0) crf[k] = f.root_face[static_cast<std::size_t>(pf)];
        }
        const NodeRef child = f.node.child(static_cast<int>(s));
        const int finest = f.finest;
        // May push (invalidates f; overwrites only the next depth's children, not kids).
        e = enter(hierarchy, child, cw, child_vertices(kids, s), false, kids.d2[s], kids.inside[s], finest, crf, stats);
      } else if (m_next_candidate < m_candidates.size()) {
        const std::uint32_t r = m_candidates[m_next_candidate++];
        const NodeRef root{r, 0, 0};
        const std::array<Vec3, 4> x = hierarchy.world_vertices(root);
        bool beyond = false;
        double d2 = 0.0;
        std::uint8_t inside = 0;
        node_tests(x, m_centre, m_radius, beyond, d2, inside);
        e = enter(hierarchy, root, hierarchy.root_word(r), x, beyond, d2, inside, finest_level(hierarchy, r), {0, 1, 2, 3},
                  stats);
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

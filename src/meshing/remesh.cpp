// SPDX-License-Identifier: Apache-2.0
// Isotropic surface remeshing by local operations, after Botsch & Kobbelt (SGP 2004).
// Written by hand for ido: an indexed triangle list with vertex→triangle incidence lists,
// which is all split / collapse / flip need on a closed manifold.
#include "ido/meshing/remesh.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <string>

#include "ido/core/error.h"

namespace ido::meshing {

namespace {

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

Vec3 tri_normal(const Vec3& a, const Vec3& b, const Vec3& c) { return (b - a).cross(c - a); }

// The edge queues of split and collapse: a batch known up front (every edge past the bound)
// and a trickle pushed later (the edges an operation created). The batch is sorted once and
// read in order, only the trickle goes through a binary heap: a heap over the whole batch
// spent most of the collapse pass sifting tens of thousands of entries through cache misses.
// Items come out in the order of Before exactly as from one std::priority_queue holding
// everything (equal items cannot be told apart, so which copy comes first does not matter).
template <class Item, class Before>
class EdgeQueue {
 public:
  explicit EdgeQueue(std::vector<Item> batch) : m_batch(std::move(batch)) {
    std::sort(m_batch.begin(), m_batch.end(), Before{});
  }
  [[nodiscard]] bool empty() const { return m_next == m_batch.size() && m_heap.empty(); }
  void push(const Item& item) {
    m_heap.push_back(item);
    std::push_heap(m_heap.begin(), m_heap.end(), After{});
  }
  /// Removes and returns the first item. Precondition: !empty().
  Item pop() {
    if (!m_heap.empty() && (m_next == m_batch.size() || Before{}(m_heap.front(), m_batch[m_next]))) {
      std::pop_heap(m_heap.begin(), m_heap.end(), After{});
      const Item item = m_heap.back();
      m_heap.pop_back();
      return item;
    }
    return m_batch[m_next++];
  }

 private:
  // The heap keeps its first item (by Before) at the front.
  struct After {
    bool operator()(const Item& x, const Item& y) const { return Before{}(y, x); }
  };
  std::vector<Item> m_batch;
  std::size_t m_next = 0;
  std::vector<Item> m_heap;
};

using EdgeItem = std::pair<double, std::uint64_t>;  // squared length (mm²), edge_key

}  // namespace

struct SurfaceRemesher::Impl {
  // Triangles holding both a and b (at most a few on a manifold: exactly 2).
  static int edge_triangles(const SurfaceRemesher& r, std::int32_t a, std::int32_t b,
                            std::int32_t out[2]) {
    int n = 0;
    for (std::int32_t t : r.m_vertex_triangles[a]) {
      const Tri& tr = r.m_triangles[t];
      if (tr[0] == b || tr[1] == b || tr[2] == b) {
        if (n < 2) out[n] = t;
        ++n;
      }
    }
    return n;
  }
  // Calls f(t) for every alive triangle that can hold an active edge, in increasing order: all
  // of them without active flags, else those with an active corner (an active edge has an
  // active end, so both its triangles are among them). Where few vertices are active (the
  // balloon's settled surface) this is far fewer than a scan of every triangle, and the passes
  // below see the same triangles in the same order as that scan would, minus ones it skips.
  template <class F>
  static void for_each_candidate_triangle(const SurfaceRemesher& r, F&& f) {
    const std::size_t nt = r.m_triangles.size();
    std::size_t active = 0;
    if (!r.m_active.empty())
      for (std::size_t v = 0; v < r.m_active.size(); ++v) active += r.m_active[v] && r.m_vertex_alive[v] ? 1 : 0;
    if (r.m_active.empty() || 8 * active > std::size_t(r.m_alive_vertices)) {
      for (std::size_t t = 0; t < nt; ++t)
        if (r.m_triangle_alive[t]) f(static_cast<std::int32_t>(t));
      return;
    }
    std::vector<std::int32_t> ts;
    ts.reserve(7 * active);
    for (std::size_t v = 0; v < r.m_active.size(); ++v)
      if (r.m_active[v] && r.m_vertex_alive[v]) ts.insert(ts.end(), r.m_vertex_triangles[v].begin(), r.m_vertex_triangles[v].end());
    std::sort(ts.begin(), ts.end());
    ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
    for (std::int32_t t : ts)
      if (r.m_triangle_alive[std::size_t(t)]) f(t);
  }
  // Whether the edge a-b takes part (see set_active).
  static bool edge_active(const SurfaceRemesher& r, std::int32_t a, std::int32_t b) {
    return r.m_active.empty() || r.m_active[std::size_t(a)] || r.m_active[std::size_t(b)];
  }
  // Vertex of triangle t that is neither a nor b.
  static std::int32_t opposite(const Tri& t, std::int32_t a, std::int32_t b) {
    for (std::int32_t v : t)
      if (v != a && v != b) return v;
    return -1;
  }
  // True when triangle t runs a→b (in its cyclic order).
  static bool runs(const Tri& t, std::int32_t a, std::int32_t b) {
    for (int k = 0; k < 3; ++k)
      if (t[k] == a && t[(k + 1) % 3] == b) return true;
    return false;
  }
  // The neighbours of v in increasing order. On a closed oriented manifold (which every
  // operation here keeps) each neighbour follows v in exactly one of its triangles.
  static void neighbours(const SurfaceRemesher& r, std::int32_t v, std::vector<std::int32_t>& out) {
    out.clear();
    for (std::int32_t t : r.m_vertex_triangles[v]) {
      const Tri& tr = r.m_triangles[t];
      out.push_back(tr[0] == v ? tr[1] : tr[1] == v ? tr[2] : tr[0]);
    }
    std::sort(out.begin(), out.end());
  }
  static std::int32_t add_triangle(SurfaceRemesher& r, const Tri& t) {
    const auto id = static_cast<std::int32_t>(r.m_triangles.size());
    r.m_triangles.push_back(t);
    r.m_triangle_alive.push_back(1);
    for (std::int32_t v : t) r.m_vertex_triangles.push_back(std::size_t(v), id);
    return id;
  }
  static void replace_in_triangle(SurfaceRemesher& r, std::int32_t t, std::int32_t from,
                                  std::int32_t to) {
    Tri& tr = r.m_triangles[t];
    for (auto& v : tr)
      if (v == from) v = to;
    r.m_vertex_triangles.remove(std::size_t(from), t);
    r.m_vertex_triangles.push_back(std::size_t(to), t);
  }
  static std::int32_t add_vertex(SurfaceRemesher& r, const Vec3& p, std::uint8_t locked) {
    const auto id = static_cast<std::int32_t>(r.m_vertices.size());
    r.m_vertices.push_back(p);
    r.m_vertex_alive.push_back(1);
    r.m_locked.push_back(locked);
    r.m_vertex_triangles.add_list();
    r.m_moved.push_back(1);
    r.m_touched.push_back(1);
    if (!r.m_active.empty()) r.m_active.push_back(1);
    ++r.m_alive_vertices;
    return id;
  }
};

SurfaceRemesher::SurfaceRemesher(const geometry::TriangleMesh& mesh, std::vector<std::uint8_t> locked)
    : m_vertices(mesh.vertices), m_triangles(mesh.triangles) {
  const auto nv = static_cast<std::int64_t>(m_vertices.size());
  if (!locked.empty() && static_cast<std::int64_t>(locked.size()) != nv)
    throw InvalidInput("remesh: locked flags must be empty or one per vertex (" +
                       std::to_string(nv) + "), got " + std::to_string(locked.size()));
  m_locked = locked.empty() ? std::vector<std::uint8_t>(m_vertices.size(), 0) : std::move(locked);
  m_vertex_alive.assign(m_vertices.size(), 1);
  m_moved.assign(m_vertices.size(), 0);
  m_touched.assign(m_vertices.size(), 0);
  m_input_vertices = m_vertices.size();
  m_triangle_alive.assign(m_triangles.size(), 1);
  m_vertex_triangles.assign(m_vertices.size());
  m_alive_vertices = nv;
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Tri& tr = m_triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tr[k] < 0 || tr[k] >= nv)
        throw InvalidInput("remesh: triangle " + std::to_string(t) + " has a vertex index out of range");
      m_vertex_triangles.push_back(std::size_t(tr[k]), static_cast<std::int32_t>(t));
    }
    if (tr[0] == tr[1] || tr[1] == tr[2] || tr[0] == tr[2])
      throw InvalidInput("remesh: triangle " + std::to_string(t) + " repeats a vertex");
  }
  // A closed, consistently oriented manifold edge runs once each way: around every vertex a,
  // each a→b of its triangles occurs once, and so does b→a. That is: the outgoing ends are
  // distinct and the incoming ends are the same set. Tested in one pass over each list with
  // per-vertex stamps (`out_mark` on an outgoing end, `in_mark` once an incoming end has
  // matched it); the message is then built by the pairwise test below, which names the first
  // failing outgoing end.
  std::vector<std::int32_t> outgoing, incoming;
  std::vector<std::uint64_t> mark(m_vertices.size(), 0);
  for (std::int32_t a = 0; a < static_cast<std::int32_t>(nv); ++a) {
    outgoing.clear();
    incoming.clear();
    for (std::int32_t t : m_vertex_triangles[std::size_t(a)]) {
      const Tri& tr = m_triangles[std::size_t(t)];
      const int k = tr[0] == a ? 0 : tr[1] == a ? 1 : 2;
      outgoing.push_back(tr[(k + 1) % 3]);
      incoming.push_back(tr[(k + 2) % 3]);
    }
    const std::uint64_t out_mark = 2 * std::uint64_t(a) + 1, in_mark = out_mark + 1;
    bool ok = true;
    for (std::int32_t b : outgoing) {
      if (mark[std::size_t(b)] == out_mark) ok = false;
      mark[std::size_t(b)] = out_mark;
    }
    for (std::int32_t c : incoming) {
      if (mark[std::size_t(c)] != out_mark) ok = false;
      mark[std::size_t(c)] = in_mark;
    }
    if (ok) continue;
    for (std::int32_t b : outgoing)
      if (std::count(outgoing.begin(), outgoing.end(), b) != 1 || std::count(incoming.begin(), incoming.end(), b) != 1)
        throw InvalidInput("remesh: the mesh is not a closed, consistently oriented 2-manifold (edge " +
                           std::to_string(std::min(a, b)) + "-" + std::to_string(std::max(a, b)) + ")");
    throw InvalidInput("remesh: the mesh is not a closed, consistently oriented 2-manifold (at vertex " +
                       std::to_string(a) + ")");
  }
}

void SurfaceRemesher::set_active(std::vector<std::uint8_t> active) {
  if (!active.empty() && active.size() != m_vertices.size())
    throw InvalidInput("remesh: active flags must be empty or one per vertex (" + std::to_string(m_vertices.size()) +
                       "), got " + std::to_string(active.size()));
  m_active = std::move(active);
}

std::int64_t SurfaceRemesher::split_long_edges(double max_length_mm) {
  const double max2 = max_length_mm * max_length_mm;
  // Each edge of triangle t with a < b (once per triangle pair: the twin has a > b) that is
  // longer than the bound.
  auto edges_of = [&](std::int32_t t, auto&& take) {
    const Tri& tr = m_triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tr[k], b = tr[(k + 1) % 3];
      if (a > b || !Impl::edge_active(*this, a, b)) continue;
      const double l2 = (m_vertices[a] - m_vertices[b]).squaredNorm();
      if (l2 > max2) take(EdgeItem{l2, edge_key(a, b)});
    }
  };
  std::vector<EdgeItem> batch;
  Impl::for_each_candidate_triangle(*this, [&](std::int32_t t) { edges_of(t, [&](const EdgeItem& e) { batch.push_back(e); }); });
  EdgeQueue<EdgeItem, std::greater<>> queue(std::move(batch));  // longest first
  std::int64_t count = 0;
  while (!queue.empty()) {
    const auto [l2, key] = queue.pop();
    const auto a = static_cast<std::int32_t>(key >> 32);
    const auto b = static_cast<std::int32_t>(key & 0xffffffffu);
    if (!m_vertex_alive[a] || !m_vertex_alive[b]) continue;
    if (std::abs((m_vertices[a] - m_vertices[b]).squaredNorm() - l2) > 1e-12 * l2) continue;
    std::int32_t ts[2];
    if (Impl::edge_triangles(*this, a, b, ts) != 2) continue;
    // Orient: t1 runs a→b, t2 runs b→a.
    std::int32_t t1 = ts[0], t2 = ts[1];
    if (!Impl::runs(m_triangles[t1], a, b)) std::swap(t1, t2);
    const std::int32_t c = Impl::opposite(m_triangles[t1], a, b);
    const std::int32_t d = Impl::opposite(m_triangles[t2], a, b);
    for (std::int32_t w : {a, b, c, d}) m_touched[std::size_t(w)] = 1;
    const std::int32_t m = Impl::add_vertex(*this, 0.5 * (m_vertices[a] + m_vertices[b]),
                                            std::uint8_t(m_locked[a] && m_locked[b]));
    // t1 (a,b,c) → (a,m,c) + (m,b,c); t2 (b,a,d) → (b,m,d) + (m,a,d).
    Impl::replace_in_triangle(*this, t1, b, m);
    const std::int32_t n1 = Impl::add_triangle(*this, Tri{m, b, c});
    Impl::replace_in_triangle(*this, t2, a, m);
    const std::int32_t n2 = Impl::add_triangle(*this, Tri{m, a, d});
    // Every long edge of the four triangles, active or not and whichever way it runs: the
    // new ones, and old ones next to the split. An inactive long edge left out would be met
    // again by each split near it: the edges from its far corner to the new vertices stay
    // about as long as it is, and the splits would never end. An edge already queued comes
    // out twice and the second time is no longer an edge.
    for (std::int32_t t : {t1, t2, n1, n2}) {
      const Tri& tr = m_triangles[t];
      for (int k = 0; k < 3; ++k) {
        const std::int32_t u = tr[k], w = tr[(k + 1) % 3];
        const double e2 = (m_vertices[u] - m_vertices[w]).squaredNorm();
        if (e2 > max2) queue.push(EdgeItem{e2, edge_key(u, w)});
      }
    }
    ++count;
  }
  return count;
}

std::int64_t SurfaceRemesher::collapse_short_edges(double min_length_mm, double max_length_mm) {
  const double min2 = min_length_mm * min_length_mm;
  const double max2 = max_length_mm * max_length_mm;
  std::vector<EdgeItem> batch;
  Impl::for_each_candidate_triangle(*this, [&](std::int32_t t) {
    const Tri& tr = m_triangles[std::size_t(t)];
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tr[k], b = tr[(k + 1) % 3];
      if (a > b || !Impl::edge_active(*this, a, b)) continue;
      const double l2 = (m_vertices[a] - m_vertices[b]).squaredNorm();
      if (l2 < min2) batch.emplace_back(l2, edge_key(a, b));
    }
  });
  EdgeQueue<EdgeItem, std::less<>> queue(std::move(batch));  // shortest first
  std::int64_t count = 0;
  // The tests below decide exactly as the textbook formulation (sorted neighbour lists, their
  // intersection, the neighbour count of each common vertex) but without building those lists:
  // on a closed edge-manifold mesh, which every operation here preserves, a vertex has as many
  // distinct neighbours as incident triangles, and a neighbour met twice (once in each of the
  // two triangles of the shared edge) is told apart by a per-vertex stamp.
  std::vector<std::uint32_t> mark(m_vertices.size(), 0);
  std::uint32_t stamp = 0;
  std::vector<std::int32_t> moved;
  while (!queue.empty() && m_alive_vertices > 4) {
    const auto [l2, key] = queue.pop();
    std::int32_t a = static_cast<std::int32_t>(key >> 32);
    std::int32_t b = static_cast<std::int32_t>(key & 0xffffffffu);
    if (!m_vertex_alive[a] || !m_vertex_alive[b]) continue;
    const double cur2 = (m_vertices[a] - m_vertices[b]).squaredNorm();
    if (cur2 >= min2) continue;
    if (m_locked[a] && m_locked[b]) continue;
    // Keep b; a disappears. A locked end stays where it is.
    if (m_locked[a]) std::swap(a, b);
    const Vec3 target = m_locked[b] ? m_vertices[b] : 0.5 * (m_vertices[a] + m_vertices[b]);
    // One pass over each end's triangles makes two tests, both of which must pass (their order
    // does not change the decision). No edge left longer than max: every neighbour of either
    // end, other than the ends (the test that fails most, so each pass stops at its first
    // failure). Link condition: the endpoints' common neighbours are exactly the two opposite
    // vertices. Neighbours of a get `in_a`; a neighbour of b holding it is common and is moved on
    // to `counted`, so that its second occurrence around b is not counted again. The pass over
    // a's triangles also finds the edge's own two (those holding b).
    const std::uint32_t in_a = stamp + 1, counted = stamp + 2;
    stamp += 2;
    bool ok = true;
    std::int32_t ts[2];
    int n_edge = 0;
    for (std::int32_t t : m_vertex_triangles[a]) {
      for (std::int32_t w : m_triangles[t]) {
        if (w == a) continue;
        mark[w] = in_a;
        if (w == b) {
          if (n_edge < 2) ts[n_edge] = t;
          ++n_edge;
        } else if ((m_vertices[w] - target).squaredNorm() > max2) {
          ok = false;
        }
      }
      if (!ok) break;
    }
    if (!ok || n_edge != 2) continue;
    std::int32_t common[2];
    int n_common = 0;
    for (std::int32_t t : m_vertex_triangles[b]) {
      for (std::int32_t w : m_triangles[t]) {
        if (w == b) continue;
        if (mark[w] == in_a) {
          mark[w] = counted;
          if (n_common < 2) common[n_common] = w;
          ++n_common;
        }
        if (w != a && (m_vertices[w] - target).squaredNorm() > max2) ok = false;
      }
      if (!ok) break;
    }
    if (!ok || n_common != 2) continue;
    // No surviving triangle may turn over or become needle-thin.
    for (std::int32_t v : {a, b}) {
      for (std::int32_t t : m_vertex_triangles[v]) {
        if (t == ts[0] || t == ts[1]) continue;
        const Tri& tr = m_triangles[t];
        Vec3 p[3], q[3];
        for (int k = 0; k < 3; ++k) {
          p[k] = m_vertices[tr[k]];
          q[k] = (tr[k] == a || tr[k] == b) ? target : p[k];
        }
        const Vec3 n0 = tri_normal(p[0], p[1], p[2]);
        const Vec3 n1 = tri_normal(q[0], q[1], q[2]);
        if (n0.dot(n1) <= 0.2 * n0.norm() * n1.norm() || n1.norm() < 1e-12) {
          ok = false;
          break;
        }
      }
      if (!ok) break;
    }
    if (!ok) continue;
    // Valence guard: the two opposite vertices lose one neighbour each; keep them ≥ 3
    // (neighbour count = incident triangle count, see above).
    if (m_vertex_triangles[common[0]].size() <= 3 || m_vertex_triangles[common[1]].size() <= 3) continue;
    // Perform: delete the two triangles of the edge, move a's others onto b.
    for (std::int32_t t : {ts[0], ts[1]}) {
      m_triangle_alive[t] = 0;
      for (std::int32_t v : m_triangles[t]) m_vertex_triangles.remove(std::size_t(v), t);
    }
    moved.assign(m_vertex_triangles[a].begin(), m_vertex_triangles[a].end());
    for (std::int32_t t : moved) Impl::replace_in_triangle(*this, t, a, b);
    if (target != m_vertices[b]) m_moved[std::size_t(b)] = 1;
    for (std::int32_t w : {b, common[0], common[1]}) m_touched[std::size_t(w)] = 1;
    m_vertices[b] = target;
    if (!m_active.empty()) m_active[std::size_t(b)] = 1;
    m_vertex_alive[a] = 0;
    m_vertex_triangles.clear(std::size_t(a));
    --m_alive_vertices;
    ++count;
    // b's edges that are now short, each once (the queue's order depends only on its
    // contents, not on the order of insertion).
    const std::uint32_t pushed = ++stamp;
    for (std::int32_t t : m_vertex_triangles[b])
      for (std::int32_t w : m_triangles[t]) {
        if (w == b || mark[w] == pushed) continue;
        mark[w] = pushed;
        const double e2 = (m_vertices[w] - m_vertices[b]).squaredNorm();
        if (e2 < min2) queue.push(EdgeItem{e2, edge_key(w, b)});
      }
  }
  return count;
}

std::int64_t SurfaceRemesher::flip_edges() {
  std::int64_t count = 0;
  // Valences in one flat array (kept up to date by each flip): the scan below reads two per
  // edge, and the incidence lists' sizes are scattered over the heap.
  std::vector<std::int32_t> valences(m_vertices.size());
  for (std::size_t v = 0; v < valences.size(); ++v) valences[v] = static_cast<std::int32_t>(m_vertex_triangles[v].size());
  auto valence = [&](std::int32_t v) { return static_cast<int>(valences[std::size_t(v)]); };
  Impl::for_each_candidate_triangle(*this, [&](std::int32_t t0) {
    for (int k = 0; k < 3; ++k) {
      const Tri tr = m_triangles[std::size_t(t0)];
      const std::int32_t a = tr[k], b = tr[(k + 1) % 3];
      if (a > b) continue;
      // The valence test below changes each of the four |v − 6| terms by ±1 and needs a net
      // fall of at least 2, so at least one end of the edge must have valence ≥ 7: skip the
      // lookups otherwise (the same decision, made earlier).
      if ((valence(a) < 7 && valence(b) < 7) || !Impl::edge_active(*this, a, b)) continue;
      std::int32_t ts[2];
      if (Impl::edge_triangles(*this, a, b, ts) != 2) continue;
      std::int32_t t1 = ts[0], t2 = ts[1];
      if (!Impl::runs(m_triangles[t1], a, b)) std::swap(t1, t2);
      const std::int32_t c = Impl::opposite(m_triangles[t1], a, b);
      const std::int32_t d = Impl::opposite(m_triangles[t2], a, b);
      if (c == d) continue;
      const int va = valence(a), vb = valence(b), vc = valence(c), vd = valence(d);
      if (va <= 3 || vb <= 3) continue;
      const int before = std::abs(va - 6) + std::abs(vb - 6) + std::abs(vc - 6) + std::abs(vd - 6);
      const int after =
          std::abs(va - 7) + std::abs(vb - 7) + std::abs(vc - 5) + std::abs(vd - 5);
      if (after >= before) continue;
      // The new edge c-d must not exist.
      bool exists = false;
      for (std::int32_t t : m_vertex_triangles[c]) {
        const Tri& x = m_triangles[t];
        if (x[0] == d || x[1] == d || x[2] == d) exists = true;
      }
      if (exists) continue;
      // New triangles (a,d,c) and (d,b,c) must face the way the old pair faced.
      const Vec3 &pa = m_vertices[a], &pb = m_vertices[b], &pc = m_vertices[c], &pd = m_vertices[d];
      const Vec3 o1 = tri_normal(pa, pb, pc), o2 = tri_normal(pb, pa, pd);
      const Vec3 n1 = tri_normal(pa, pd, pc), n2 = tri_normal(pd, pb, pc);
      const double l1 = n1.norm(), l2 = n2.norm();
      if (l1 < 1e-12 || l2 < 1e-12) continue;
      // Reject folds: new normals must agree with each other and with the old ones.
      if (n1.dot(n2) <= 0.5 * l1 * l2) continue;
      const Vec3 old = o1.normalized() + o2.normalized();
      if (n1.dot(old) <= 0.0 || n2.dot(old) <= 0.0) continue;
      // Flip in place: t1 (a,b,c) → (a,d,c); t2 (b,a,d) → (d,b,c).
      Impl::replace_in_triangle(*this, t1, b, d);  // (a,d,c)
      Impl::replace_in_triangle(*this, t2, a, c);  // (b,c,d) ≡ (d,b,c)
      for (std::int32_t w : {a, b, c, d}) m_touched[std::size_t(w)] = 1;
      --valences[std::size_t(a)];
      --valences[std::size_t(b)];
      ++valences[std::size_t(c)];
      ++valences[std::size_t(d)];
      ++count;
    }
  });
  return count;
}

void SurfaceRemesher::relax_tangentially(double weight) {
  const std::size_t nv = m_vertices.size();
  std::vector<Vec3> next = m_vertices;
  std::vector<std::int32_t> nb;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m_vertex_alive[v] || m_locked[v] || m_vertex_triangles[v].empty() || (!m_active.empty() && !m_active[v]))
      continue;
    Vec3 normal = Vec3::Zero();
    for (std::int32_t t : m_vertex_triangles[v]) {
      const Tri& tr = m_triangles[t];
      normal += tri_normal(m_vertices[tr[0]], m_vertices[tr[1]], m_vertices[tr[2]]);
    }
    const double ln = normal.norm();
    if (ln < 1e-300) continue;
    normal /= ln;
    Impl::neighbours(*this, static_cast<std::int32_t>(v), nb);
    Vec3 centroid = Vec3::Zero();
    for (std::int32_t w : nb) centroid += m_vertices[w];
    centroid /= double(nb.size());
    Vec3 step = centroid - m_vertices[v];
    step -= normal * normal.dot(step);
    next[v] = m_vertices[v] + weight * step;
    if (next[v] != m_vertices[v]) m_moved[v] = m_touched[v] = 1;
  }
  m_vertices = std::move(next);
}

RemeshStats SurfaceRemesher::remesh(const RemeshOptions& options) {
  if (!(options.target_edge_mm > 0.0) || !std::isfinite(options.target_edge_mm))
    throw InvalidInput("remesh: target_edge_mm must be positive");
  RemeshStats stats;
  const double hi = options.split_ratio * options.target_edge_mm;
  const double lo = options.collapse_ratio * options.target_edge_mm;
  for (int it = 0; it < options.iterations; ++it) {
    stats.splits += split_long_edges(hi);
    stats.collapses += collapse_short_edges(lo, hi);
    if (options.flip) stats.flips += flip_edges();
    if (options.relax) relax_tangentially(options.relax_weight);
  }
  // Relaxation may stretch a few edges past the bound: a last split pass restores it.
  if (options.relax && options.iterations > 0) stats.splits += split_long_edges(hi);
  return stats;
}

geometry::TriangleMesh SurfaceRemesher::mesh() const {
  geometry::TriangleMesh out;
  std::vector<std::int32_t> remap(m_vertices.size(), -1);
  for (std::size_t v = 0; v < m_vertices.size(); ++v) {
    if (!m_vertex_alive[v] || m_vertex_triangles[v].empty()) continue;
    remap[v] = static_cast<std::int32_t>(out.vertices.size());
    out.vertices.push_back(m_vertices[v]);
  }
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    if (!m_triangle_alive[t]) continue;
    const Tri& tr = m_triangles[t];
    out.triangles.push_back(Tri{remap[tr[0]], remap[tr[1]], remap[tr[2]]});
  }
  return out;
}

std::vector<std::int32_t> SurfaceRemesher::input_index() const {
  std::vector<std::int32_t> out;
  for (std::size_t v = 0; v < m_vertices.size(); ++v)
    if (m_vertex_alive[v] && !m_vertex_triangles[v].empty())
      out.push_back(v < m_input_vertices && !m_moved[v] ? static_cast<std::int32_t>(v) : -1);
  return out;
}

std::vector<std::uint8_t> SurfaceRemesher::touched() const {
  std::vector<std::uint8_t> out;
  for (std::size_t v = 0; v < m_vertices.size(); ++v)
    if (m_vertex_alive[v] && !m_vertex_triangles[v].empty()) out.push_back(m_touched[v]);
  return out;
}

std::vector<std::uint8_t> SurfaceRemesher::locked() const {
  std::vector<std::uint8_t> out;
  for (std::size_t v = 0; v < m_vertices.size(); ++v)
    if (m_vertex_alive[v] && !m_vertex_triangles[v].empty()) out.push_back(m_locked[v]);
  return out;
}

geometry::TriangleMesh remesh(const geometry::TriangleMesh& mesh, const RemeshOptions& options) {
  SurfaceRemesher r(mesh);
  r.remesh(options);
  return r.mesh();
}

}  // namespace ido::meshing

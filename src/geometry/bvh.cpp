// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/bvh.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <numeric>

#include "bvh_build.h"
#include "ido/core/parallel.h"
#include "ido/geometry/distance.h"
#include "ido/geometry/mesh_topology.h"

namespace ido::geometry {

namespace detail {

namespace {

/// Spreads the low 10 bits of x so that there are two zero bits between each.
std::uint32_t spread_bits(std::uint32_t x) {
  x &= 0x3ffu;
  x = (x | (x << 16)) & 0x030000ffu;
  x = (x | (x << 8)) & 0x0300f00fu;
  x = (x | (x << 4)) & 0x030c30c3u;
  x = (x | (x << 2)) & 0x09249249u;
  return x;
}

}  // namespace

BvhTree build_bvh(const std::vector<Aabb>& boxes, const std::vector<Vec3>& centroids,
                  int leaf_size) {
  // Items are ordered along a Morton (Z-order) curve of their centroids, then the ordered
  // range is halved recursively; boxes are filled bottom-up. O(n log n) for the sort, O(n)
  // for the rest (the "linear BVH" idea of Lauterbach et al. 2009, simplified).
  BvhTree tree;
  const auto n = static_cast<std::int32_t>(boxes.size());
  if (n == 0) return tree;
  leaf_size = std::max(leaf_size, 1);
  Aabb cbox;
  for (const Vec3& c : centroids) cbox.extend(c);
  const Vec3 lo = cbox.min;
  const Vec3 ext = cbox.extent();
  std::vector<std::uint64_t> keys(static_cast<std::size_t>(n));
  for (std::int32_t i = 0; i < n; ++i) {
    std::uint32_t code = 0;
    for (int k = 0; k < 3; ++k) {
      const double t = ext[k] > 0.0 ? (centroids[static_cast<std::size_t>(i)][k] - lo[k]) / ext[k] : 0.0;
      const auto q = static_cast<std::uint32_t>(std::clamp(t * 1023.0, 0.0, 1023.0));
      code |= spread_bits(q) << k;
    }
    keys[static_cast<std::size_t>(i)] = (static_cast<std::uint64_t>(code) << 32) | static_cast<std::uint32_t>(i);
  }
  std::sort(keys.begin(), keys.end());
  tree.order.resize(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < keys.size(); ++i) tree.order[i] = static_cast<std::int32_t>(keys[i] & 0xffffffffu);

  tree.nodes.reserve(static_cast<std::size_t>(2 * n / leaf_size + 2));
  tree.nodes.push_back({});
  std::vector<std::pair<std::int32_t, std::int32_t>> ranges{{0, n}};  // per node
  for (std::size_t i = 0; i < tree.nodes.size(); ++i) {  // breadth-first creation
    const auto [begin, end] = ranges[i];
    if (end - begin <= leaf_size) {
      tree.nodes[i].first = begin;
      tree.nodes[i].count = end - begin;
      continue;
    }
    const std::int32_t mid = begin + (end - begin) / 2;
    tree.nodes[i].first = static_cast<std::int32_t>(tree.nodes.size());
    tree.nodes[i].count = 0;
    tree.nodes.push_back({});
    tree.nodes.push_back({});
    ranges.emplace_back(begin, mid);
    ranges.emplace_back(mid, end);
  }
  for (std::size_t i = tree.nodes.size(); i-- > 0;) {  // children come after their parent
    BvhNode& node = tree.nodes[i];
    if (node.leaf()) {
      for (std::int32_t s = node.first; s < node.first + node.count; ++s) {
        node.box.extend(boxes[static_cast<std::size_t>(tree.order[static_cast<std::size_t>(s)])]);
      }
    } else {
      node.box = tree.nodes[static_cast<std::size_t>(node.first)].box;
      node.box.extend(tree.nodes[static_cast<std::size_t>(node.first + 1)].box);
    }
  }
  return tree;
}

BvhTree build_triangle_bvh(const TriangleMesh& mesh, int leaf_size) {
  const std::size_t nt = mesh.triangles.size();
  std::vector<Aabb> boxes(nt);
  std::vector<Vec3> centroids(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const Tri& tri = mesh.triangles[t];
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(tri[0])];
    const Vec3& b = mesh.vertices[static_cast<std::size_t>(tri[1])];
    const Vec3& c = mesh.vertices[static_cast<std::size_t>(tri[2])];
    boxes[t] = Aabb::of_triangle(a, b, c);
    centroids[t] = (a + b + c) / 3.0;
  }
  return build_bvh(boxes, centroids, leaf_size);
}

}  // namespace detail

TriangleBvh::TriangleBvh(const TriangleMesh& mesh, int leaf_size) {
  validate_mesh(mesh);
  const std::size_t nt = mesh.triangles.size();
  detail::BvhTree tree = detail::build_triangle_bvh(mesh, leaf_size);
  m_nodes.reserve(tree.nodes.size());
  for (const auto& n : tree.nodes) m_nodes.push_back({n.box, n.first, n.count});
  m_triangle_id = std::move(tree.order);
  m_slot.resize(nt);
  m_corners.resize(nt);
  m_boxes.resize(nt);
  for (std::size_t s = 0; s < nt; ++s) {
    const auto t = static_cast<std::size_t>(m_triangle_id[s]);
    m_slot[t] = static_cast<std::int32_t>(s);
    const Tri& tri = mesh.triangles[t];
    m_corners[s] = {mesh.vertices[static_cast<std::size_t>(tri[0])],
                    mesh.vertices[static_cast<std::size_t>(tri[1])],
                    mesh.vertices[static_cast<std::size_t>(tri[2])]};
    m_boxes[s] = Aabb::of_triangle(m_corners[s][0], m_corners[s][1], m_corners[s][2]);
  }
}

Aabb TriangleBvh::bounds() const { return m_nodes.empty() ? Aabb{} : m_nodes[0].box; }

const std::array<Vec3, 3>& TriangleBvh::corners(std::int32_t id) const {
  return m_corners[static_cast<std::size_t>(m_slot[static_cast<std::size_t>(id)])];
}

ClosestPoint TriangleBvh::closest_point(const Vec3& p) const {
  return closest_point(p, std::numeric_limits<double>::infinity());
}

ClosestPoint TriangleBvh::closest_point(const Vec3& p, double max_distance_mm) const {
  ClosestPoint best;
  if (m_nodes.empty()) return best;
  double best2 = max_distance_mm * max_distance_mm;
  if (!(max_distance_mm < std::numeric_limits<double>::infinity())) {
    best2 = std::numeric_limits<double>::infinity();
  }
  std::int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = m_nodes[static_cast<std::size_t>(stack[--top])];
    if (node.box.squared_distance(p) > best2) continue;
    if (node.count > 0) {
      for (std::int32_t s = node.first; s < node.first + node.count; ++s) {
        const auto& c = m_corners[static_cast<std::size_t>(s)];
        if (m_boxes[static_cast<std::size_t>(s)].squared_distance(p) > best2) continue;
        const Vec3 q = closest_point_on_triangle(p, c[0], c[1], c[2]);
        const double d2 = (q - p).squaredNorm();
        if (d2 < best2 || (d2 == best2 && best.triangle < 0)) {
          best2 = d2;
          best.point = q;
          best.triangle = m_triangle_id[static_cast<std::size_t>(s)];
        }
      }
      continue;
    }
    const double dl = m_nodes[static_cast<std::size_t>(node.first)].box.squared_distance(p);
    const double dr = m_nodes[static_cast<std::size_t>(node.first + 1)].box.squared_distance(p);
    // Push the farther child first so the nearer one is visited first.
    if (dl <= dr) {
      if (dr <= best2) stack[top++] = node.first + 1;
      if (dl <= best2) stack[top++] = node.first;
    } else {
      if (dl <= best2) stack[top++] = node.first;
      if (dr <= best2) stack[top++] = node.first + 1;
    }
  }
  if (best.triangle >= 0) best.distance_mm = std::sqrt(best2);
  return best;
}

std::vector<std::int32_t> TriangleBvh::overlapping(const Aabb& box) const {
  std::vector<std::int32_t> out;
  if (m_nodes.empty() || box.empty()) return out;
  std::vector<std::int32_t> stack{0};
  while (!stack.empty()) {
    const Node& node = m_nodes[static_cast<std::size_t>(stack.back())];
    stack.pop_back();
    if (!node.box.overlaps(box)) continue;
    if (node.count > 0) {
      for (std::int32_t s = node.first; s < node.first + node.count; ++s) {
        if (m_boxes[static_cast<std::size_t>(s)].overlaps(box)) out.push_back(m_triangle_id[static_cast<std::size_t>(s)]);
      }
    } else {
      stack.push_back(node.first);
      stack.push_back(node.first + 1);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::pair<std::int32_t, std::int32_t>> TriangleBvh::self_pairs(
    const std::function<bool(std::int32_t, std::int32_t)>& accept, bool threaded) const {
  return traverse_self(accept, threaded, false);
}

bool TriangleBvh::any_self_pair(const std::function<bool(std::int32_t, std::int32_t)>& accept,
                                bool threaded) const {
  return !traverse_self(accept, threaded, true).empty();
}

std::vector<std::pair<std::int32_t, std::int32_t>> TriangleBvh::traverse_self(
    const std::function<bool(std::int32_t, std::int32_t)>& accept, bool threaded,
    bool first_only) const {
  std::atomic<bool> stop{false};
  using Pair = std::pair<std::int32_t, std::int32_t>;
  std::vector<Pair> result;
  if (m_nodes.empty()) return result;
  // A task is a node pair (a, b); a == b means "pairs inside node a".
  struct Task {
    std::int32_t a, b;
  };
  auto test_slots = [&](std::int32_t s, std::int32_t r, std::vector<Pair>& out) {
    if (!m_boxes[static_cast<std::size_t>(s)].overlaps(m_boxes[static_cast<std::size_t>(r)])) return;
    std::int32_t i = m_triangle_id[static_cast<std::size_t>(s)];
    std::int32_t j = m_triangle_id[static_cast<std::size_t>(r)];
    if (i > j) std::swap(i, j);
    if (accept(i, j)) {
      out.emplace_back(i, j);
      if (first_only) stop.store(true, std::memory_order_relaxed);
    }
  };
  // Expands a task one level: either resolves it (leaves) or returns its sub-tasks.
  auto expand = [&](const Task& t, std::vector<Task>& sub, std::vector<Pair>& out) {
    const Node& na = m_nodes[static_cast<std::size_t>(t.a)];
    if (t.a == t.b) {
      if (na.count > 0) {
        for (std::int32_t s = na.first; s < na.first + na.count; ++s) {
          for (std::int32_t r = s + 1; r < na.first + na.count; ++r) test_slots(s, r, out);
        }
      } else {
        sub.push_back({na.first, na.first});
        sub.push_back({na.first + 1, na.first + 1});
        sub.push_back({na.first, na.first + 1});
      }
      return;
    }
    const Node& nb = m_nodes[static_cast<std::size_t>(t.b)];
    if (!na.box.overlaps(nb.box)) return;
    if (na.count > 0 && nb.count > 0) {
      for (std::int32_t s = na.first; s < na.first + na.count; ++s) {
        if (!m_boxes[static_cast<std::size_t>(s)].overlaps(nb.box)) continue;
        for (std::int32_t r = nb.first; r < nb.first + nb.count; ++r) test_slots(s, r, out);
      }
      return;
    }
    // Descend the node with the larger box (or the only inner one).
    const bool split_a = nb.count > 0 || (na.count == 0 && na.box.diagonal() >= nb.box.diagonal());
    if (split_a) {
      sub.push_back({na.first, t.b});
      sub.push_back({na.first + 1, t.b});
    } else {
      sub.push_back({t.a, nb.first});
      sub.push_back({t.a, nb.first + 1});
    }
  };
  auto run = [&](Task root, std::vector<Pair>& out) {
    std::vector<Task> stack{root};
    std::vector<Task> sub;
    while (!stack.empty()) {
      if (first_only && stop.load(std::memory_order_relaxed)) return;
      const Task t = stack.back();
      stack.pop_back();
      sub.clear();
      expand(t, sub, out);
      stack.insert(stack.end(), sub.begin(), sub.end());
    }
  };
  // Breadth-first expansion into enough independent tasks for the worker threads.
  std::vector<Task> tasks{{0, 0}};
  if (threaded) {
    for (int round = 0; round < 12 && tasks.size() < 512; ++round) {
      std::vector<Task> next;
      std::vector<Task> sub;
      for (const Task& t : tasks) {
        if (first_only && stop.load(std::memory_order_relaxed)) break;
        sub.clear();
        expand(t, sub, result);
        next.insert(next.end(), sub.begin(), sub.end());
      }
      tasks = std::move(next);
      if (tasks.empty()) break;
    }
  }
  std::vector<std::vector<Pair>> partial(tasks.size());
  parallel_for(
      tasks.size(), [&](std::size_t i) { run(tasks[i], partial[i]); }, threaded, 1);
  for (const auto& p : partial) result.insert(result.end(), p.begin(), p.end());
  std::sort(result.begin(), result.end());
  return result;
}

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/mesh_checks.h"

#include <algorithm>
#include <numeric>

#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/predicates.h"

namespace ido::geometry {
namespace {

/// Counts vertices whose incident triangles do not form a single edge-connected fan. For
/// vertex v, each incident triangle (v, a, b) links a and b; the fan is single when the link
/// graph over the neighbours is connected.
std::size_t count_non_manifold_vertices(const TriangleMesh& mesh) {
  const std::size_t nv = mesh.vertices.size();
  // CSR of (vertex → link edges).
  std::vector<std::int32_t> offset(nv + 1, 0);
  for (const Tri& t : mesh.triangles) {
    for (const std::int32_t v : t) ++offset[static_cast<std::size_t>(v) + 1];
  }
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  std::vector<Edge> link(static_cast<std::size_t>(offset[nv]));
  std::vector<std::int32_t> fill(offset.begin(), offset.end() - 1);
  for (const Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = t[static_cast<std::size_t>(k)];
      link[static_cast<std::size_t>(fill[static_cast<std::size_t>(v)]++)] = {
          t[static_cast<std::size_t>((k + 1) % 3)], t[static_cast<std::size_t>((k + 2) % 3)]};
    }
  }
  std::size_t bad = 0;
  std::vector<std::int32_t> nodes;
  std::vector<std::int32_t> parent;
  for (std::size_t v = 0; v < nv; ++v) {
    const auto b = static_cast<std::size_t>(offset[v]);
    const auto e = static_cast<std::size_t>(offset[v + 1]);
    if (e - b <= 1) continue;
    nodes.clear();
    for (std::size_t i = b; i < e; ++i) {
      nodes.push_back(link[i][0]);
      nodes.push_back(link[i][1]);
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    parent.resize(nodes.size());
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](std::int32_t x) {
      while (parent[static_cast<std::size_t>(x)] != x) {
        parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
        x = parent[static_cast<std::size_t>(x)];
      }
      return x;
    };
    auto local = [&](std::int32_t g) {
      return static_cast<std::int32_t>(std::lower_bound(nodes.begin(), nodes.end(), g) - nodes.begin());
    };
    std::size_t groups = nodes.size();
    for (std::size_t i = b; i < e; ++i) {
      const std::int32_t x = find(local(link[i][0]));
      const std::int32_t y = find(local(link[i][1]));
      if (x != y) {
        parent[static_cast<std::size_t>(x)] = y;
        --groups;
      }
    }
    if (groups > 1) ++bad;
  }
  return bad;
}

}  // namespace

bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  return collinear3d(a, b, c);
}

double signed_volume(const TriangleMesh& mesh) {
  Aabb box;
  for (const Tri& t : mesh.triangles) {
    for (const std::int32_t v : t) box.extend(mesh.vertices[static_cast<std::size_t>(v)]);
  }
  if (box.empty()) return 0.0;
  const Vec3 o = box.centre();
  double six_v = 0.0;
  for (const Tri& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[static_cast<std::size_t>(t[0])] - o;
    const Vec3 b = mesh.vertices[static_cast<std::size_t>(t[1])] - o;
    const Vec3 c = mesh.vertices[static_cast<std::size_t>(t[2])] - o;
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

double surface_area(const TriangleMesh& mesh) {
  double twice = 0.0;
  for (const Tri& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Vec3& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    twice += (b - a).cross(c - a).norm();
  }
  return 0.5 * twice;
}

MeshCheckReport check_mesh(const TriangleMesh& mesh) {
  validate_mesh(mesh);
  MeshCheckReport r;
  const EdgeMap map = build_edge_map(mesh);
  r.triangles = mesh.triangles.size();
  r.edges = map.edges.size();
  std::vector<char> used(mesh.vertices.size(), 0);
  Aabb box;
  for (const Tri& t : mesh.triangles) {
    for (const std::int32_t v : t) {
      used[static_cast<std::size_t>(v)] = 1;
      box.extend(mesh.vertices[static_cast<std::size_t>(v)]);
    }
    if (is_degenerate_triangle(mesh.vertices[static_cast<std::size_t>(t[0])],
                               mesh.vertices[static_cast<std::size_t>(t[1])],
                               mesh.vertices[static_cast<std::size_t>(t[2])])) {
      ++r.degenerate_triangles;
    }
  }
  r.vertices = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));
  if (!box.empty()) {
    r.bounds_min = box.min;
    r.bounds_max = box.max;
  }
  bool oriented = true;
  for (const EdgeInfo& e : map.edges) {
    if (e.triangle_count == 1) ++r.boundary_edges;
    if (e.triangle_count > 2) ++r.non_manifold_edges;
    if (e.triangle_count == 2 && !(e.forward == 1 && e.backward == 1)) oriented = false;
    if (e.vertices[0] == e.vertices[1]) oriented = false;
  }
  r.closed = r.boundary_edges == 0 && r.triangles > 0;
  r.edge_manifold = r.non_manifold_edges == 0;
  r.non_manifold_vertices = count_non_manifold_vertices(mesh);
  r.vertex_manifold = r.non_manifold_vertices == 0;
  r.oriented = oriented && r.edge_manifold;
  r.euler_characteristic = static_cast<std::int64_t>(r.vertices) -
                           static_cast<std::int64_t>(r.edges) +
                           static_cast<std::int64_t>(r.triangles);
  const std::vector<std::int32_t> comp = triangle_components(mesh);
  r.components = comp.empty() ? 0 : *std::max_element(comp.begin(), comp.end()) + 1;
  if (r.closed && r.edge_manifold && r.vertex_manifold && r.oriented) {
    // Per-component χ: vertices, edges, faces each belong to exactly one component.
    std::vector<std::int64_t> chi(static_cast<std::size_t>(r.components), 0);
    std::vector<std::int32_t> vertex_comp(mesh.vertices.size(), -1);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      chi[static_cast<std::size_t>(comp[t])] += 1;
      for (const std::int32_t v : mesh.triangles[t]) vertex_comp[static_cast<std::size_t>(v)] = comp[t];
    }
    for (const std::int32_t c : vertex_comp) {
      if (c >= 0) chi[static_cast<std::size_t>(c)] += 1;
    }
    for (const EdgeInfo& e : map.edges) {
      chi[static_cast<std::size_t>(vertex_comp[static_cast<std::size_t>(e.vertices[0])])] -= 1;
    }
    int genus = 0;
    bool valid = true;
    for (const std::int64_t x : chi) {
      if (x > 2 || (2 - x) % 2 != 0) valid = false;
      genus += static_cast<int>((2 - x) / 2);
    }
    if (valid) r.genus = genus;
  }
  r.area_mm2 = surface_area(mesh);
  r.signed_volume_mm3 = signed_volume(mesh);
  return r;
}

bool is_closed(const TriangleMesh& mesh) {
  const EdgeMap map = build_edge_map(mesh);
  if (mesh.triangles.empty()) return false;
  return std::none_of(map.edges.begin(), map.edges.end(),
                      [](const EdgeInfo& e) { return e.triangle_count == 1; });
}

std::int64_t euler_characteristic(const TriangleMesh& mesh) {
  const EdgeMap map = build_edge_map(mesh);
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const Tri& t : mesh.triangles) {
    for (const std::int32_t v : t) used[static_cast<std::size_t>(v)] = 1;
  }
  return static_cast<std::int64_t>(std::count(used.begin(), used.end(), 1)) -
         static_cast<std::int64_t>(map.edges.size()) +
         static_cast<std::int64_t>(mesh.triangles.size());
}

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/mesh_topology.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>

#include "ido/core/error.h"

namespace ido::geometry {
namespace {

/// Union–find with path halving.
struct DisjointSets {
  std::vector<std::int32_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) {
    std::iota(parent.begin(), parent.end(), 0);
  }
  std::int32_t find(std::int32_t x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      auto& p = parent[static_cast<std::size_t>(x)];
      p = parent[static_cast<std::size_t>(p)];
      x = p;
    }
    return x;
  }
  void unite(std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent[static_cast<std::size_t>(a)] = b;  // smaller id becomes the root
  }
};

void check_indices(const TriangleMesh& mesh) {
  const auto n = static_cast<std::int64_t>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (const std::int32_t v : mesh.triangles[t]) {
      if (v < 0 || v >= n) {
        throw InvalidInput("triangle mesh: triangle " + std::to_string(t) + " has vertex index " +
                           std::to_string(v) + " outside [0, " + std::to_string(n) + ")");
      }
    }
  }
}

FieldMap select_entities(const FieldMap& fields, const std::vector<std::int32_t>& keep) {
  FieldMap out;
  for (const auto& [name, f] : fields) {
    Field g;
    g.components = f.components;
    const auto nc = static_cast<std::size_t>(std::max(f.components, 0));
    g.values.reserve(keep.size() * nc);
    for (const std::int32_t e : keep) {
      const auto start = static_cast<std::size_t>(e) * nc;
      if (start + nc > f.values.size()) break;  // short field: keep what exists
      g.values.insert(g.values.end(), f.values.begin() + static_cast<std::ptrdiff_t>(start),
                      f.values.begin() + static_cast<std::ptrdiff_t>(start + nc));
    }
    out.emplace(name, std::move(g));
  }
  return out;
}

}  // namespace

void validate_mesh(const TriangleMesh& mesh) {
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!mesh.vertices[v].allFinite()) {
      throw InvalidInput("triangle mesh: vertex " + std::to_string(v) +
                         " has a coordinate that is not finite");
    }
  }
  check_indices(mesh);
}

EdgeMap build_edge_map(const TriangleMesh& mesh) {
  check_indices(mesh);
  const std::size_t nt = mesh.triangles.size();
  struct HalfEdge {
    std::int64_t key;
    std::int32_t triangle;
    std::int8_t corner;
    bool forward;
  };
  std::vector<HalfEdge> half(nt * 3);
  for (std::size_t t = 0; t < nt; ++t) {
    const Tri& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tri[static_cast<std::size_t>(k)];
      const std::int32_t b = tri[static_cast<std::size_t>((k + 1) % 3)];
      const std::int32_t lo = std::min(a, b);
      const std::int32_t hi = std::max(a, b);
      half[t * 3 + static_cast<std::size_t>(k)] = {(static_cast<std::int64_t>(lo) << 32) | hi,
                                                   static_cast<std::int32_t>(t),
                                                   static_cast<std::int8_t>(k), a <= b};
    }
  }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
  });
  EdgeMap map;
  map.triangle_edges.assign(nt, {-1, -1, -1});
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    EdgeInfo info;
    info.vertices = {static_cast<std::int32_t>(half[i].key >> 32),
                     static_cast<std::int32_t>(half[i].key & 0xffffffff)};
    const auto id = static_cast<std::int32_t>(map.edges.size());
    for (; j < half.size() && half[j].key == half[i].key; ++j) {
      if (info.triangle_count < 2) info.triangles[static_cast<std::size_t>(info.triangle_count)] = half[j].triangle;
      ++info.triangle_count;
      (half[j].forward ? info.forward : info.backward)++;
      map.triangle_edges[static_cast<std::size_t>(half[j].triangle)]
                        [static_cast<std::size_t>(half[j].corner)] = id;
    }
    map.edges.push_back(info);
    i = j;
  }
  return map;
}

std::vector<Edge> unique_edges(const TriangleMesh& mesh) {
  const EdgeMap map = build_edge_map(mesh);
  std::vector<Edge> out;
  out.reserve(map.edges.size());
  for (const EdgeInfo& e : map.edges) out.push_back(e.vertices);
  return out;
}

std::vector<std::vector<std::int32_t>> vertex_triangles(const TriangleMesh& mesh) {
  check_indices(mesh);
  std::vector<std::vector<std::int32_t>> out(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Tri& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = tri[static_cast<std::size_t>(k)];
      bool repeated = false;
      for (int m = 0; m < k; ++m) repeated = repeated || tri[static_cast<std::size_t>(m)] == v;
      if (!repeated) out[static_cast<std::size_t>(v)].push_back(static_cast<std::int32_t>(t));
    }
  }
  return out;
}

std::vector<std::int32_t> triangle_components(const TriangleMesh& mesh) {
  check_indices(mesh);
  DisjointSets sets(mesh.vertices.size());
  for (const Tri& t : mesh.triangles) {
    sets.unite(t[0], t[1]);
    sets.unite(t[1], t[2]);
  }
  std::vector<std::int32_t> label(mesh.vertices.size(), -1);
  std::vector<std::int32_t> out(mesh.triangles.size());
  std::int32_t next = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto root = static_cast<std::size_t>(sets.find(mesh.triangles[t][0]));
    if (label[root] < 0) label[root] = next++;
    out[t] = label[root];
  }
  return out;
}

int connected_components(const TriangleMesh& mesh) {
  const std::vector<std::int32_t> labels = triangle_components(mesh);
  return labels.empty() ? 0 : *std::max_element(labels.begin(), labels.end()) + 1;
}

TriangleMesh weld_vertices(const TriangleMesh& mesh, double tol_mm) {
  if (!(tol_mm >= 0.0) || !std::isfinite(tol_mm)) {
    throw InvalidInput("weld_vertices: tolerance must be finite and >= 0, got " +
                       std::to_string(tol_mm));
  }
  validate_mesh(mesh);
  const std::size_t nv = mesh.vertices.size();
  DisjointSets sets(nv);
  // Uniform grid of cell size max(tol, tiny): a vertex can only merge with vertices in its
  // own or the 26 neighbouring cells.
  const double cell = tol_mm > 0.0 ? tol_mm : 1.0;
  struct KeyHash {
    std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
      // Unsigned arithmetic: wrap-around is intended here.
      return (static_cast<std::size_t>(k[0]) * 73856093u) ^ (static_cast<std::size_t>(k[1]) * 19349663u) ^
             (static_cast<std::size_t>(k[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<std::int32_t>, KeyHash> grid;
  grid.reserve(nv);
  auto cell_of = [&](double x) {
    // Clamped so that huge coordinates over a tiny tolerance cannot overflow; clamped cells
    // only merge more candidates, the distance test stays exact.
    return static_cast<std::int64_t>(std::clamp(std::floor(x / cell), -4e18, 4e18));
  };
  auto key_of = [&](const Vec3& p) {
    return std::array<std::int64_t, 3>{cell_of(p.x()), cell_of(p.y()), cell_of(p.z())};
  };
  const double tol2 = tol_mm * tol_mm;
  for (std::size_t v = 0; v < nv; ++v) {
    const Vec3& p = mesh.vertices[v];
    const auto k = key_of(p);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end()) continue;
          for (const std::int32_t w : it->second) {
            if ((mesh.vertices[static_cast<std::size_t>(w)] - p).squaredNorm() <= tol2) {
              sets.unite(static_cast<std::int32_t>(v), w);
            }
          }
        }
      }
    }
    grid[k].push_back(static_cast<std::int32_t>(v));
  }
  TriangleMesh out;
  out.vertices = mesh.vertices;
  out.point_fields = mesh.point_fields;
  std::vector<std::int32_t> kept_cells;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    Tri tri = mesh.triangles[t];
    for (auto& v : tri) v = sets.find(v);  // the root is the smallest index of the cluster
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    out.triangles.push_back(tri);
    kept_cells.push_back(static_cast<std::int32_t>(t));
  }
  out.cell_fields = select_entities(mesh.cell_fields, kept_cells);
  remove_unused_vertices(out);
  return out;
}

void remove_unused_vertices(TriangleMesh& mesh) {
  check_indices(mesh);
  std::vector<std::int32_t> new_index(mesh.vertices.size(), -1);
  for (const Tri& t : mesh.triangles) {
    for (const std::int32_t v : t) new_index[static_cast<std::size_t>(v)] = 0;
  }
  std::vector<std::int32_t> kept;
  for (std::size_t v = 0; v < new_index.size(); ++v) {
    if (new_index[v] == 0) {
      new_index[v] = static_cast<std::int32_t>(kept.size());
      kept.push_back(static_cast<std::int32_t>(v));
    }
  }
  if (kept.size() == mesh.vertices.size()) return;
  std::vector<Vec3> vertices;
  vertices.reserve(kept.size());
  for (const std::int32_t v : kept) vertices.push_back(mesh.vertices[static_cast<std::size_t>(v)]);
  mesh.vertices = std::move(vertices);
  for (Tri& t : mesh.triangles) {
    for (auto& v : t) v = new_index[static_cast<std::size_t>(v)];
  }
  mesh.point_fields = select_entities(mesh.point_fields, kept);
}

TriangleMesh without_unused_vertices(TriangleMesh mesh) {
  remove_unused_vertices(mesh);
  return mesh;
}

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
// Self-intersection detection, surface checks, marching tetrahedra and the balloon's
// topology repair. Written by hand for ido.
#include "ido/segment/topology_repair.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <numeric>
#include <unordered_map>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/meshing/remesh.h"
#include "ido/meshing/signed_distance.h"

namespace ido::segment {

namespace {

double orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a));
}

int sgn(double x, double eps) { return x > eps ? 1 : (x < -eps ? -1 : 0); }

// Does the open segment pq cross the triangle abc (non-coplanar, proper crossing)?
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                              const Vec3& c, double scale) {
  const double eps = 1e-14 * scale * scale * scale;
  const int s1 = sgn(orient(a, b, c, p), eps), s2 = sgn(orient(a, b, c, q), eps);
  if (s1 == 0 || s2 == 0 || s1 == s2) return false;
  const int e1 = sgn(orient(p, q, a, b), eps), e2 = sgn(orient(p, q, b, c), eps),
            e3 = sgn(orient(p, q, c, a), eps);
  if (e1 == 0 || e2 == 0 || e3 == 0) return false;  // grazing an edge: not counted
  return e1 == e2 && e2 == e3;
}

bool triangles_intersect(const geometry::TriangleMesh& m, std::int32_t t1, std::int32_t t2) {
  const Tri& A = m.triangles[t1];
  const Tri& B = m.triangles[t2];
  int shared = 0;
  int sa[3] = {-1, -1, -1}, sb[3] = {-1, -1, -1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (A[i] == B[j]) {
        sa[shared] = i;
        sb[shared] = j;
        ++shared;
      }
  const Vec3* a[3] = {&m.vertices[A[0]], &m.vertices[A[1]], &m.vertices[A[2]]};
  const Vec3* b[3] = {&m.vertices[B[0]], &m.vertices[B[1]], &m.vertices[B[2]]};
  double scale = 0;
  for (int i = 0; i < 3; ++i) {
    scale = std::max(scale, (*a[i] - *a[(i + 1) % 3]).norm());
    scale = std::max(scale, (*b[i] - *b[(i + 1) % 3]).norm());
  }
  if (shared >= 3) return true;  // duplicate triangle
  if (shared == 2) {
    // Folded flat onto each other: normals opposite and the far vertices on the same side.
    const Vec3 na = (*a[1] - *a[0]).cross(*a[2] - *a[0]);
    const Vec3 nb = (*b[1] - *b[0]).cross(*b[2] - *b[0]);
    return na.dot(nb) < -0.9999 * na.norm() * nb.norm();
  }
  if (shared == 1) {
    const int ia = sa[0], ib = sb[0];
    const Vec3& p = *a[(ia + 1) % 3];
    const Vec3& q = *a[(ia + 2) % 3];
    if (segment_crosses_triangle(p, q, *b[0], *b[1], *b[2], scale)) return true;
    const Vec3& r = *b[(ib + 1) % 3];
    const Vec3& s = *b[(ib + 2) % 3];
    return segment_crosses_triangle(r, s, *a[0], *a[1], *a[2], scale);
  }
  for (int i = 0; i < 3; ++i) {
    if (segment_crosses_triangle(*a[i], *a[(i + 1) % 3], *b[0], *b[1], *b[2], scale)) return true;
    if (segment_crosses_triangle(*b[i], *b[(i + 1) % 3], *a[0], *a[1], *a[2], scale)) return true;
  }
  return false;
}

}  // namespace

std::vector<std::pair<std::int32_t, std::int32_t>> find_self_intersections(
    const geometry::TriangleMesh& mesh, bool threaded) {
  const std::size_t nt = mesh.triangles.size();
  std::vector<std::pair<std::int32_t, std::int32_t>> result;
  if (nt < 2) return result;
  const auto nv = static_cast<std::int32_t>(mesh.vertices.size());
  for (const Tri& t : mesh.triangles)
    for (std::int32_t v : t)
      if (v < 0 || v >= nv) throw InvalidInput("self-intersection: vertex index out of range");
  std::vector<Vec3> lo(nt), hi(nt);
  double mean_extent = 0;
  Vec3 glo = Vec3::Constant(INFINITY);
  for (std::size_t t = 0; t < nt; ++t) {
    const Tri& tr = mesh.triangles[t];
    lo[t] = mesh.vertices[tr[0]].cwiseMin(mesh.vertices[tr[1]]).cwiseMin(mesh.vertices[tr[2]]);
    hi[t] = mesh.vertices[tr[0]].cwiseMax(mesh.vertices[tr[1]]).cwiseMax(mesh.vertices[tr[2]]);
    mean_extent += (hi[t] - lo[t]).maxCoeff();
    glo = glo.cwiseMin(lo[t]);
  }
  const double cell = std::max(2.0 * mean_extent / double(nt), 1e-9);
  auto cell_of = [&](const Vec3& p) {
    return std::array<std::int64_t, 3>{std::int64_t(std::floor((p[0] - glo[0]) / cell)),
                                       std::int64_t(std::floor((p[1] - glo[1]) / cell)),
                                       std::int64_t(std::floor((p[2] - glo[2]) / cell))};
  };
  auto key_of = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return std::uint64_t(i) * 73856093ull ^ std::uint64_t(j) * 19349663ull * 1024ull ^
           std::uint64_t(k) * 83492791ull * 1048576ull;
  };
  // Cell → triangles (exact cell coordinates kept to resolve hash collisions).
  struct Entry {
    std::int64_t i, j, k;
    std::int32_t t;
  };
  std::vector<Entry> entries;
  entries.reserve(nt * 2);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto c0 = cell_of(lo[t]), c1 = cell_of(hi[t]);
    for (std::int64_t k = c0[2]; k <= c1[2]; ++k)
      for (std::int64_t j = c0[1]; j <= c1[1]; ++j)
        for (std::int64_t i = c0[0]; i <= c1[0]; ++i) entries.push_back({i, j, k, std::int32_t(t)});
  }
  std::sort(entries.begin(), entries.end(), [&](const Entry& x, const Entry& y) {
    if (x.k != y.k) return x.k < y.k;
    if (x.j != y.j) return x.j < y.j;
    if (x.i != y.i) return x.i < y.i;
    return x.t < y.t;
  });
  (void)key_of;
  std::vector<std::pair<std::size_t, std::size_t>> cells;
  for (std::size_t s = 0; s < entries.size();) {
    std::size_t e = s + 1;
    while (e < entries.size() && entries[e].i == entries[s].i && entries[e].j == entries[s].j &&
           entries[e].k == entries[s].k)
      ++e;
    if (e - s > 1) cells.emplace_back(s, e);
    s = e;
  }
  std::mutex mutex;
  parallel_for_ranges(
      cells.size(),
      [&](std::size_t cb, std::size_t ce) {
        std::vector<std::pair<std::int32_t, std::int32_t>> local;
        for (std::size_t c = cb; c < ce; ++c) {
          const auto [s, e] = cells[c];
          for (std::size_t x = s; x < e; ++x)
            for (std::size_t y = x + 1; y < e; ++y) {
              const std::int32_t t1 = entries[x].t, t2 = entries[y].t;
              // Boxes must overlap; test the pair only in the cell holding the overlap's min corner.
              const Vec3 olo = lo[t1].cwiseMax(lo[t2]), ohi = hi[t1].cwiseMin(hi[t2]);
              if ((olo.array() > ohi.array()).any()) continue;
              const auto oc = cell_of(olo);
              if (oc[0] != entries[x].i || oc[1] != entries[x].j || oc[2] != entries[x].k) continue;
              if (triangles_intersect(mesh, t1, t2)) local.emplace_back(std::min(t1, t2), std::max(t1, t2));
            }
        }
        if (!local.empty()) {
          std::lock_guard<std::mutex> lock(mutex);
          result.insert(result.end(), local.begin(), local.end());
        }
      },
      threaded, 64);
  std::sort(result.begin(), result.end());
  result.erase(std::unique(result.begin(), result.end()), result.end());
  return result;
}

SurfaceCheck check_surface(const geometry::TriangleMesh& mesh) {
  SurfaceCheck c;
  c.vertices = static_cast<std::int64_t>(mesh.vertices.size());
  c.triangles = static_cast<std::int64_t>(mesh.triangles.size());
  const auto nv = static_cast<std::int32_t>(mesh.vertices.size());
  std::unordered_map<std::uint64_t, std::array<int, 2>> edges;  // [a<b count, a>b count]
  edges.reserve(mesh.triangles.size() * 2);
  std::vector<std::vector<std::int32_t>> vt(mesh.vertices.size());
  std::vector<std::int32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Tri& tr = mesh.triangles[t];
    for (std::int32_t v : tr)
      if (v < 0 || v >= nv) throw InvalidInput("surface check: vertex index out of range");
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tr[k], b = tr[(k + 1) % 3];
      const std::uint64_t key = (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
      edges[key][a < b ? 0 : 1] += 1;
      vt[a].push_back(std::int32_t(t));
      parent[find(a)] = find(b);
    }
    const Vec3 &p = mesh.vertices[tr[0]], &q = mesh.vertices[tr[1]], &r = mesh.vertices[tr[2]];
    c.area_mm2 += 0.5 * (q - p).cross(r - p).norm();
    c.volume_mm3 += p.dot(q.cross(r)) / 6.0;
  }
  c.edges = static_cast<std::int64_t>(edges.size());
  c.closed = true;
  c.edge_manifold = true;
  c.oriented = true;
  for (const auto& [key, n] : edges) {
    const int total = n[0] + n[1];
    if (total != 2) c.closed = false;
    if (total > 2) c.edge_manifold = false;
    if (n[0] != 1 || n[1] != 1) c.oriented = false;
  }
  c.vertex_manifold = true;
  std::unordered_map<std::int32_t, std::int32_t> next;
  for (std::size_t v = 0; v < vt.size() && c.vertex_manifold; ++v) {
    if (vt[v].empty()) continue;
    next.clear();
    for (std::int32_t t : vt[v]) {
      const Tri& tr = mesh.triangles[t];
      int k = 0;
      while (tr[k] != std::int32_t(v)) ++k;
      const std::int32_t b = tr[(k + 1) % 3], cc = tr[(k + 2) % 3];
      if (next.count(b)) {
        c.vertex_manifold = false;
        break;
      }
      next[b] = cc;
    }
    if (!c.vertex_manifold) break;
    // Walk the fan from one start: it must visit every triangle.
    std::int32_t start = next.begin()->first, cur = start;
    std::size_t steps = 0;
    do {
      auto it = next.find(cur);
      if (it == next.end()) break;
      cur = it->second;
      ++steps;
    } while (cur != start && steps <= vt[v].size());
    if (steps != vt[v].size() || cur != start) c.vertex_manifold = false;
  }
  c.euler_characteristic = c.vertices - c.edges + c.triangles;
  std::int64_t comps = 0;
  for (std::int32_t v = 0; v < nv; ++v)
    if (!vt[v].empty() && find(v) == v) ++comps;
  c.components = comps;
  return c;
}

geometry::TriangleMesh extract_zero_level(const image::Volume<float>& field, bool threaded) {
  geometry::TriangleMesh out;
  const Index3 n = field.size();
  if (n[0] < 2 || n[1] < 2 || n[2] < 2) return out;
  auto value = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> float {
    if (i == 0 || j == 0 || k == 0 || i == n[0] - 1 || j == n[1] - 1 || k == n[2] - 1)
      return std::max(field(i, j, k), 1.0f);
    return field(i, j, k);
  };
  // Kuhn subdivision: tetrahedron p = (0, e_a, e_a+e_b, 1) for each permutation (a, b, c).
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::array<std::array<std::array<int, 3>, 4>, 6> tets{};
  std::array<int, 6> tet_sign{};
  for (int t = 0; t < 6; ++t) {
    std::array<int, 3> c{0, 0, 0};
    tets[t][0] = c;
    for (int s = 0; s < 3; ++s) {
      c[kPerm[t][s]] = 1;
      tets[t][s + 1] = c;
    }
    Vec3 w[4];
    for (int v = 0; v < 4; ++v)
      w[v] = field.index_to_world_matrix() * Vec3(tets[t][v][0], tets[t][v][1], tets[t][v][2]);
    tet_sign[t] = orient(w[0], w[1], w[2], w[3]) > 0 ? 1 : -1;
  }
  // Process k-slabs in parallel, each producing triangles keyed by global grid-edge ids.
  using EdgeId = std::uint64_t;
  const std::uint64_t total = std::uint64_t(n[0] * n[1] * n[2]);
  struct SlabOut {
    std::vector<std::array<EdgeId, 3>> tris;
  };
  std::vector<SlabOut> slabs(static_cast<std::size_t>(n[2] - 1));
  parallel_for(
      static_cast<std::size_t>(n[2] - 1),
      [&](std::size_t ks) {
        const auto k = static_cast<std::int64_t>(ks);
        auto& tris = slabs[ks].tris;
        for (std::int64_t j = 0; j + 1 < n[1]; ++j)
          for (std::int64_t i = 0; i + 1 < n[0]; ++i) {
            float cv[8];
            int inside = 0;
            for (int c = 0; c < 8; ++c) {
              cv[c] = value(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
              inside += cv[c] < 0.0f;
            }
            if (inside == 0 || inside == 8) continue;
            for (int t = 0; t < 6; ++t) {
              std::uint64_t id[4];
              bool in[4];
              int nin = 0;
              for (int v = 0; v < 4; ++v) {
                const auto& o = tets[t][v];
                const int c = o[0] | (o[1] << 1) | (o[2] << 2);
                in[v] = cv[c] < 0.0f;
                nin += in[v];
                id[v] = std::uint64_t(field.linear_index(i + o[0], j + o[1], k + o[2]));
              }
              if (nin == 0 || nin == 4) continue;
              auto eid = [&](int x, int y) {
                const std::uint64_t a = std::min(id[x], id[y]), b = std::max(id[x], id[y]);
                return a * total + b;
              };
              // Even permutations of (0,1,2,3) starting with each vertex.
              static constexpr int kRest[4][3] = {{1, 2, 3}, {0, 3, 2}, {3, 0, 1}, {2, 1, 0}};
              if (nin == 1 || nin == 3) {
                int x = 0;
                while (in[x] != (nin == 1)) ++x;
                const int* r = kRest[x];
                std::array<EdgeId, 3> tri{eid(x, r[0]), eid(x, r[1]), eid(x, r[2])};
                // Positive tet: normal points away from x. Flip for a negative tet, and when
                // x is the outside vertex (the normal must point towards it).
                if ((tet_sign[t] < 0) != (nin == 3)) std::swap(tri[1], tri[2]);
                tris.push_back(tri);
              } else {
                // Inside a, b; outside c, d with (a, b, c, d) an even permutation.
                int a = -1, b = -1, cc = -1, d = -1;
                for (int v = 0; v < 4; ++v) {
                  if (in[v]) (a < 0 ? a : b) = v;
                  else (cc < 0 ? cc : d) = v;
                }
                // Parity of the permutation (a, b, c, d).
                const int perm[4] = {a, b, cc, d};
                int inv = 0;
                for (int p = 0; p < 4; ++p)
                  for (int q = p + 1; q < 4; ++q) inv += perm[p] > perm[q];
                const bool flip = ((inv & 1) != 0) != (tet_sign[t] < 0);
                std::array<EdgeId, 4> quad{eid(a, cc), eid(a, d), eid(b, d), eid(b, cc)};
                std::array<EdgeId, 3> t1{quad[0], quad[1], quad[2]}, t2{quad[0], quad[2], quad[3]};
                if (flip) {
                  std::swap(t1[1], t1[2]);
                  std::swap(t2[1], t2[2]);
                }
                tris.push_back(t1);
                tris.push_back(t2);
              }
            }
          }
      },
      threaded, 1);
  std::unordered_map<EdgeId, std::int32_t> vertex_of;
  auto vertex = [&](EdgeId e) -> std::int32_t {
    auto it = vertex_of.find(e);
    if (it != vertex_of.end()) return it->second;
    const std::uint64_t a = e / total, b = e % total;
    const std::int64_t ia = std::int64_t(a) % n[0], ja = (std::int64_t(a) / n[0]) % n[1], ka = std::int64_t(a) / (n[0] * n[1]);
    const std::int64_t ib = std::int64_t(b) % n[0], jb = (std::int64_t(b) / n[0]) % n[1], kb = std::int64_t(b) / (n[0] * n[1]);
    const double fa = value(ia, ja, ka), fb = value(ib, jb, kb);
    double t = fa / (fa - fb);
    t = std::clamp(t, 1e-3, 1.0 - 1e-3);
    const Vec3 pa = field.index_to_world(Vec3(double(ia), double(ja), double(ka)));
    const Vec3 pb = field.index_to_world(Vec3(double(ib), double(jb), double(kb)));
    const auto id = static_cast<std::int32_t>(out.vertices.size());
    out.vertices.push_back(pa + t * (pb - pa));
    vertex_of.emplace(e, id);
    return id;
  };
  for (const auto& s : slabs)
    for (const auto& tri : s.tris) out.triangles.push_back(Tri{vertex(tri[0]), vertex(tri[1]), vertex(tri[2])});
  return out;
}

namespace {

// Keeps the connected components whose enclosed volume reaches min_volume.
geometry::TriangleMesh drop_small_components(const geometry::TriangleMesh& mesh, double min_volume) {
  const auto nv = static_cast<std::int32_t>(mesh.vertices.size());
  std::vector<std::int32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Tri& t : mesh.triangles) {
    parent[find(t[0])] = find(t[1]);
    parent[find(t[1])] = find(t[2]);
  }
  std::unordered_map<std::int32_t, double> volume;
  for (const Tri& t : mesh.triangles)
    volume[find(t[0])] += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]])) / 6.0;
  geometry::TriangleMesh out;
  std::vector<std::int32_t> remap(mesh.vertices.size(), -1);
  for (const Tri& t : mesh.triangles) {
    if (volume[find(t[0])] < min_volume) continue;
    Tri nt;
    for (int k = 0; k < 3; ++k) {
      if (remap[t[k]] < 0) {
        remap[t[k]] = static_cast<std::int32_t>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[t[k]]);
      }
      nt[k] = remap[t[k]];
    }
    out.triangles.push_back(nt);
  }
  (void)nv;
  return out;
}

}  // namespace

geometry::TriangleMesh repair_topology(
    const geometry::TriangleMesh& mesh,
    const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const TopologyRepairOptions& options) {
  if (mesh.triangles.empty()) throw InvalidInput("topology repair: the mesh has no triangles");
  if (!(options.grid_spacing_mm > 0) || !(options.target_edge_mm > 0))
    throw InvalidInput("topology repair: grid spacing and target edge must be positive");
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double h = options.grid_spacing_mm;
  const Vec3 origin = lo - Vec3::Constant(3 * h);
  Index3 size;
  for (int a = 0; a < 3; ++a) size[a] = static_cast<std::int64_t>(std::ceil((hi[a] - lo[a]) / h)) + 7;
  const image::Volume<float> grid(size, Vec3::Constant(h), origin);
  meshing::SignedDistanceOptions sd;
  sd.threaded = options.threaded;
  sd.band_mm = 2.0 * h;
  if (!intersecting_pairs.empty()) {
    sd.distance_triangles.assign(mesh.triangles.size(), 1);
    for (const auto& [a, b] : intersecting_pairs) {
      if (a >= 0 && std::size_t(a) < mesh.triangles.size()) sd.distance_triangles[a] = 0;
      if (b >= 0 && std::size_t(b) < mesh.triangles.size()) sd.distance_triangles[b] = 0;
    }
  }
  const image::Volume<float> field = meshing::signed_distance(mesh, grid, sd);
  geometry::TriangleMesh level = extract_zero_level(field, options.threaded);
  if (options.min_component_volume_mm3 > 0) level = drop_small_components(level, options.min_component_volume_mm3);
  if (level.triangles.empty() || !options.remesh) return level;
  meshing::RemeshOptions ro;
  ro.target_edge_mm = options.target_edge_mm;
  ro.iterations = 3;
  return meshing::remesh(level, ro);
}

}  // namespace ido::segment

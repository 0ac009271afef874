// SPDX-License-Identifier: Apache-2.0
// The boundary surface's conforming assembly (welding, T-junction splits, the 2-manifold
// split) into compact storage; assemble_surface() is this surface made into a TriangleMesh.
#include "ido/drill/assembled_surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "point_index.h"
namespace ido::drill {

struct AssembledSurface::Data {
  std::span<const Vec3> mesh_vertices;
  detail::PointIndex keys;                  // vertices 0 … nk − 1: the faces' corners (first use)
  std::vector<Vec3> centres;                // then the centres of fanned faces
  std::vector<std::int32_t> copy_source;    // then the copies of split vertices: their originals
  detail::BlockArray<Tri> triangles;
  std::vector<std::size_t> root_end;        // root r's triangles end at root_end[r]

  [[nodiscard]] Vec3 position(std::size_t i) const noexcept {
    const std::size_t nk = keys.size();
    if (i < nk) return point_position(keys.key(i), mesh_vertices);
    if (i < nk + centres.size()) return centres[i - nk];
    return position(static_cast<std::size_t>(copy_source[i - nk - centres.size()]));
  }
  [[nodiscard]] std::size_t vertex_count() const noexcept { return keys.size() + centres.size() + copy_source.size(); }
};

namespace {

// The point halfway between @p a and @p b, if it is a point of the hierarchy (at most four
// mesh vertices, even weights); exact = false otherwise.
PointKey midpoint(const PointKey& a, const PointKey& b, bool& exact) {
  std::array<std::int32_t, 8> id{};
  std::array<std::int32_t, 8> w{};
  int n = 0;
  auto add = [&](std::int32_t i, std::int32_t wt) {
    for (int k = 0; k < n; ++k)
      if (id[static_cast<std::size_t>(k)] == i) {
        w[static_cast<std::size_t>(k)] += wt;
        return;
      }
    id[static_cast<std::size_t>(n)] = i;
    w[static_cast<std::size_t>(n)] = wt;
    ++n;
  };
  for (std::size_t k = 0; k < 4; ++k) {
    if (a.id[k] >= 0) add(a.id[k], a.weight[k]);
    if (b.id[k] >= 0) add(b.id[k], b.weight[k]);
  }
  exact = n <= 4;
  PointKey m;
  if (!exact) return m;
  // Sort by id.
  for (int i = 1; i < n; ++i)
    for (int j = i; j > 0 && id[static_cast<std::size_t>(j - 1)] > id[static_cast<std::size_t>(j)]; --j) {
      std::swap(id[static_cast<std::size_t>(j - 1)], id[static_cast<std::size_t>(j)]);
      std::swap(w[static_cast<std::size_t>(j - 1)], w[static_cast<std::size_t>(j)]);
    }
  for (int k = 0; k < n; ++k) {
    if (w[static_cast<std::size_t>(k)] % 2 != 0) {
      exact = false;
      return m;
    }
    m.id[static_cast<std::size_t>(k)] = id[static_cast<std::size_t>(k)];
    m.weight[static_cast<std::size_t>(k)] = w[static_cast<std::size_t>(k)] / 2;
  }
  return m;
}

// Union-find over the triangles around one vertex (their indices in its star).
struct StarSets {
  std::vector<std::uint32_t> parent;
  void reset(std::size_t n) {
    parent.resize(n);
    for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<std::uint32_t>(i);
  }
  std::uint32_t find(std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void join(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
};

// A fan of triangles around a vertex that gets its own copy of the vertex.
struct FanCopy {
  std::uint64_t first_corner;  // 3 t + k of the fan's first triangle
  std::int32_t vertex;
  std::vector<std::uint32_t> triangles;
};

// Makes a closed, consistently oriented surface a 2-manifold without moving anything.
// Where leaves touch along an edge only, that edge has 2k triangles; sorted by angle about
// the edge they alternate in direction, and each triangle running against the edge's
// direction bounds, with the next one counter-clockwise, one wedge of material: those two
// are paired. Around every vertex the triangles joined through paired (or ordinary)
// edges form fans; each fan after the first (in triangle order) gets its own copy of the
// vertex, copies numbered in the order of their fans' first triangles. So an edge shared by
// two wedges becomes one edge per wedge, and a vertex where parts touch at a point becomes
// one vertex per part; positions (and so the enclosed volume) are unchanged.
// Worked vertex by vertex over its star (every triangle of an edge is in the star of both its
// ends, and both ends pair an edge's triangles alike: the pairing is computed from the edge's
// lower vertex). The stars (the triangles of each vertex, in increasing order) are listed for
// a range of vertices at a time, at most about @p batch_corners entries, so what is held
// beyond the mesh is a count per vertex, one batch of stars and the fans that need a copy.
// Returns the copies in the order they are numbered.
template <class Tris, class Position>
std::vector<FanCopy> fans_to_copy(const Tris& tris, std::size_t nv, Position&& position, std::size_t batch_corners) {
  const std::size_t nt = tris.size();
  std::vector<std::uint32_t> count(nv, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (const auto v : tris[t]) ++count[static_cast<std::size_t>(v)];
  struct Side {
    std::int32_t other;   // the edge's other end
    std::uint32_t local;  // the triangle's place in the star (so: in triangle order)
  };
  std::vector<FanCopy> copies;
  std::vector<Side> sides;
  std::vector<std::pair<double, std::size_t>> around;
  std::vector<std::uint32_t> fan_first;
  std::vector<std::uint32_t> first, fill, star;
  StarSets sets;
  for (std::size_t v0 = 0; v0 < nv;) {
    // The batch [v0, v1): at least one vertex, at most batch_corners corners otherwise.
    std::size_t v1 = v0, corners = 0;
    while (v1 < nv && (v1 == v0 || corners + count[v1] <= batch_corners)) corners += count[v1++];
    first.assign(v1 - v0 + 1, 0);
    for (std::size_t v = v0; v < v1; ++v) first[v - v0 + 1] = first[v - v0] + count[v];
    fill.assign(first.begin(), first.end() - 1);
    star.resize(corners);
    for (std::size_t t = 0; t < nt; ++t)
      for (const auto v : tris[t]) {
        const auto u = static_cast<std::size_t>(v);
        if (u >= v0 && u < v1) star[fill[u - v0]++] = static_cast<std::uint32_t>(t);
      }
    for (std::size_t v = v0; v < v1; ++v) {
      const std::uint32_t* star_v = star.data() + first[v - v0];
      const std::size_t n_star = first[v - v0 + 1] - first[v - v0];
      if (n_star == 0) continue;
      const auto vi = static_cast<std::int32_t>(v);
      sides.clear();
      for (std::size_t i = 0; i < n_star; ++i) {
        const auto& tr = tris[star_v[i]];
        for (const auto w : tr)
          if (w != vi) sides.push_back({w, static_cast<std::uint32_t>(i)});
      }
      std::sort(sides.begin(), sides.end(),
                [](const Side& x, const Side& y) { return std::tie(x.other, x.local) < std::tie(y.other, y.local); });
      sets.reset(n_star);
      for (std::size_t i = 0; i < sides.size();) {
        std::size_t j = i;
        while (j < sides.size() && sides[j].other == sides[i].other) ++j;
        const std::size_t n = j - i;
        if (n == 2) {
          sets.join(sides[i].local, sides[i + 1].local);
        } else if (n > 2 && n % 2 == 0) {
          const std::int32_t lo = std::min(vi, sides[i].other), hi = std::max(vi, sides[i].other);
          // Direction (lo → hi) and third vertex of the triangle of side k.
          auto forward = [&](std::size_t k) {
            const auto& tr = tris[star_v[sides[k].local]];
            for (std::size_t c = 0; c < 3; ++c)
              if (tr[c] == lo) return tr[(c + 1) % 3] == hi;
            return false;
          };
          auto apex = [&](std::size_t k) {
            const auto& tr = tris[star_v[sides[k].local]];
            for (const auto u : tr)
              if (u != lo && u != hi) return u;
            return tr[0];
          };
          const Vec3 a = position(static_cast<std::size_t>(lo));
          const Vec3 d = (position(static_cast<std::size_t>(hi)) - a).normalized();
          const Vec3 e1 = d.unitOrthogonal(), e2 = d.cross(e1);
          around.clear();
          for (std::size_t k = i; k < j; ++k) {
            const Vec3 w = position(static_cast<std::size_t>(apex(k))) - a;
            around.emplace_back(std::atan2(w.dot(e2), w.dot(e1)), k);
          }
          std::sort(around.begin(), around.end());
          bool alternate = true;
          for (std::size_t k = 0; k < n; ++k)
            alternate = alternate && forward(around[k].second) != forward(around[(k + 1) % n].second);
          if (alternate)
            for (std::size_t k = 0; k < n; ++k)
              if (!forward(around[k].second))
                sets.join(sides[around[k].second].local, sides[around[(k + 1) % n].second].local);
        }
        i = j;
      }
      // The fan of the star's first triangle keeps the vertex; every other fan gets a copy.
      const std::uint32_t kept = sets.find(0);
      fan_first.assign(n_star, std::numeric_limits<std::uint32_t>::max());
      for (std::size_t i = 1; i < n_star; ++i) {
        const std::uint32_t f = sets.find(static_cast<std::uint32_t>(i));
        if (f == kept) continue;
        if (fan_first[f] == std::numeric_limits<std::uint32_t>::max()) {
          fan_first[f] = static_cast<std::uint32_t>(copies.size());
          const auto& tr = tris[star_v[i]];
          const std::size_t k = tr[0] == vi ? 0 : (tr[1] == vi ? 1 : 2);
          copies.push_back({3 * static_cast<std::uint64_t>(star_v[i]) + k, vi, {}});
        }
        copies[fan_first[f]].triangles.push_back(star_v[i]);
      }
    }
    v0 = v1;
  }
  // Copies numbered in the order their fans are first met, triangle by triangle.
  std::sort(copies.begin(), copies.end(),
            [](const FanCopy& x, const FanCopy& y) { return x.first_corner < y.first_corner; });
  return copies;
}

// Welds the faces' corners by their exact keys (numbered in order of first use), splits each
// face's edges at the surface vertices strictly inside them (a face with such vertices is
// fanned from its centre) and makes the result a 2-manifold. release(r) is called once root
// r's faces are numbered (the owning constructor frees them there): from then on a face is
// its three corner numbers, 12 bytes instead of 32.
}  // namespace

template <class Release>
void AssembledSurface::assemble(std::span<const std::vector<SurfaceFace>> v_lists, const SurfaceAssemblyOptions& options,
                                Release&& release) {
  Data& d = *m;
  // The index grows with the keys, into the memory of the faces freed so far (sized for all
  // of them at once, it would come on top of every face).
  d.keys = detail::PointIndex();
  detail::BlockArray<Tri> corners;
  std::vector<std::size_t> face_end(v_lists.size());
  for (std::size_t r = 0; r < v_lists.size(); ++r) {
    for (const auto& f : v_lists[r]) {
      Tri c{};
      for (std::size_t e = 0; e < 3; ++e) c[e] = d.keys.insert(f.key(e));
      corners.push_back(c);
    }
    face_end[r] = corners.size();
    release(r);
  }
  const std::size_t nk = d.keys.size();
  std::vector<std::int32_t> ring;
  // Appends the vertices strictly inside edge (a, b) that are surface vertices, in order.
  auto split = [&](auto&& self, const PointKey& a, const PointKey& b) -> void {
    bool exact = true;
    const PointKey m = midpoint(a, b, exact);
    if (!exact) return;
    const std::int32_t i = d.keys.find(m);
    if (i < 0) return;
    self(self, a, m);
    ring.push_back(i);
    self(self, m, b);
  };
  d.root_end.assign(v_lists.size(), 0);
  std::size_t f = 0;
  for (std::size_t r = 0; r < v_lists.size(); ++r) {
    for (; f < face_end[r]; ++f) {
      const Tri c = corners[f];
      const std::array<PointKey, 3> k{d.keys.key(static_cast<std::size_t>(c[0])),
                                      d.keys.key(static_cast<std::size_t>(c[1])),
                                      d.keys.key(static_cast<std::size_t>(c[2]))};
      ring.clear();
      for (std::size_t e = 0; e < 3; ++e) {
        ring.push_back(c[e]);
        split(split, k[e], k[(e + 1) % 3]);
      }
      if (ring.size() == 3) {
        d.triangles.push_back({ring[0], ring[1], ring[2]});
        continue;
      }
      // Fan from the face centroid (strictly inside, so no triangle degenerates).
      const auto centre = static_cast<std::int32_t>(nk + d.centres.size());
      d.centres.push_back((point_position(k[0], d.mesh_vertices) + point_position(k[1], d.mesh_vertices) +
                           point_position(k[2], d.mesh_vertices)) / 3.0);
      for (std::size_t i = 0; i < ring.size(); ++i) d.triangles.push_back({ring[i], ring[(i + 1) % ring.size()], centre});
    }
    d.root_end[r] = d.triangles.size();
    corners.release_before(f);
  }
  corners.clear();
  d.keys.release_table();  // the split needs no look-up: free the table first
  const std::size_t nv = d.vertex_count();
  const auto copies = fans_to_copy(d.triangles, nv, [&d](std::size_t i) { return d.position(i); },
                                   std::max<std::size_t>(options.star_batch_corners, 1));
  d.copy_source.reserve(copies.size());
  for (const auto& c : copies) {
    const auto index = static_cast<std::int32_t>(d.vertex_count());
    d.copy_source.push_back(c.vertex);
    for (const auto t : c.triangles)
      for (auto& u : d.triangles[t])
        if (u == c.vertex) u = index;
  }
}

AssembledSurface::AssembledSurface(std::vector<std::vector<SurfaceFace>>&& v_lists, std::span<const Vec3> vertices_mm,
                                   const SurfaceAssemblyOptions& options)
    : m(std::make_unique<Data>()) {
  m->mesh_vertices = vertices_mm;
  auto lists = std::move(v_lists);
  detail::FreedPages pages;
  assemble(lists, options, [&](std::size_t r) {
    pages.freed(lists[r].capacity() * sizeof(SurfaceFace));
    std::vector<SurfaceFace>().swap(lists[r]);
  });
}

AssembledSurface::AssembledSurface(std::span<const std::vector<SurfaceFace>> v_lists, std::span<const Vec3> vertices_mm,
                                   const SurfaceAssemblyOptions& options)
    : m(std::make_unique<Data>()) {
  m->mesh_vertices = vertices_mm;
  assemble(v_lists, options, [](std::size_t) {});
}

AssembledSurface::~AssembledSurface() = default;
AssembledSurface::AssembledSurface(AssembledSurface&&) noexcept = default;
AssembledSurface& AssembledSurface::operator=(AssembledSurface&&) noexcept = default;

std::size_t AssembledSurface::vertex_count() const noexcept { return m->vertex_count(); }
std::size_t AssembledSurface::triangle_count() const noexcept { return m->triangles.size(); }
Vec3 AssembledSurface::vertex(std::size_t i) const noexcept { return m->position(i); }
const Tri& AssembledSurface::triangle(std::size_t t) const noexcept { return m->triangles[t]; }
const std::vector<std::size_t>& AssembledSurface::root_ends() const noexcept { return m->root_end; }

geometry::TriangleMesh AssembledSurface::to_mesh() const {
  geometry::TriangleMesh mesh;
  const std::size_t nv = vertex_count(), nt = triangle_count();
  mesh.vertices.reserve(nv);
  for (std::size_t i = 0; i < nv; ++i) mesh.vertices.push_back(m->position(i));
  mesh.triangles.reserve(nt);
  for (std::size_t t = 0; t < nt; ++t) mesh.triangles.push_back(m->triangles[t]);
  auto& root = mesh.cell_fields["root"];
  root.values.reserve(nt);
  for_each_triangle_root([&root](std::uint32_t r) { root.values.push_back(static_cast<double>(r)); });
  return mesh;
}

std::size_t AssembledSurface::memory_bytes() const noexcept {
  return m->keys.memory_bytes() + m->triangles.memory_bytes() + m->centres.capacity() * sizeof(Vec3) +
         m->copy_source.capacity() * sizeof(std::int32_t) + m->root_end.capacity() * sizeof(std::size_t);
}

geometry::TriangleMesh assemble_surface(std::span<const std::vector<SurfaceFace>> v_lists,
                                        std::span<const Vec3> vertices_mm) {
  return AssembledSurface(v_lists, vertices_mm).to_mesh();
}

geometry::TriangleMesh assemble_surface(std::vector<std::vector<SurfaceFace>>&& v_lists,
                                        std::span<const Vec3> vertices_mm) {
  return AssembledSurface(std::move(v_lists), vertices_mm).to_mesh();
}

}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
// Narrow-band signed distance; the sign comes from geometry::WindingNumber (hierarchical
// generalised winding number). Written by hand for ido (see the header for the papers).
#include "ido/meshing/signed_distance.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/predicates.h"
#include "ido/geometry/winding_number.h"
#include "ido/image/index_box.h"
#include "ido/meshing/voxelize.h"

namespace ido::meshing {

namespace {

// Every edge is run once each way (a closed, consistently oriented surface): then the
// winding number is an integer off the surface, 0 far away, and changes by ±1 across each
// triangle.
bool closed_and_oriented(const geometry::TriangleMesh& m) {
  const geometry::EdgeMap map = geometry::build_edge_map(m);
  return std::all_of(map.edges.begin(), map.edges.end(), [](const geometry::EdgeInfo& e) {
    return e.forward == 1 && e.backward == 1 && e.vertices[0] != e.vertices[1];
  });
}

}  // namespace

Vec3 closest_point_on_triangle_mm(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

image::Volume<float> distance_grid(const geometry::TriangleMesh& surface, double spacing_mm, int margin_cells) {
  if (surface.vertices.empty()) throw InvalidInput("distance grid: the mesh has no vertices");
  if (!(spacing_mm > 0) || !std::isfinite(spacing_mm) || margin_cells < 0)
    throw InvalidInput("distance grid: the spacing must be positive and the margin not negative");
  const geometry::Aabb box = geometry::Aabb::of(surface.vertices);
  const Vec3 &lo = box.min, &hi = box.max;
  Index3 size;
  for (int a = 0; a < 3; ++a)
    size[a] = static_cast<std::int64_t>(std::ceil((hi[a] - lo[a]) / spacing_mm)) + 2 * margin_cells + 1;
  return image::Volume<float>(size, Vec3::Constant(spacing_mm), lo - Vec3::Constant(margin_cells * spacing_mm));
}

image::Volume<float> signed_distance(const geometry::TriangleMesh& surface,
                                     const image::Volume<float>& grid,
                                     const SignedDistanceOptions& options) {
  if (grid.empty()) throw InvalidInput("signed distance: the grid is empty");
  if (surface.triangles.empty()) throw InvalidInput("signed distance: the surface has no triangles");
  if (!options.distance_triangles.empty() && options.distance_triangles.size() != surface.triangles.size())
    throw InvalidInput("signed distance: distance_triangles must hold one flag per triangle");
  const auto nv = static_cast<std::int32_t>(surface.vertices.size());
  for (const Tri& t : surface.triangles)
    for (std::int32_t v : t)
      if (v < 0 || v >= nv) throw InvalidInput("signed distance: triangle vertex index out of range");

  const double band = options.band_mm > 0 ? options.band_mm : 2.0 * grid.spacing().maxCoeff();
  const Index3 n = grid.size();
  image::Volume<float> out = grid.like<float>(static_cast<float>(band));
  std::vector<float>& dist = out.data();

  // Narrow band: every counted triangle writes the distance of grid points in its padded box.
  // Parallel over slabs of k; each slab visits the triangles overlapping it.
  std::vector<std::int32_t> tris;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    if (options.distance_triangles.empty() || options.distance_triangles[t]) tris.push_back(std::int32_t(t));
  // The grid points within the band of a triangle: its index-space box padded by the band; a
  // rotated grid maps an axis box to a rotated box, so there every axis is padded by the most.
  const auto padded_box = [&](const Tri& t, double band_mm) {
    const Vec3 pad_axis = (Vec3::Constant(band_mm).array() / grid.spacing().array()).matrix();
    const Vec3 pad = grid.direction().isIdentity(1e-9) ? pad_axis : Vec3::Constant(pad_axis.maxCoeff());
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (std::int32_t v : t) {
      const Vec3 idx = grid.world_to_index(surface.vertices[v]);
      lo = lo.cwiseMin(idx);
      hi = hi.cwiseMax(idx);
    }
    return image::IndexBox::of_centres(lo - pad, hi + pad, n);
  };
  std::vector<image::IndexBox> boxes(tris.size());
  for (std::size_t q = 0; q < tris.size(); ++q) boxes[q] = padded_box(surface.triangles[tris[q]], band);
  // Bucket triangles per k-slab for the parallel pass.
  const std::int64_t slab = 4;
  const std::int64_t nslabs = (n[2] + slab - 1) / slab;
  std::vector<std::vector<std::int32_t>> per_slab(static_cast<std::size_t>(nslabs));
  for (std::size_t q = 0; q < tris.size(); ++q) {
    if (boxes[q].empty()) continue;
    for (std::int64_t s = boxes[q].lo[2] / slab; s <= boxes[q].hi[2] / slab; ++s)
      per_slab[static_cast<std::size_t>(s)].push_back(std::int32_t(q));
  }
  parallel_for(
      static_cast<std::size_t>(nslabs),
      [&](std::size_t s) {
        const std::int64_t k0 = std::int64_t(s) * slab, k1 = std::min(n[2], k0 + slab);
        for (std::int32_t q : per_slab[s]) {
          const Tri& t = surface.triangles[tris[q]];
          const Vec3 &a = surface.vertices[t[0]], &b = surface.vertices[t[1]], &c = surface.vertices[t[2]];
          const image::IndexBox& bx = boxes[q];
          // The distance to the triangle is at least the distance to its plane: a point whose
          // plane distance already exceeds what its slot holds cannot lower it (the margin
          // covers the rounding of both), so the closest-point query is skipped there.
          const Vec3 nrm = (b - a).cross(c - a);
          const double nrm_len = nrm.norm();
          const Vec3 unit = nrm_len > 0 ? Vec3(nrm / nrm_len) : Vec3::Zero();
          for (std::int64_t k = std::max(k0, bx.lo[2]); k <= std::min(k1 - 1, bx.hi[2]); ++k)
            for (std::int64_t j = bx.lo[1]; j <= bx.hi[1]; ++j)
              for (std::int64_t i = bx.lo[0]; i <= bx.hi[0]; ++i) {
                const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
                float& slot = dist[out.linear_index(i, j, k)];
                if (std::abs(unit.dot(p - a)) > double(slot) * (1.0 + 1e-6) + 1e-9) continue;
                const double d = (closest_point_on_triangle_mm(p, a, b, c) - p).norm();
                if (d < slot) slot = static_cast<float>(d);
              }
        }
      },
      options.threaded, 1);

  if (options.sign == SignMethod::automatic && closed_and_oriented(surface)) {
    // The winding number is then an integer off the surface: the one voxelisation's rows.
    const image::Volume<std::uint8_t> inside = voxelize(surface, grid, {.threaded = options.threaded});
    for (std::size_t l = 0; l < dist.size(); ++l)
      if (inside.data()[l]) dist[l] = -std::max(dist[l], std::numeric_limits<float>::min());
    return out;
  }
  // Sign of any other surface, by the generalised winding number. It is constant off a
  // closed surface, so two 6-neighbours p, q (a spacing L apart) share it when the segment pq misses every triangle. The distance to
  // the surface is 1-Lipschitz, so along pq it stays above (d(p) + d(q) − L) / 2: the step is
  // safe when d(p) + d(q) > L. Grid points joined by safe steps form components that take the
  // sign of one winding-number evaluation each; only points with no safe step (on or very
  // near the surface) evaluate it themselves. d here is a lower bound of the distance to every
  // triangle: the least of the computed distance (to the counted triangles, at most band_mm),
  // 1.01 × the largest spacing, and the distance to the uncounted triangles near them.
  const geometry::WindingNumber winding(surface, {.beta = options.winding_beta});
  const auto total = static_cast<std::int64_t>(dist.size());
  const double reach = 1.01 * grid.spacing().maxCoeff();
  // Distance to the uncounted triangles within their boxes padded by the reach (the reach
  // elsewhere); empty when every triangle counts.
  std::vector<float> uncounted;
  if (!options.distance_triangles.empty()) {
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      if (options.distance_triangles[t]) continue;
      if (uncounted.empty()) uncounted.assign(dist.size(), static_cast<float>(reach));
      const Tri& tr = surface.triangles[t];
      const Vec3 &a = surface.vertices[tr[0]], &b = surface.vertices[tr[1]], &c = surface.vertices[tr[2]];
      padded_box(tr, reach).for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) {
        const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
        float& slot = uncounted[out.linear_index(i, j, k)];
        slot = std::min(slot, static_cast<float>((closest_point_on_triangle_mm(p, a, b, c) - p).norm()));
      });
    }
  }
  auto bound = [&](std::size_t v) {
    const double d = std::min(double(std::abs(dist[v])), reach);
    return uncounted.empty() ? d : std::min(d, double(uncounted[v]));
  };
  // A step along axis a is safe when the bounds add up to more than its length (with a
  // margin far above the float rounding of the distances).
  const std::int64_t stride[3] = {1, n[0], n[0] * n[1]};
  double need[3];
  for (int a = 0; a < 3; ++a) need[a] = grid.spacing()[a] * (1.0 + 1e-4) + 1e-9;
  auto for_safe_neighbours = [&](std::int64_t v, auto&& visit) {
    const std::int64_t c[3] = {v % n[0], (v / n[0]) % n[1], v / (n[0] * n[1])};
    const double bv = bound(std::size_t(v));
    for (int a = 0; a < 3; ++a)
      for (int sgn : {-1, 1}) {
        const std::int64_t ca = c[a] + sgn;
        if (ca < 0 || ca >= n[a]) continue;
        const std::int64_t w = v + sgn * stride[a];
        if (bv + bound(std::size_t(w)) > need[a] && visit(w)) return;
      }
  };
  auto inside_at = [&](std::int64_t v) {
    const Vec3 p = grid.index_to_world(Vec3(double(v % n[0]), double((v / n[0]) % n[1]), double(v / (n[0] * n[1]))));
    return winding.at(p) > 0.5;
  };
  // Inside is strictly negative, also at a grid point lying on a counted triangle (distance
  // 0), so a zero-level extraction never sees an inside point as outside.
  auto make_inside = [&](std::int64_t v) { dist[v] = -std::max(dist[v], std::numeric_limits<float>::min()); };
  // Points without a safe step evaluate the winding number themselves, in parallel.
  std::vector<std::uint8_t> seen(dist.size(), 0);
  parallel_for(
      static_cast<std::size_t>(total),
      [&](std::size_t idx) {
        bool any = false;
        for_safe_neighbours(std::int64_t(idx), [&](std::int64_t) { return any = true; });
        seen[idx] = any ? 0 : 1;
      },
      options.threaded, 1024);
  parallel_for(
      static_cast<std::size_t>(total),
      [&](std::size_t idx) {
        if (seen[idx] && inside_at(std::int64_t(idx))) make_inside(std::int64_t(idx));
      },
      options.threaded, 1024);
  // The others: one evaluation per component of safe steps, at the component's lowest index
  // (where a scan in index order would start it). Components by a concurrent union–find in
  // which a root is only ever linked under a smaller index, so every component ends with its
  // lowest index as root whatever the threads' interleaving: the same evaluations, the same
  // signs as a serial flood fill.
  std::vector<std::atomic<std::int64_t>> parent(dist.size());
  parallel_for(
      static_cast<std::size_t>(total), [&](std::size_t v) { parent[v].store(std::int64_t(v), std::memory_order_relaxed); },
      options.threaded, 4096);
  auto find = [&](std::int64_t v) {
    for (;;) {
      const std::int64_t p = parent[std::size_t(v)].load(std::memory_order_relaxed);
      if (p == v) return v;
      // Path halving: any ancestor is a valid parent (a root's index only falls).
      const std::int64_t gp = parent[std::size_t(p)].load(std::memory_order_relaxed);
      std::int64_t expected = p;
      if (gp != p) parent[std::size_t(v)].compare_exchange_weak(expected, gp, std::memory_order_relaxed);
      v = gp;
    }
  };
  auto unite = [&](std::int64_t a, std::int64_t b) {
    for (;;) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);  // link the larger root under the smaller
      std::int64_t expected = a;
      if (parent[std::size_t(a)].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
    }
  };
  // Each safe step once, from its lower end (the same safety test as `seen` above, so an
  // unseen point never steps to a seen one).
  parallel_for(
      static_cast<std::size_t>(total),
      [&](std::size_t idx) {
        if (seen[idx]) return;
        const auto v = std::int64_t(idx);
        for_safe_neighbours(v, [&](std::int64_t w) {
          if (w > v) unite(v, w);
          return false;
        });
      },
      options.threaded, 4096);
  // Roots evaluate the winding number; every member takes its root's sign.
  std::vector<std::uint8_t> root_inside(dist.size(), 0);
  parallel_for(
      static_cast<std::size_t>(total),
      [&](std::size_t idx) {
        if (!seen[idx] && parent[idx].load(std::memory_order_relaxed) == std::int64_t(idx))
          root_inside[idx] = inside_at(std::int64_t(idx)) ? 1 : 0;
      },
      options.threaded, 1024);
  parallel_for(
      static_cast<std::size_t>(total),
      [&](std::size_t idx) {
        if (!seen[idx] && root_inside[std::size_t(find(std::int64_t(idx)))]) make_inside(std::int64_t(idx));
      },
      options.threaded, 4096);
  return out;
}

}  // namespace ido::meshing

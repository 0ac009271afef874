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
#include "ido/geometry/winding_number.h"

namespace ido::meshing {

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
  struct Box { std::int64_t lo[3], hi[3]; };
  std::vector<Box> boxes(tris.size());
  const Vec3 pad_index = (Vec3::Constant(band).array() / grid.spacing().array()).matrix();
  for (std::size_t q = 0; q < tris.size(); ++q) {
    const Tri& t = surface.triangles[tris[q]];
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (std::int32_t v : t) {
      const Vec3 idx = grid.world_to_index(surface.vertices[v]);
      lo = lo.cwiseMin(idx);
      hi = hi.cwiseMax(idx);
    }
    // A rotated grid maps an axis box to a rotated box: pad by the full band on each axis.
    const double pad_any = pad_index.maxCoeff();
    for (int a = 0; a < 3; ++a) {
      const double pad = grid.direction().isIdentity(1e-9) ? pad_index[a] : pad_any;
      boxes[q].lo[a] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(lo[a] - pad)));
      boxes[q].hi[a] = std::min<std::int64_t>(n[a] - 1, static_cast<std::int64_t>(std::floor(hi[a] + pad)));
    }
  }
  // Bucket triangles per k-slab for the parallel pass.
  const std::int64_t slab = 4;
  const std::int64_t nslabs = (n[2] + slab - 1) / slab;
  std::vector<std::vector<std::int32_t>> per_slab(static_cast<std::size_t>(nslabs));
  for (std::size_t q = 0; q < tris.size(); ++q) {
    if (boxes[q].lo[0] > boxes[q].hi[0] || boxes[q].lo[1] > boxes[q].hi[1] || boxes[q].lo[2] > boxes[q].hi[2]) continue;
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
          const Box& bx = boxes[q];
          for (std::int64_t k = std::max(k0, bx.lo[2]); k <= std::min(k1 - 1, bx.hi[2]); ++k)
            for (std::int64_t j = bx.lo[1]; j <= bx.hi[1]; ++j)
              for (std::int64_t i = bx.lo[0]; i <= bx.hi[0]; ++i) {
                const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
                const double d = (closest_point_on_triangle_mm(p, a, b, c) - p).norm();
                float& slot = dist[out.linear_index(i, j, k)];
                if (d < slot) slot = static_cast<float>(d);
              }
        }
      },
      options.threaded, 1);

  // Sign: winding number at band voxels; one evaluation per connected far component.
  const geometry::WindingNumber winding(surface, {.beta = options.winding_beta});
  const auto total = static_cast<std::int64_t>(dist.size());
  const float fband = static_cast<float>(band);
  parallel_for(
      static_cast<std::size_t>(total),
      [&](std::size_t idx) {
        if (dist[idx] >= fband) return;
        const std::int64_t i = std::int64_t(idx) % n[0];
        const std::int64_t j = (std::int64_t(idx) / n[0]) % n[1];
        const std::int64_t k = std::int64_t(idx) / (n[0] * n[1]);
        const Vec3 p = grid.index_to_world(Vec3(double(i), double(j), double(k)));
        // Inside is strictly negative, also at a grid point lying on a counted triangle
        // (distance 0), so a zero-level extraction never sees an inside point as outside.
        if (winding.at(p) > 0.5) dist[idx] = -std::max(dist[idx], std::numeric_limits<float>::min());
      },
      options.threaded, 1024);
  std::vector<std::uint8_t> seen(dist.size(), 0);
  std::vector<std::int64_t> stack;
  for (std::int64_t start = 0; start < total; ++start) {
    if (seen[start] || dist[start] < fband) continue;
    const std::int64_t i0 = start % n[0], j0 = (start / n[0]) % n[1], k0 = start / (n[0] * n[1]);
    const bool inside =
        winding.at(grid.index_to_world(Vec3(double(i0), double(j0), double(k0)))) > 0.5;
    stack.push_back(start);
    seen[start] = 1;
    while (!stack.empty()) {
      const std::int64_t v = stack.back();
      stack.pop_back();
      if (inside) dist[v] = -fband;
      const std::int64_t i = v % n[0], j = (v / n[0]) % n[1], k = v / (n[0] * n[1]);
      const std::int64_t nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k},
                                     {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
      for (const auto& q : nb) {
        if (!out.contains(q[0], q[1], q[2])) continue;
        const auto w = static_cast<std::int64_t>(out.linear_index(q[0], q[1], q[2]));
        if (seen[w] || dist[w] < fband) continue;
        seen[w] = 1;
        stack.push_back(w);
      }
    }
  }
  return out;
}

}  // namespace ido::meshing

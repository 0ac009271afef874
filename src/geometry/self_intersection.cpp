// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/self_intersection.h"


#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <mutex>

#include "ido/core/parallel.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/bvh.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/predicates.h"
#include "ido/geometry/triangle_intersection.h"

namespace ido::geometry {
namespace {

/// Reorders the corners of two triangles so that the shared vertex indices come first, in
/// the same order in both; returns the number of shared distinct indices.
int align_shared(const Tri& a, const Tri& b, std::array<int, 3>& pa, std::array<int, 3>& pb) {
  int shared = 0;
  std::array<bool, 3> used_a{false, false, false};
  std::array<bool, 3> used_b{false, false, false};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (!used_a[static_cast<std::size_t>(i)] && !used_b[static_cast<std::size_t>(j)] &&
          a[static_cast<std::size_t>(i)] == b[static_cast<std::size_t>(j)]) {
        used_a[static_cast<std::size_t>(i)] = used_b[static_cast<std::size_t>(j)] = true;
        pa[static_cast<std::size_t>(shared)] = i;
        pb[static_cast<std::size_t>(shared)] = j;
        ++shared;
        break;
      }
    }
  }
  int na = shared;
  int nb = shared;
  for (int i = 0; i < 3; ++i) {
    if (!used_a[static_cast<std::size_t>(i)]) pa[static_cast<std::size_t>(na++)] = i;
    if (!used_b[static_cast<std::size_t>(i)]) pb[static_cast<std::size_t>(nb++)] = i;
  }
  return shared;
}

bool pair_intersects(const std::vector<Vec3>& vertices, const Tri& ta, const Tri& tb) {
  std::array<int, 3> pa{};
  std::array<int, 3> pb{};
  const int shared = align_shared(ta, tb, pa, pb);
  auto at = [&](const Tri& t, int k) -> const Vec3& {
    return vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
  };
  const Triangle3 a{at(ta, pa[0]), at(ta, pa[1]), at(ta, pa[2])};
  const Triangle3 b{at(tb, pb[0]), at(tb, pb[1]), at(tb, pb[2])};
  if (shared == 0) return triangles_intersect(a, b);
  // Fast exits for the common neighbour pairs (the full test repeats them in rare cases).
  if (shared == 1) {
    if (sign_of(orient3d(b[0], b[1], b[2], a[1])) * sign_of(orient3d(b[0], b[1], b[2], a[2])) > 0) return false;
    if (sign_of(orient3d(a[0], a[1], a[2], b[1])) * sign_of(orient3d(a[0], a[1], a[2], b[2])) > 0) return false;
  } else if (shared == 2) {
    if (orient3d(a[0], a[1], a[2], b[2]) != 0.0) return false;
  }
  return adjacent_triangles_intersect(a, b, shared);
}

}  // namespace

bool mesh_triangles_intersect(const TriangleMesh& mesh, std::int32_t t1, std::int32_t t2) {
  const Tri& a = mesh.triangles[static_cast<std::size_t>(t1)];
  const Tri& b = mesh.triangles[static_cast<std::size_t>(t2)];
  return pair_intersects(mesh.vertices, a, b);
}

namespace {

using Pairs = std::vector<std::pair<std::int32_t, std::int32_t>>;

/// Broad phase on a uniform grid (cell size 2.5× the mean triangle box extent), the usual
/// case for surface meshes with triangles of similar size: each triangle is registered in
/// the cells its box overlaps (bucketed by a counting sort), every pair of triangles
/// sharing a cell has its boxes compared, and a pair is reported only by the cell holding
/// the lower corner of the two boxes' intersection (so exactly once). Returns false, doing
/// nothing, when the grid would be unreasonable (very uneven triangle sizes or a huge
/// grid): the caller then uses the BVH.
template <class Accept>
bool grid_pairs(const std::vector<Aabb>& boxes, const Accept& accept, bool threaded,
                bool first_only, Pairs& out) {
  const std::size_t n = boxes.size();
  Aabb all;
  double mean_extent = 0.0;
  for (const Aabb& b : boxes) {
    all.extend(b);
    mean_extent += b.extent().maxCoeff();
  }
  mean_extent /= static_cast<double>(n);
  const double h = 2.5 * mean_extent;
  if (!(h > 0.0)) return false;
  const Vec3 dims_real = (all.extent() / h).array().floor() + 1.0;
  if (dims_real.prod() > static_cast<double>(8 * n + 4096)) return false;
  const std::array<std::uint32_t, 3> dims{static_cast<std::uint32_t>(dims_real.x()),
                                          static_cast<std::uint32_t>(dims_real.y()),
                                          static_cast<std::uint32_t>(dims_real.z())};
  const double inv_h = 1.0 / h;
  auto cell = [&](double x, int k) {
    const double c = std::floor((x - all.min[k]) * inv_h);
    return static_cast<std::uint32_t>(std::clamp(c, 0.0, static_cast<double>(dims[static_cast<std::size_t>(k)] - 1)));
  };
  auto key = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return (static_cast<std::size_t>(z) * dims[1] + y) * dims[0] + x;
  };
  // Per triangle: its cell range.
  std::vector<std::array<std::uint32_t, 6>> range(n);
  std::size_t entries = 0;
  for (std::size_t t = 0; t < n; ++t) {
    std::size_t cells = 1;
    for (int k = 0; k < 3; ++k) {
      range[t][static_cast<std::size_t>(k)] = cell(boxes[t].min[k], k);
      range[t][static_cast<std::size_t>(k) + 3] = cell(boxes[t].max[k], k);
      cells *= range[t][static_cast<std::size_t>(k) + 3] - range[t][static_cast<std::size_t>(k)] + 1;
    }
    entries += cells;
    if (entries > 32 * n + 1024) return false;
  }
  // Counting sort of (cell, triangle) entries by cell; triangles stay ascending in a cell.
  const std::size_t ncells = static_cast<std::size_t>(dims_real.prod());
  std::vector<std::uint32_t> start(ncells + 1, 0);
  auto for_cells = [&](std::size_t t, auto&& f) {
    const auto& r = range[t];
    for (std::uint32_t z = r[2]; z <= r[5]; ++z) {
      for (std::uint32_t y = r[1]; y <= r[4]; ++y) {
        for (std::uint32_t x = r[0]; x <= r[3]; ++x) f(key(x, y, z));
      }
    }
  };
  for (std::size_t t = 0; t < n; ++t) for_cells(t, [&](std::size_t c) { ++start[c + 1]; });
  for (std::size_t c = 0; c < ncells; ++c) start[c + 1] += start[c];
  std::vector<std::int32_t> items(entries);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < n; ++t) {
      for_cells(t, [&](std::size_t c) { items[fill[c]++] = static_cast<std::int32_t>(t); });
    }
  }
  std::vector<std::uint32_t> busy;  // cells holding at least two triangles
  for (std::size_t c = 0; c < ncells; ++c) {
    if (start[c + 1] - start[c] >= 2) busy.push_back(static_cast<std::uint32_t>(c));
  }
  std::atomic<bool> stop{false};
  std::mutex merge;
  parallel_for_ranges(
      busy.size(),
      [&](std::size_t gb, std::size_t ge) {
        Pairs local;
        std::vector<Aabb> gathered;
        std::vector<std::array<std::uint32_t, 3>> low;
        for (std::size_t g = gb; g < ge; ++g) {
          if (first_only && stop.load(std::memory_order_relaxed)) break;
          const std::size_t c = busy[g];
          const std::uint32_t b = start[c];
          const std::uint32_t e = start[c + 1];
          gathered.clear();
          low.clear();
          for (std::uint32_t i = b; i < e; ++i) {
            const auto t = static_cast<std::size_t>(items[i]);
            gathered.push_back(boxes[t]);
            low.push_back({range[t][0], range[t][1], range[t][2]});
          }
          const std::uint32_t cz = static_cast<std::uint32_t>(c / (static_cast<std::size_t>(dims[0]) * dims[1]));
          const std::uint32_t cy = static_cast<std::uint32_t>((c / dims[0]) % dims[1]);
          const std::uint32_t cx = static_cast<std::uint32_t>(c % dims[0]);
          for (std::uint32_t i = 0; i < e - b; ++i) {
            const Aabb& bi = gathered[i];
            const auto& li = low[i];
            for (std::uint32_t j = i + 1; j < e - b; ++j) {
              // Owner test first (integers): the lower corner of the boxes' intersection
              // lies in cell max(lo_i, lo_j), which must be this cell.
              const auto& lj = low[j];
              if (std::max(li[0], lj[0]) != cx || std::max(li[1], lj[1]) != cy ||
                  std::max(li[2], lj[2]) != cz) {
                continue;
              }
              if (!bi.overlaps(gathered[j])) continue;
              if (accept(items[b + i], items[b + j])) {
                local.emplace_back(items[b + i], items[b + j]);
                if (first_only) stop.store(true, std::memory_order_relaxed);
              }
            }
          }
        }
        if (!local.empty()) {
          const std::lock_guard<std::mutex> lock(merge);
          out.insert(out.end(), local.begin(), local.end());
        }
      },
      threaded, 64);
  std::sort(out.begin(), out.end());
  return true;
}

Pairs find_pairs(const TriangleMesh& mesh, const SelfIntersectionOptions& options, bool first_only) {
  validate_mesh(mesh);
  Pairs out;
  if (mesh.triangles.size() < 2) return out;
  std::vector<Aabb> boxes(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Tri& tri = mesh.triangles[t];
    boxes[t] = Aabb::of_triangle(mesh.vertices[static_cast<std::size_t>(tri[0])],
                                 mesh.vertices[static_cast<std::size_t>(tri[1])],
                                 mesh.vertices[static_cast<std::size_t>(tri[2])]);
  }
  auto accept = [&](std::int32_t i, std::int32_t j) {
    return pair_intersects(mesh.vertices, mesh.triangles[static_cast<std::size_t>(i)],
                           mesh.triangles[static_cast<std::size_t>(j)]);
  };
  if (grid_pairs(boxes, accept, options.threaded, first_only, out)) return out;
  const TriangleBvh bvh(mesh);
  if (first_only) {
    if (bvh.any_self_pair(accept, options.threaded)) out.emplace_back(-1, -1);
    return out;
  }
  return bvh.self_pairs(accept, options.threaded);
}

}  // namespace

std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections(
    const TriangleMesh& mesh, const SelfIntersectionOptions& options) {
  return find_pairs(mesh, options, false);
}

bool has_self_intersections(const TriangleMesh& mesh, const SelfIntersectionOptions& options) {
  return !find_pairs(mesh, options, true).empty();
}

}  // namespace ido::geometry

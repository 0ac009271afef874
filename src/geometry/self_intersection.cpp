// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/self_intersection.h"

#include <atomic>

#include "ido/geometry/bvh.h"
#include "ido/geometry/mesh_topology.h"
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

bool pair_intersects(const Tri& ta, const Triangle3& ca, const Tri& tb, const Triangle3& cb) {
  std::array<int, 3> pa{};
  std::array<int, 3> pb{};
  const int shared = align_shared(ta, tb, pa, pb);
  if (shared == 0) return triangles_intersect(ca, cb);
  const Triangle3 a{ca[static_cast<std::size_t>(pa[0])], ca[static_cast<std::size_t>(pa[1])],
                    ca[static_cast<std::size_t>(pa[2])]};
  const Triangle3 b{cb[static_cast<std::size_t>(pb[0])], cb[static_cast<std::size_t>(pb[1])],
                    cb[static_cast<std::size_t>(pb[2])]};
  return adjacent_triangles_intersect(a, b, shared);
}

}  // namespace

bool mesh_triangles_intersect(const TriangleMesh& mesh, std::int32_t t1, std::int32_t t2) {
  const Tri& a = mesh.triangles[static_cast<std::size_t>(t1)];
  const Tri& b = mesh.triangles[static_cast<std::size_t>(t2)];
  auto corners = [&](const Tri& t) {
    return Triangle3{mesh.vertices[static_cast<std::size_t>(t[0])], mesh.vertices[static_cast<std::size_t>(t[1])],
                     mesh.vertices[static_cast<std::size_t>(t[2])]};
  };
  return pair_intersects(a, corners(a), b, corners(b));
}

std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections(
    const TriangleMesh& mesh, const SelfIntersectionOptions& options) {
  const TriangleBvh bvh(mesh);
  return bvh.self_pairs(
      [&](std::int32_t i, std::int32_t j) {
        return pair_intersects(mesh.triangles[static_cast<std::size_t>(i)], bvh.corners(i),
                               mesh.triangles[static_cast<std::size_t>(j)], bvh.corners(j));
      },
      options.threaded);
}

bool has_self_intersections(const TriangleMesh& mesh, const SelfIntersectionOptions& options) {
  const TriangleBvh bvh(mesh);
  std::atomic<bool> found{false};
  (void)bvh.self_pairs(
      [&](std::int32_t i, std::int32_t j) {
        if (found.load(std::memory_order_relaxed)) return false;
        if (pair_intersects(mesh.triangles[static_cast<std::size_t>(i)], bvh.corners(i),
                            mesh.triangles[static_cast<std::size_t>(j)], bvh.corners(j))) {
          found.store(true, std::memory_order_relaxed);
        }
        return false;
      },
      options.threaded);
  return found.load();
}

}  // namespace ido::geometry

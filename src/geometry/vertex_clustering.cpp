// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/vertex_clustering.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "ido/core/error.h"
#include "ido/geometry/aabb.h"

namespace ido::geometry {

TriangleMesh cluster_vertices(const TriangleMesh& mesh, double cell_mm) {
  if (!(cell_mm > 0.0) || !std::isfinite(cell_mm))
    throw InvalidInput("vertex clustering: the cell size must be positive and finite, not " + std::to_string(cell_mm));
  TriangleMesh out;
  const std::size_t n = mesh.vertices.size();
  if (n == 0) return out;
  for (const Tri& t : mesh.triangles)
    for (const std::int32_t v : t)
      if (v < 0 || static_cast<std::size_t>(v) >= n) throw InvalidInput("vertex clustering: a triangle names a vertex out of range");

  // The grid: cubes of cell_mm from the bounding box's minimum; a cube's key is its linear index.
  const Aabb box = Aabb::of(mesh.vertices);
  const Vec3 &lo = box.min, &hi = box.max;
  std::array<std::uint64_t, 3> dims{};
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::floor((hi[a] - lo[a]) / cell_mm) + 1.0;
    if (!std::isfinite(d)) throw InvalidInput("vertex clustering: a vertex is not finite");
    cells *= d;
    if (cells > 4.6e18) throw InvalidInput("vertex clustering: the cell size makes more than 2^62 cells");
    dims[std::size_t(a)] = static_cast<std::uint64_t>(d);
  }
  auto cell_of = [&](const Vec3& p) {
    std::array<std::uint64_t, 3> c{};
    for (int a = 0; a < 3; ++a) {
      const double f = std::floor((p[a] - lo[a]) / cell_mm);
      c[std::size_t(a)] = std::min(dims[std::size_t(a)] - 1, static_cast<std::uint64_t>(std::max(0.0, f)));
    }
    return c[0] + dims[0] * (c[1] + dims[1] * c[2]);
  };

  // Cluster ids in key order (sorting, not hashing: the output does not depend on a hash).
  std::vector<std::pair<std::uint64_t, std::int32_t>> keyed(n);
  for (std::size_t i = 0; i < n; ++i) keyed[i] = {cell_of(mesh.vertices[i]), static_cast<std::int32_t>(i)};
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::int32_t> cluster(n);
  std::vector<Vec3> sum;
  std::vector<double> members;
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first) {
      sum.emplace_back(Vec3::Zero());
      members.push_back(0.0);
    }
    const auto v = static_cast<std::size_t>(keyed[i].second);
    cluster[v] = static_cast<std::int32_t>(sum.size() - 1);
    sum.back() += mesh.vertices[v];
    members.back() += 1.0;
  }
  std::vector<Vec3> centre(sum.size());
  for (std::size_t c = 0; c < sum.size(); ++c) centre[c] = sum[c] / members[c];

  // Triangles over three clusters, each written from its smallest cluster on (same cyclic
  // order, so the same orientation) so that repeats sort next to each other.
  const double min_double_area = 2e-9 * cell_mm * cell_mm;
  std::vector<Tri> tris;
  tris.reserve(mesh.triangles.size());
  for (const Tri& t : mesh.triangles) {
    Tri c = {cluster[std::size_t(t[0])], cluster[std::size_t(t[1])], cluster[std::size_t(t[2])]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    const Vec3& a = centre[std::size_t(c[0])];
    if ((centre[std::size_t(c[1])] - a).cross(centre[std::size_t(c[2])] - a).norm() <= min_double_area) continue;
    const auto first = static_cast<std::size_t>(std::min_element(c.begin(), c.end()) - c.begin());
    tris.push_back({c[first], c[(first + 1) % 3], c[(first + 2) % 3]});
  }
  std::sort(tris.begin(), tris.end());
  tris.erase(std::unique(tris.begin(), tris.end()), tris.end());

  // Only the clusters the kept triangles use, numbered in cluster order.
  std::vector<std::int32_t> new_id(centre.size(), -1);
  for (const Tri& t : tris)
    for (const std::int32_t c : t) new_id[std::size_t(c)] = 0;
  for (std::size_t c = 0; c < centre.size(); ++c)
    if (new_id[c] == 0) {
      new_id[c] = static_cast<std::int32_t>(out.vertices.size());
      out.vertices.push_back(centre[c]);
    }
  out.triangles.reserve(tris.size());
  for (const Tri& t : tris) out.triangles.push_back({new_id[std::size_t(t[0])], new_id[std::size_t(t[1])], new_id[std::size_t(t[2])]});
  return out;
}

TriangleMesh cluster_vertices_to(const TriangleMesh& mesh, std::size_t max_triangles) {
  if (max_triangles == 0) throw InvalidInput("vertex clustering: the triangle budget must be at least 1");
  if (mesh.triangles.size() <= max_triangles) return mesh;
  double area = 0.0;
  for (const Tri& t : mesh.triangles) {
    const Vec3& a = mesh.vertices.at(std::size_t(t[0]));
    area += 0.5 * (mesh.vertices.at(std::size_t(t[1])) - a).cross(mesh.vertices.at(std::size_t(t[2])) - a).norm();
  }
  // A surface crossing a cubic grid occupies about 1.5 cubes per cell² of area, and a
  // triangulation has about twice as many triangles as vertices.
  double cell = std::sqrt(3.0 * std::max(area, 1e-300) / static_cast<double>(max_triangles));
  for (;;) {
    TriangleMesh out = cluster_vertices(mesh, cell);
    if (out.triangles.size() <= max_triangles) return out;
    cell *= 1.2;
  }
}

}  // namespace ido::geometry

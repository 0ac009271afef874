// SPDX-License-Identifier: Apache-2.0
#include "ido/view/tet_section.h"

#include <algorithm>
#include <cmath>

#include "ido/core/error.h"
#include "ido/geometry/tet_quality.h"

namespace ido::view {
namespace {

void check_indices(const geometry::TetMesh& mesh) {
  const auto n = static_cast<std::int64_t>(mesh.vertices.size());
  for (const Tet& t : mesh.tets)
    for (std::int32_t v : t)
      if (v < 0 || v >= n) throw InvalidInput("tetrahedral mesh: a vertex index is out of range");
}

}  // namespace

TetSection tet_section(const geometry::TetMesh& mesh, const viz::ClipPlane& plane) {
  check_indices(mesh);
  if (!(plane.normal.norm() > 0)) throw InvalidInput("clip plane: the normal must not be zero");
  const Vec3 n = plane.normal.normalized();
  TetSection out;
  std::vector<double> side(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) side[i] = (mesh.vertices[i] - plane.point).dot(n);
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (const Tet& t : mesh.tets) {
    bool above = false, below = false;
    for (std::int32_t v : t) (side[std::size_t(v)] > 0 ? above : below) = true;
    if (!above || !below) continue;
    std::array<Vec3, 4> points;
    int count = 0;
    for (const auto& e : kEdges) {
      const auto a = std::size_t(t[std::size_t(e[0])]), b = std::size_t(t[std::size_t(e[1])]);
      const double da = side[a], db = side[b];
      if ((da > 0) == (db > 0)) continue;
      const double s = da / (da - db);
      points[std::size_t(count++)] = mesh.vertices[a] + s * (mesh.vertices[b] - mesh.vertices[a]);
    }
    if (count < 3) continue;
    // Order the polygon's corners by angle about their centroid, counter-clockwise about n.
    Vec3 c = Vec3::Zero();
    for (int i = 0; i < count; ++i) c += points[std::size_t(i)];
    c /= count;
    const Vec3 u = n.unitOrthogonal(), w = n.cross(u);
    std::array<std::pair<double, Vec3>, 4> ordered;
    for (int i = 0; i < count; ++i) {
      const Vec3 d = points[std::size_t(i)] - c;
      ordered[std::size_t(i)] = {std::atan2(d.dot(w), d.dot(u)), points[std::size_t(i)]};
    }
    std::sort(ordered.begin(), ordered.begin() + count, [](const auto& x, const auto& y) { return x.first < y.first; });
    const auto base = static_cast<std::int32_t>(out.faces.vertices.size());
    for (int i = 0; i < count; ++i) out.faces.vertices.push_back(ordered[std::size_t(i)].second);
    for (int i = 1; i + 1 < count; ++i) out.faces.triangles.push_back({base, base + i, base + i + 1});
    for (int i = 0; i < count; ++i)
      out.edges.push_back({ordered[std::size_t(i)].second, ordered[std::size_t((i + 1) % count)].second});
    ++out.cut_tets;
  }
  return out;
}

std::vector<std::size_t> dihedral_histogram(const geometry::TetMesh& mesh, int bins) {
  if (bins < 1 || bins > 3600) throw InvalidInput("dihedral histogram: bins must be 1..3600");
  check_indices(mesh);
  std::vector<std::size_t> counts(std::size_t(bins), 0);
  for (const Tet& t : mesh.tets) {
    const auto angles = geometry::dihedral_angles_deg(mesh.vertices[std::size_t(t[0])], mesh.vertices[std::size_t(t[1])],
                                                      mesh.vertices[std::size_t(t[2])], mesh.vertices[std::size_t(t[3])]);
    for (double a : angles) {
      if (!std::isfinite(a)) continue;
      const int b = std::clamp(static_cast<int>(a / 180.0 * bins), 0, bins - 1);
      ++counts[std::size_t(b)];
    }
  }
  return counts;
}

}  // namespace ido::view

// SPDX-License-Identifier: Apache-2.0
// Mesh → mask, the project's one voxelisation. Written by hand for ido: a scanline crossing
// count with exact orientation predicates and a symbolic perturbation, so a voxel centre on a
// shared edge or vertex is counted once; no packaged library gives that on an oriented,
// anisotropic image grid (ITK's TriangleMeshToBinaryImageFilter rounds such centres either way).
#include "ido/meshing/voxelize.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/geometry/predicates.h"

namespace ido::meshing {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

image::Volume<std::uint8_t> voxelize(const geometry::TriangleMesh& mesh, const image::GridGeometry& grid, const VoxelizeOptions& options) {
  image::Volume<std::uint8_t> out(grid.size, grid.spacing_mm, grid.origin_mm, grid.direction, 0);
  if (out.empty() || mesh.triangles.empty()) return out;
  const std::int64_t nx = grid.size[0], ny = grid.size[1], nz = grid.size[2];
  const std::size_t nv = mesh.vertices.size();
  std::vector<Vec3> q(nv);
  for (std::size_t m = 0; m < nv; ++m) {
    if (!mesh.vertices[m].allFinite()) throw InvalidInput("voxelize: vertex coordinate is not finite");
    q[m] = out.world_to_index(mesh.vertices[m]);
  }
  const double handed = out.world_to_index_matrix().determinant() < 0.0 ? -1.0 : 1.0;
  // Bin triangles by the (j, k) rows their (y, z) bounding box may cover.
  const std::size_t rows = std::size_t(ny * nz);
  std::vector<std::size_t> start(rows + 1, 0);
  std::vector<std::array<std::int64_t, 4>> span(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Tri& tri = mesh.triangles[t];
    for (int c = 0; c < 3; ++c)
      if (tri[std::size_t(c)] < 0 || std::size_t(tri[std::size_t(c)]) >= nv)
        throw InvalidInput("voxelize: triangle " + std::to_string(t) + " has a vertex index out of range");
    double ylo = kInf, yhi = -kInf, zlo = kInf, zhi = -kInf;
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = q[std::size_t(tri[std::size_t(c)])];
      ylo = std::min(ylo, p.y());
      yhi = std::max(yhi, p.y());
      zlo = std::min(zlo, p.z());
      zhi = std::max(zhi, p.z());
    }
    auto& s = span[t];
    s = {std::max<std::int64_t>(0, std::int64_t(std::floor(ylo))), std::min<std::int64_t>(ny - 1, std::int64_t(std::ceil(yhi))),
         std::max<std::int64_t>(0, std::int64_t(std::floor(zlo))), std::min<std::int64_t>(nz - 1, std::int64_t(std::ceil(zhi)))};
    for (std::int64_t k = s[2]; k <= s[3]; ++k)
      for (std::int64_t j = s[0]; j <= s[1]; ++j) ++start[std::size_t(j + ny * k) + 1];
  }
  for (std::size_t r = 0; r < rows; ++r) start[r + 1] += start[r];
  std::vector<std::int32_t> bins(start[rows]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& s = span[t];
      for (std::int64_t k = s[2]; k <= s[3]; ++k)
        for (std::int64_t j = s[0]; j <= s[1]; ++j) bins[fill[std::size_t(j + ny * k)]++] = std::int32_t(t);
    }
  }
  // Side of the query point (py, pz) + (ε, ε²) w.r.t. the directed edge a→b in the (y, z)
  // plane, ±1 (Simulation of Simplicity, Edelsbrunner & Mücke 1990, for the point only). The edge is evaluated in a canonical vertex order so the two triangles
  // sharing it get exactly opposite answers.
  auto side = [](const Vec3& a0, const Vec3& b0, double py, double pz) -> int {
    const bool swap = (b0.y() < a0.y()) || (b0.y() == a0.y() && b0.z() < a0.z());
    const Vec3& a = swap ? b0 : a0;
    const Vec3& b = swap ? a0 : b0;
    const double ey = b.y() - a.y(), ez = b.z() - a.z();
    // Exact sign (adaptive predicate), so the triangles around a vertex partition the plane.
    const double o = geometry::orient2d(Vec2(a.y(), a.z()), Vec2(b.y(), b.z()), Vec2(py, pz));
    int sgn = o > 0 ? 1 : o < 0 ? -1 : 0;
    if (sgn == 0) sgn = ez != 0 ? (ez < 0 ? 1 : -1) : (ey > 0 ? 1 : ey < 0 ? -1 : 0);
    return swap ? -sgn : sgn;
  };
  parallel_for_ranges(
      rows,
      [&](std::size_t rb, std::size_t re) {
        std::vector<std::pair<double, int>> hits;
        for (std::size_t r = rb; r < re; ++r) {
          if (start[r] == start[r + 1]) continue;
          const double py = double(std::int64_t(r) % ny), pz = double(std::int64_t(r) / ny);
          hits.clear();
          for (std::size_t b = start[r]; b < start[r + 1]; ++b) {
            const Tri& tri = mesh.triangles[std::size_t(bins[b])];
            const Vec3 &a = q[std::size_t(tri[0])], &bb = q[std::size_t(tri[1])], &c = q[std::size_t(tri[2])];
            const int s0 = side(a, bb, py, pz), s1 = side(bb, c, py, pz), s2 = side(c, a, py, pz);
            if (s0 == 0 || s0 != s1 || s1 != s2) continue;
            // Barycentric weights from the unperturbed sub-areas; x of the crossing.
            const double wa = (c.y() - bb.y()) * (pz - bb.z()) - (c.z() - bb.z()) * (py - bb.y());
            const double wb = (a.y() - c.y()) * (pz - c.z()) - (a.z() - c.z()) * (py - c.y());
            const double wc = (bb.y() - a.y()) * (pz - a.z()) - (bb.z() - a.z()) * (py - a.y());
            const double sum = wa + wb + wc;
            const double x = sum != 0.0 ? (wa * a.x() + wb * bb.x() + wc * c.x()) / sum : (a.x() + bb.x() + c.x()) / 3.0;
            // s0 > 0: the triangle is counter-clockwise in (y, z), its normal has +x: leaving.
            hits.emplace_back(x, s0 > 0 ? -1 : 1);
          }
          if (hits.empty()) continue;
          std::sort(hits.begin(), hits.end());
          std::uint8_t* row = out.data().data() + r * std::size_t(nx);
          int winding = 0;
          std::size_t h = 0;
          for (std::int64_t i = 0; i < nx; ++i) {
            while (h < hits.size() && hits[h].first < double(i)) winding += hits[h++].second;
            row[i] = winding * handed > 0 ? 1 : 0;
          }
        }
      },
      options.threaded, 16);
  return out;
}

}  // namespace ido::meshing

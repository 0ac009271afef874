// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/generators.h"

#include <array>
#include <cmath>
#include <string>
#include <unordered_map>

#include "ido/core/error.h"
#include "ido/sim/fem_common.h"

namespace ido::sim {

namespace {

// Cube corners by bit pattern: bit 0 = +x, bit 1 = +y, bit 2 = +z.
constexpr std::array<std::array<int, 4>, 6> kSix = {{{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                                     {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}}};
// Five tetrahedra: a central one on the odd-parity corners and four corner tetrahedra,
// or the mirror image (used on alternate cells so that face diagonals match).
constexpr std::array<std::array<int, 4>, 5> kFiveEven = {{{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7},
                                                          {5, 1, 4, 7}, {6, 2, 4, 7}}};
constexpr std::array<std::array<int, 4>, 5> kFiveOdd = {{{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 3, 6},
                                                         {4, 0, 5, 6}, {7, 3, 5, 6}}};

void add_oriented(geometry::TetMesh& mesh, Tet t) {
  const double v = tet_signed_volume(mesh.vertices[static_cast<std::size_t>(t[0])],
                                     mesh.vertices[static_cast<std::size_t>(t[1])],
                                     mesh.vertices[static_cast<std::size_t>(t[2])],
                                     mesh.vertices[static_cast<std::size_t>(t[3])]);
  if (v < 0.0) std::swap(t[2], t[3]);
  mesh.tets.push_back(t);
}

void split_cell(geometry::TetMesh& mesh, const std::array<std::int32_t, 8>& c, HexSplit split,
                bool odd) {
  if (split == HexSplit::Six) {
    for (const auto& t : kSix) add_oriented(mesh, {c[t[0]], c[t[1]], c[t[2]], c[t[3]]});
  } else {
    for (const auto& t : odd ? kFiveOdd : kFiveEven)
      add_oriented(mesh, {c[t[0]], c[t[1]], c[t[2]], c[t[3]]});
  }
}

}  // namespace

geometry::TetMesh make_beam(const Vec3& size_mm, const Vec3i& cells, const Vec3& origin_mm,
                            HexSplit split) {
  if (cells.minCoeff() < 1) throw InvalidInput("beam: every cell count must be at least 1");
  if (!(size_mm.minCoeff() > 0.0) || !size_mm.allFinite())
    throw InvalidInput("beam: every size must be positive");
  geometry::TetMesh mesh;
  const int nx = cells.x() + 1, ny = cells.y() + 1, nz = cells.z() + 1;
  mesh.vertices.reserve(static_cast<std::size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        mesh.vertices.push_back(origin_mm + Vec3(size_mm.x() * i / cells.x(), size_mm.y() * j / cells.y(),
                                                 size_mm.z() * k / cells.z()));
  auto id = [&](int i, int j, int k) { return static_cast<std::int32_t>(i + nx * (j + ny * k)); };
  for (int k = 0; k < cells.z(); ++k)
    for (int j = 0; j < cells.y(); ++j)
      for (int i = 0; i < cells.x(); ++i) {
        std::array<std::int32_t, 8> c;
        for (int b = 0; b < 8; ++b) c[static_cast<std::size_t>(b)] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        split_cell(mesh, c, split, ((i + j + k) & 1) != 0);
      }
  return mesh;
}

geometry::TetMesh make_cube(double edge_mm, int cells, const Vec3& centre_mm, HexSplit split) {
  return make_beam(Vec3::Constant(edge_mm), Vec3i::Constant(cells),
                   centre_mm - Vec3::Constant(0.5 * edge_mm), split);
}

geometry::TetMesh make_sphere(double radius_mm, int cells_per_radius, const Vec3& centre_mm) {
  if (!(radius_mm > 0.0) || !std::isfinite(radius_mm)) throw InvalidInput("sphere: radius must be positive");
  if (cells_per_radius < 1) throw InvalidInput("sphere: cells per radius must be at least 1");
  const int n = 2 * cells_per_radius;
  const double h = radius_mm / cells_per_radius;
  const Vec3 origin = centre_mm - Vec3::Constant(radius_mm);
  geometry::TetMesh mesh;
  std::unordered_map<std::int64_t, std::int32_t> index;
  auto vertex = [&](int i, int j, int k) {
    const std::int64_t key = (static_cast<std::int64_t>(k) * (n + 1) + j) * (n + 1) + i;
    const auto it = index.find(key);
    if (it != index.end()) return it->second;
    const auto id = static_cast<std::int32_t>(mesh.vertices.size());
    mesh.vertices.push_back(origin + h * Vec3(i, j, k));
    index.emplace(key, id);
    return id;
  };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 c = origin + h * Vec3(i + 0.5, j + 0.5, k + 0.5);
        if ((c - centre_mm).norm() > radius_mm) continue;
        std::array<std::int32_t, 8> cv;
        for (int b = 0; b < 8; ++b) cv[static_cast<std::size_t>(b)] = vertex(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        split_cell(mesh, cv, HexSplit::Six, false);
      }
  return mesh;
}

}  // namespace ido::sim

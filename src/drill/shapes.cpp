// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/shapes.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include "ido/core/error.h"
#include "ido/sim/generators.h"

namespace ido::drill {
namespace {

double signed_vol(const std::vector<Vec3>& v, const Tet& t) {
  const auto& a = v[static_cast<std::size_t>(t[0])];
  return (v[static_cast<std::size_t>(t[1])] - a).dot((v[static_cast<std::size_t>(t[2])] - a).cross(v[static_cast<std::size_t>(t[3])] - a));
}

void orient(geometry::TetMesh& m) {
  for (auto& t : m.tets)
    if (signed_vol(m.vertices, t) < 0.0) std::swap(t[2], t[3]);
}

double parse_number(std::string_view text, std::string_view spec) {
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v)) {
    throw InvalidInput("shape '" + std::string(spec) + "': '" + std::string(text) + "' is not a number");
  }
  return v;
}

}  // namespace

geometry::TetMesh make_cube12(double size_mm) {
  if (!(size_mm > 0.0)) throw InvalidInput("cube12: size must be positive");
  geometry::TetMesh m;
  for (int b = 0; b < 8; ++b) m.vertices.emplace_back((b & 1) * size_mm, ((b >> 1) & 1) * size_mm, ((b >> 2) & 1) * size_mm);
  m.vertices.emplace_back(0.5 * size_mm, 0.5 * size_mm, 0.5 * size_mm);
  // Faces as quads (corner bit patterns), each split along one diagonal.
  static constexpr int kQuads[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
  for (const auto& q : kQuads) {
    m.tets.push_back({q[0], q[1], q[2], 8});
    m.tets.push_back({q[0], q[2], q[3], 8});
  }
  orient(m);
  return m;
}

geometry::TetMesh make_block(const Vec3& size_mm, double cell_mm) {
  if (!(size_mm.minCoeff() > 0.0) || !size_mm.allFinite() || !(cell_mm > 0.0) || !std::isfinite(cell_mm)) {
    throw InvalidInput("block: sizes and cell size must be positive and finite");
  }
  std::array<int, 3> n{};
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    n[static_cast<std::size_t>(a)] = std::max(1, static_cast<int>(std::lround(size_mm[a] / cell_mm)));
    cells *= n[static_cast<std::size_t>(a)];
  }
  if (cells * 6.0 > 1e7) throw InvalidInput("block: more than 10^7 tetrahedra; use a larger cell");
  // The box's hexahedral grid and its 6-tetrahedron split are the simulation library's (one
  // generator for both): vertex (i, j, k) at size·(i, j, k)/n, the 6 Kuhn tetrahedra around
  // each cell's main diagonal, positively oriented.
  return sim::make_beam(size_mm, Vec3i(n[0], n[1], n[2]));
}

geometry::TetMesh make_shape(std::string_view spec) {
  if (spec == "cube") return make_block(Vec3::Ones(), 1.0);
  if (spec == "cube12") return make_cube12(1.0);
  if (spec.starts_with("block:")) {
    std::vector<double> v;
    std::string_view rest = spec.substr(6);
    while (!rest.empty()) {
      const auto comma = rest.find(',');
      v.push_back(parse_number(rest.substr(0, comma), spec));
      if (comma == std::string_view::npos) break;
      rest = rest.substr(comma + 1);
    }
    if (v.size() != 3 && v.size() != 4) {
      throw InvalidInput("shape '" + std::string(spec) + "': expected block:SX,SY,SZ[,CELL]");
    }
    const Vec3 size(v[0], v[1], v[2]);
    const double cell = v.size() == 4 ? v[3] : size.minCoeff() / 4.0;
    return make_block(size, cell);
  }
  throw InvalidInput("unknown shape '" + std::string(spec) + "' (expected cube, cube12 or block:SX,SY,SZ[,CELL])");
}

}  // namespace ido::drill

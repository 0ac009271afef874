// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/primitives.h"

#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "ido/core/error.h"

namespace ido::geometry {
namespace {

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

}  // namespace

TriangleMesh icosphere(const Vec3& centre_mm, double radius_mm, int subdivisions) {
  if (!(radius_mm > 0.0) || !std::isfinite(radius_mm) || !centre_mm.allFinite()) {
    throw InvalidInput("icosphere: radius must be finite and > 0, got " + std::to_string(radius_mm));
  }
  if (subdivisions < 0 || subdivisions > 10) {
    throw InvalidInput("icosphere: subdivisions must be in [0, 10], got " +
                       std::to_string(subdivisions));
  }
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> unit{{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                         {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                         {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (Vec3& v : unit) v.normalize();
  std::vector<Tri> tris{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                        {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                        {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                        {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> mid;
    auto midpoint = [&](std::int32_t a, std::int32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const auto id = static_cast<std::int32_t>(unit.size());
      unit.push_back((unit[at(a)] + unit[at(b)]).normalized());
      mid.emplace(key, id);
      return id;
    };
    std::vector<Tri> next;
    next.reserve(tris.size() * 4);
    for (const Tri& t : tris) {
      const std::int32_t ab = midpoint(t[0], t[1]);
      const std::int32_t bc = midpoint(t[1], t[2]);
      const std::int32_t ca = midpoint(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    tris = std::move(next);
  }
  TriangleMesh mesh;
  mesh.vertices.reserve(unit.size());
  for (const Vec3& u : unit) mesh.vertices.push_back(centre_mm + radius_mm * u);
  mesh.triangles = std::move(tris);
  return mesh;
}

TriangleMesh box_surface(const Vec3& min_mm, const Vec3& max_mm) {
  if (!min_mm.allFinite() || !max_mm.allFinite() || !(min_mm.array() < max_mm.array()).all()) {
    throw InvalidInput("box_surface: min must be finite and below max in every coordinate");
  }
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.emplace_back((i & 1) ? max_mm.x() : min_mm.x(), (i & 2) ? max_mm.y() : min_mm.y(),
                               (i & 4) ? max_mm.z() : min_mm.z());
  }
  // Vertex i has bits (x, y, z) = (i & 1, i & 2, i & 4).
  mesh.triangles = {{0, 2, 3}, {0, 3, 1},   // z = min, normal −z
                    {4, 5, 7}, {4, 7, 6},   // z = max, normal +z
                    {0, 1, 5}, {0, 5, 4},   // y = min, normal −y
                    {2, 6, 7}, {2, 7, 3},   // y = max, normal +y
                    {0, 4, 6}, {0, 6, 2},   // x = min, normal −x
                    {1, 3, 7}, {1, 7, 5}};  // x = max, normal +x
  return mesh;
}

TriangleMesh torus_surface(const Vec3& centre_mm, double major_mm, double minor_mm, int nu,
                           int nv) {
  if (!(minor_mm > 0.0) || !(major_mm > minor_mm) || !std::isfinite(major_mm) ||
      !centre_mm.allFinite()) {
    throw InvalidInput("torus_surface: need 0 < minor radius < major radius");
  }
  if (nu < 3 || nv < 3) throw InvalidInput("torus_surface: nu and nv must be >= 3");
  TriangleMesh mesh;
  for (int i = 0; i < nu; ++i) {
    const double u = 2.0 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2.0 * kPi * j / nv;
      const double rho = major_mm + minor_mm * std::cos(v);
      mesh.vertices.push_back(centre_mm +
                              Vec3(rho * std::cos(u), rho * std::sin(u), minor_mm * std::sin(v)));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      // (∂/∂u) × (∂/∂v) points outward, so (i,j) → (i+1,j) → (i+1,j+1) is counter-clockwise.
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return mesh;
}

TriangleMesh uv_cylinder(const Vec3& base_mm, const Vec3& top_mm, double radius_mm, int segments,
                         int rings) {
  if (!(radius_mm > 0.0) || !std::isfinite(radius_mm) || !base_mm.allFinite() ||
      !top_mm.allFinite() || (top_mm - base_mm).norm() == 0.0) {
    throw InvalidInput("uv_cylinder: need a radius > 0 and two distinct finite end points");
  }
  if (segments < 3 || rings < 1) throw InvalidInput("uv_cylinder: need segments >= 3 and rings >= 1");
  const Vec3 axis = (top_mm - base_mm).normalized();
  const Vec3 helper = std::abs(axis.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 e1 = axis.cross(helper).normalized();
  const Vec3 e2 = axis.cross(e1);  // (e1, e2, axis) right-handed
  TriangleMesh mesh;
  for (int r = 0; r <= rings; ++r) {
    const Vec3 c = base_mm + (top_mm - base_mm) * (static_cast<double>(r) / rings);
    for (int s = 0; s < segments; ++s) {
      const double a = 2.0 * kPi * s / segments;
      mesh.vertices.push_back(c + radius_mm * (std::cos(a) * e1 + std::sin(a) * e2));
    }
  }
  const auto base_centre = static_cast<std::int32_t>(mesh.vertices.size());
  mesh.vertices.push_back(base_mm);
  mesh.vertices.push_back(top_mm);
  auto id = [&](int r, int s) { return static_cast<std::int32_t>(r * segments + (s % segments)); };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      mesh.triangles.push_back({id(r, s), id(r, s + 1), id(r + 1, s + 1)});
      mesh.triangles.push_back({id(r, s), id(r + 1, s + 1), id(r + 1, s)});
    }
  }
  for (int s = 0; s < segments; ++s) {
    mesh.triangles.push_back({base_centre, id(0, s + 1), id(0, s)});
    mesh.triangles.push_back({base_centre + 1, id(rings, s), id(rings, s + 1)});
  }
  return mesh;
}

TetMesh box_tets(const Vec3& min_mm, const Vec3& max_mm, int n) {
  if (!min_mm.allFinite() || !max_mm.allFinite() || !(min_mm.array() < max_mm.array()).all()) {
    throw InvalidInput("box_tets: min must be finite and below max in every coordinate");
  }
  if (n < 1 || n > 200) throw InvalidInput("box_tets: n must be in [1, 200], got " + std::to_string(n));
  TetMesh mesh;
  const Vec3 step = (max_mm - min_mm) / n;
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        // Exact end coordinates on the box faces.
        mesh.vertices.emplace_back(i == n ? max_mm.x() : min_mm.x() + i * step.x(),
                                   j == n ? max_mm.y() : min_mm.y() + j * step.y(),
                                   k == n ? max_mm.z() : min_mm.z() + k * step.z());
      }
    }
  }
  auto id = [&](int i, int j, int k) { return static_cast<std::int32_t>((k * (n + 1) + j) * (n + 1) + i); };
  // Kuhn triangulation: for each permutation of the axes, the path 0 → e_p0 → e_p0+e_p1 → 111.
  constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        for (const auto& p : kPerm) {
          int c[3] = {0, 0, 0};
          std::array<std::int32_t, 4> tet{};
          tet[0] = id(i, j, k);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] = 1;
            tet[static_cast<std::size_t>(s) + 1] = id(i + c[0], j + c[1], k + c[2]);
          }
          // Even permutations give one orientation, odd ones the other: fix by a swap.
          const Vec3& a = mesh.vertices[at(tet[0])];
          const double vol = (mesh.vertices[at(tet[1])] - a)
                                 .dot((mesh.vertices[at(tet[2])] - a).cross(mesh.vertices[at(tet[3])] - a));
          if (vol < 0.0) std::swap(tet[2], tet[3]);
          mesh.tets.push_back(tet);
        }
      }
    }
  }
  return mesh;
}

}  // namespace ido::geometry

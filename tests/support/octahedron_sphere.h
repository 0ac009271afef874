// SPDX-License-Identifier: Apache-2.0
#pragma once
// A sphere triangulated by subdividing an octahedron and projecting onto the sphere. Tests
// use it as a reference surface built independently of the library's own icosphere.

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "ido/geometry/triangle_mesh.h"

namespace ido::test {

/// Closed, outward-oriented sphere of radius @p r (mm) about @p centre; 8·4^subdivisions
/// triangles.
inline geometry::TriangleMesh octahedron_sphere(const Vec3& centre, double r, int subdivisions) {
  geometry::TriangleMesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return mid[key] = int(m.vertices.size()) - 1;
    };
    std::vector<Tri> finer;
    for (const Tri& t : m.triangles) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      finer.push_back({t[0], a, c});
      finer.push_back({t[1], b, a});
      finer.push_back({t[2], c, b});
      finer.push_back({a, b, c});
    }
    m.triangles = std::move(finer);
  }
  for (auto& v : m.vertices) v = centre + v.normalized() * r;
  return m;
}

}  // namespace ido::test

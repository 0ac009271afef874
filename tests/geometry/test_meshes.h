// SPDX-License-Identifier: Apache-2.0
// Small meshes shared by the geometry tests.
#pragma once

#include <random>

#include "ido/geometry/triangle_mesh.h"

namespace ido::test {

/// Moves every vertex of @p mesh to a random place within @p amplitude_mm (uniform box).
inline geometry::TriangleMesh jittered(geometry::TriangleMesh mesh, double amplitude_mm,
                                       unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude_mm, amplitude_mm);
  for (Vec3& v : mesh.vertices) v += Vec3(u(rng), u(rng), u(rng));
  return mesh;
}

/// Concatenates two meshes (indices of @p b shifted).
inline geometry::TriangleMesh merged(geometry::TriangleMesh a, const geometry::TriangleMesh& b) {
  const auto shift = static_cast<std::int32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Tri t : b.triangles) {
    for (auto& v : t) v += shift;
    a.triangles.push_back(t);
  }
  return a;
}

}  // namespace ido::test

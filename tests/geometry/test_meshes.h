// SPDX-License-Identifier: Apache-2.0
// Small meshes shared by the geometry tests.
#pragma once

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

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

/// @p mesh with its vertices and triangles in random order drawn from @p rng (the same
/// surface, no index locality left).
template <class Rng>
geometry::TriangleMesh shuffled(geometry::TriangleMesh mesh, Rng&& rng) {
  std::vector<std::int32_t> new_id(mesh.vertices.size());
  for (std::size_t v = 0; v < new_id.size(); ++v) new_id[v] = static_cast<std::int32_t>(v);
  std::shuffle(new_id.begin(), new_id.end(), rng);
  std::vector<Vec3> vertices(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) vertices[static_cast<std::size_t>(new_id[v])] = mesh.vertices[v];
  mesh.vertices = std::move(vertices);
  for (Tri& t : mesh.triangles) {
    for (auto& i : t) i = new_id[static_cast<std::size_t>(i)];
  }
  std::shuffle(mesh.triangles.begin(), mesh.triangles.end(), rng);
  return mesh;
}

}  // namespace ido::test

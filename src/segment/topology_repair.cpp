// SPDX-License-Identifier: Apache-2.0
// The balloon's topology repair: signed distance from the non-intersecting faces, its zero
// level by the project's marching cubes, remeshed. Written by hand for ido.
#include "ido/segment/topology_repair.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/meshing/marching_cubes.h"
#include "ido/meshing/remesh.h"
#include "ido/meshing/signed_distance.h"

namespace ido::segment {

namespace {

// Keeps the connected components whose enclosed volume reaches min_volume.
geometry::TriangleMesh drop_small_components(const geometry::TriangleMesh& mesh, double min_volume) {
  const auto nv = static_cast<std::int32_t>(mesh.vertices.size());
  std::vector<std::int32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Tri& t : mesh.triangles) {
    parent[find(t[0])] = find(t[1]);
    parent[find(t[1])] = find(t[2]);
  }
  std::unordered_map<std::int32_t, double> volume;
  for (const Tri& t : mesh.triangles)
    volume[find(t[0])] += mesh.vertices[t[0]].dot(mesh.vertices[t[1]].cross(mesh.vertices[t[2]])) / 6.0;
  geometry::TriangleMesh out;
  std::vector<std::int32_t> remap(mesh.vertices.size(), -1);
  for (const Tri& t : mesh.triangles) {
    if (volume[find(t[0])] < min_volume) continue;
    Tri nt;
    for (int k = 0; k < 3; ++k) {
      if (remap[t[k]] < 0) {
        remap[t[k]] = static_cast<std::int32_t>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[t[k]]);
      }
      nt[k] = remap[t[k]];
    }
    out.triangles.push_back(nt);
  }
  (void)nv;
  return out;
}

}  // namespace

geometry::TriangleMesh repair_topology(
    const geometry::TriangleMesh& mesh,
    const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const TopologyRepairOptions& options) {
  if (mesh.triangles.empty()) throw InvalidInput("topology repair: the mesh has no triangles");
  if (!(options.grid_spacing_mm > 0) || !(options.target_edge_mm > 0))
    throw InvalidInput("topology repair: grid spacing and target edge must be positive");
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double h = options.grid_spacing_mm;
  const Vec3 origin = lo - Vec3::Constant(3 * h);
  Index3 size;
  for (int a = 0; a < 3; ++a) size[a] = static_cast<std::int64_t>(std::ceil((hi[a] - lo[a]) / h)) + 7;
  const image::Volume<float> grid(size, Vec3::Constant(h), origin);
  meshing::SignedDistanceOptions sd;
  sd.threaded = options.threaded;
  // Marching cubes reads only the ends of grid edges the zero level crosses, within one
  // spacing of the surface: a band just above the spacing gives the same level as a wider one
  // (bit for bit on the three real cases) with far fewer distance queries than 2 h.
  sd.band_mm = 1.05 * h;
  if (!intersecting_pairs.empty()) {
    sd.distance_triangles.assign(mesh.triangles.size(), 1);
    for (const auto& [a, b] : intersecting_pairs) {
      if (a >= 0 && std::size_t(a) < mesh.triangles.size()) sd.distance_triangles[a] = 0;
      if (b >= 0 && std::size_t(b) < mesh.triangles.size()) sd.distance_triangles[b] = 0;
    }
  }
  const image::Volume<float> field = meshing::signed_distance(mesh, grid, sd);
  geometry::TriangleMesh level = meshing::marching_cubes(field, {.iso_value = 0.0f, .threaded = options.threaded});
  if (options.min_component_volume_mm3 > 0) level = drop_small_components(level, options.min_component_volume_mm3);
  if (level.triangles.empty() || !options.remesh) return level;
  meshing::RemeshOptions ro;
  ro.target_edge_mm = options.target_edge_mm;
  ro.iterations = 3;
  return meshing::remesh(level, ro);
}

}  // namespace ido::segment

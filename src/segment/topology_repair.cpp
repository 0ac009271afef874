// SPDX-License-Identifier: Apache-2.0
// The balloon's topology repair: signed distance from the non-intersecting faces, its zero
// level by the project's marching cubes, remeshed; and the local repair of folds. Written by
// hand for ido.
#include "ido/segment/topology_repair.h"

#include <algorithm>
#include <cmath>

#include "ido/core/error.h"
#include "ido/core/math.h"
#include "ido/core/parallel.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/self_intersection.h"
#include "ido/geometry/winding_number.h"
#include "ido/meshing/marching_cubes.h"
#include "ido/meshing/remesh.h"
#include "ido/meshing/signed_distance.h"

namespace ido::segment {

geometry::TriangleMesh keep_components(const geometry::TriangleMesh& mesh, double min_volume_mm3,
                                       const std::vector<Vec3>& keep_points_mm) {
  const std::vector<std::int32_t> component = geometry::triangle_components(mesh);
  std::size_t nc = 0;
  for (std::int32_t c : component) nc = std::max(nc, std::size_t(c) + 1);
  std::vector<double> volume(nc, 0.0);
  // winding[c · P + q]: component c's winding number at point q (Σ solid angles / 4π).
  const std::size_t np = keep_points_mm.size();
  std::vector<double> winding(nc * np, 0.0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto c = std::size_t(component[t]);
    const Vec3 &a = mesh.vertices[mesh.triangles[t][0]], &b = mesh.vertices[mesh.triangles[t][1]],
               &d = mesh.vertices[mesh.triangles[t][2]];
    volume[c] += a.dot(b.cross(d)) / 6.0;
    for (std::size_t q = 0; q < np; ++q) winding[c * np + q] += geometry::solid_angle(keep_points_mm[q], a, b, d);
  }
  std::vector<std::uint8_t> keep(nc, 0), holds(nc, 0);
  bool any_holds = false;
  for (std::size_t c = 0; c < nc; ++c) {
    keep[c] = volume[c] >= min_volume_mm3 ? 1 : 0;
    for (std::size_t q = 0; q < np; ++q) holds[c] |= winding[c * np + q] / (4.0 * kPi) > 0.5 ? 1 : 0;
    any_holds |= keep[c] && holds[c];
  }
  if (any_holds)
    for (std::size_t c = 0; c < nc; ++c) keep[c] &= holds[c];
  // Vertices renumbered in order of first use by a kept triangle.
  geometry::TriangleMesh out;
  std::vector<std::int32_t> remap(mesh.vertices.size(), -1);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!keep[std::size_t(component[t])]) continue;
    Tri nt;
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = mesh.triangles[t][k];
      if (remap[std::size_t(v)] < 0) {
        remap[std::size_t(v)] = static_cast<std::int32_t>(out.vertices.size());
        out.vertices.push_back(mesh.vertices[std::size_t(v)]);
      }
      nt[k] = remap[std::size_t(v)];
    }
    out.triangles.push_back(nt);
  }
  return out;
}

geometry::TriangleMesh repair_topology(
    const geometry::TriangleMesh& mesh,
    const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const TopologyRepairOptions& options) {
  if (mesh.triangles.empty()) throw InvalidInput("topology repair: the mesh has no triangles");
  if (!(options.grid_spacing_mm > 0) || !(options.target_edge_mm > 0))
    throw InvalidInput("topology repair: grid spacing and target edge must be positive");
  const double h = options.grid_spacing_mm;
  const image::Volume<float> grid = meshing::distance_grid(mesh, h, 3);
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
  if (options.min_component_volume_mm3 > 0 || !options.keep_points_mm.empty())
    level = keep_components(level, options.min_component_volume_mm3, options.keep_points_mm);
  if (level.triangles.empty() || !options.remesh) return level;
  meshing::RemeshOptions ro;
  ro.target_edge_mm = options.target_edge_mm;
  ro.iterations = 3;
  return meshing::remesh(level, ro);
}

std::optional<std::vector<std::int32_t>> untangle_folds(
    geometry::TriangleMesh& mesh, const std::vector<std::pair<std::int32_t, std::int32_t>>& intersecting_pairs,
    const std::vector<std::uint8_t>& fixed, const FoldRepairOptions& options) {
  const std::size_t n = mesh.vertices.size();
  if (intersecting_pairs.empty() || options.rings < 0 || options.rounds <= 0) return std::nullopt;
  if (!fixed.empty() && fixed.size() != n)
    throw InvalidInput("untangle folds: fixed flags must be empty or one per vertex");
  // Vertex → neighbours (CSR): each triangle a→b gives a its neighbour b; on a closed
  // manifold every neighbour appears exactly once.
  std::vector<std::int32_t> first(n + 1, 0), nb(3 * mesh.triangles.size());
  for (const Tri& t : mesh.triangles)
    for (std::int32_t v : t) ++first[std::size_t(v) + 1];
  for (std::size_t i = 0; i < n; ++i) first[i + 1] += first[i];
  {
    std::vector<std::int32_t> at(first.begin(), first.end() - 1);
    for (const Tri& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) nb[std::size_t(at[std::size_t(t[k])]++)] = t[(k + 1) % 3];
  }
  // Every pair must be a fold: breadth-first from one triangle's corners, options.rings deep,
  // meets a corner of the other.
  std::vector<std::uint32_t> mark(n, 0);
  std::uint32_t stamp = 0;
  std::vector<std::int32_t> ring, next_ring;
  for (const auto& [a, b] : intersecting_pairs) {
    ++stamp;
    ring.assign(mesh.triangles[std::size_t(a)].begin(), mesh.triangles[std::size_t(a)].end());
    for (std::int32_t v : ring) mark[std::size_t(v)] = stamp;
    for (int r = 0; r < options.rings; ++r) {
      next_ring.clear();
      for (std::int32_t v : ring)
        for (std::int32_t q = first[std::size_t(v)]; q < first[std::size_t(v) + 1]; ++q)
          if (const std::int32_t w = nb[std::size_t(q)]; mark[std::size_t(w)] != stamp) {
            mark[std::size_t(w)] = stamp;
            next_ring.push_back(w);
          }
      ring.swap(next_ring);
    }
    const Tri& tb = mesh.triangles[std::size_t(b)];
    if (mark[std::size_t(tb[0])] != stamp && mark[std::size_t(tb[1])] != stamp && mark[std::size_t(tb[2])] != stamp)
      return std::nullopt;
  }
  // The region: the intersecting triangles' corners and their one-ring.
  std::vector<std::uint8_t> in_region(n, 0);
  std::vector<std::int32_t> region;
  auto add = [&](std::int32_t v) {
    if (!in_region[std::size_t(v)]) {
      in_region[std::size_t(v)] = 1;
      region.push_back(v);
    }
  };
  for (const auto& [a, b] : intersecting_pairs)
    for (std::int32_t t : {a, b})
      for (std::int32_t v : mesh.triangles[std::size_t(t)]) add(v);
  auto grow = [&] {
    const std::size_t m = region.size();
    for (std::size_t r = 0; r < m; ++r)
      for (std::int32_t q = first[std::size_t(region[r])]; q < first[std::size_t(region[r]) + 1]; ++q)
        add(nb[std::size_t(q)]);
  };
  grow();
  geometry::TriangleMesh work = mesh;
  std::vector<Vec3> moved;
  for (int round = 0; round < options.rounds; ++round) {
    for (int pass = 0; pass < 2; ++pass) {
      moved.resize(region.size());
      for (std::size_t r = 0; r < region.size(); ++r) {
        const auto v = std::size_t(region[r]);
        moved[r] = work.vertices[v];
        if ((!fixed.empty() && fixed[v]) || first[v + 1] == first[v]) continue;
        Vec3 c = Vec3::Zero();
        for (std::int32_t q = first[v]; q < first[v + 1]; ++q) c += work.vertices[std::size_t(nb[std::size_t(q)])];
        c /= double(first[v + 1] - first[v]);
        moved[r] = 0.5 * (work.vertices[v] + c);
      }
      for (std::size_t r = 0; r < region.size(); ++r) work.vertices[std::size_t(region[r])] = moved[r];
    }
    // The region meets nothing when no triangle with a corner in it intersects any other.
    std::vector<std::uint8_t> region_triangles(work.triangles.size());
    for (std::size_t t = 0; t < work.triangles.size(); ++t) {
      const Tri& tr = work.triangles[t];
      region_triangles[t] = in_region[std::size_t(tr[0])] | in_region[std::size_t(tr[1])] | in_region[std::size_t(tr[2])];
    }
    if (geometry::self_intersections_touching(work, region_triangles, {.threaded = options.threaded}).empty()) {
      mesh.vertices = std::move(work.vertices);
      return region;
    }
    grow();
  }
  return std::nullopt;
}

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
// Calcified plaque next to a segmented lumen: a reach-limited growth over
// bright voxels and the union of the two as one level set. Written by hand for
// ido.
#include "ido/segment/calcification.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <unordered_map>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/core/statistics.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/self_intersection.h"
#include "ido/image/filters.h"
#include "ido/meshing/marching_cubes.h"
#include "ido/meshing/remesh.h"
#include "ido/meshing/signed_distance.h"
#include "ido/segment/balloon.h"
#include "ido/segment/topology_repair.h"

namespace ido::segment {
namespace {

constexpr std::array<std::array<int, 3>, 6> kFaceSteps = {
    {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};

/// Plaque voxels (1) on the grid of @p ct: the reach-limited growth from the
/// lumen mask, then pieces smaller than min_voxels removed.
image::Volume<std::uint8_t> grow_plaque(const image::Volume<std::uint8_t> &lumen, const image::Volume<float> &ct,
                                        const CalcificationOptions &o) {
  const Index3 n = ct.size();
  image::Volume<std::uint8_t> plaque = lumen.like(std::uint8_t{0});
  std::vector<std::uint8_t> queued(ct.voxel_count(), 0);
  std::unordered_map<std::size_t, Vec3> source;  // queued voxel → world position of its lumen voxel
  std::deque<Index3> queue;
  auto world = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return ct.index_to_world(Vec3(double(i), double(j), double(k)));
  };
  auto try_queue = [&](std::int64_t i, std::int64_t j, std::int64_t k, const Vec3 &from) {
    if (!ct.contains(i, j, k)) return;
    const std::size_t li = ct.linear_index(i, j, k);
    if (queued[li] || lumen.data()[li] || !(ct.data()[li] > o.threshold)) return;
    if ((world(i, j, k) - from).norm() > o.max_reach_mm) return;
    queued[li] = 1;
    source.emplace(li, from);
    queue.push_back({i, j, k});
  };
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        if (!lumen(i, j, k)) continue;
        const Vec3 from = world(i, j, k);
        for (const auto &d : kFaceSteps) try_queue(i + d[0], j + d[1], k + d[2], from);
      }
  while (!queue.empty()) {
    const Index3 v = queue.front();
    queue.pop_front();
    plaque(v[0], v[1], v[2]) = 1;
    const Vec3 from = source.at(ct.linear_index(v[0], v[1], v[2]));
    for (const auto &d : kFaceSteps) try_queue(v[0] + d[0], v[1] + d[1], v[2] + d[2], from);
  }
  if (o.min_voxels <= 1) return plaque;
  // Face-connected pieces; small ones are noise above the threshold.
  std::vector<std::uint8_t> seen(ct.voxel_count(), 0);
  std::vector<Index3> piece;
  for (std::size_t start = 0; start < plaque.voxel_count(); ++start) {
    if (!plaque.data()[start] || seen[start]) continue;
    piece.clear();
    const auto ni = static_cast<std::int64_t>(start) % n[0];
    const auto nj = (static_cast<std::int64_t>(start) / n[0]) % n[1];
    const auto nk = static_cast<std::int64_t>(start) / (n[0] * n[1]);
    seen[start] = 1;
    piece.push_back({ni, nj, nk});
    for (std::size_t q = 0; q < piece.size(); ++q) {
      const Index3 v = piece[q];
      for (const auto &d : kFaceSteps) {
        const std::int64_t i = v[0] + d[0], j = v[1] + d[1], k = v[2] + d[2];
        if (!ct.contains(i, j, k)) continue;
        const std::size_t li = ct.linear_index(i, j, k);
        if (plaque.data()[li] && !seen[li]) {
          seen[li] = 1;
          piece.push_back({i, j, k});
        }
      }
    }
    if (static_cast<std::int64_t>(piece.size()) < o.min_voxels)
      for (const Index3 &v : piece) plaque(v[0], v[1], v[2]) = 0;
  }
  return plaque;
}


}  // namespace

CalcificationResult add_calcification(const geometry::TriangleMesh &lumen, const image::Volume<float> &ct,
                                      const CalcificationOptions &o) {
  if (ct.empty()) throw InvalidInput("calcification: the image is empty");
  if (lumen.triangles.empty()) throw InvalidInput("calcification: the lumen surface has no triangles");
  if (!std::isfinite(o.threshold)) throw InvalidInput("calcification: the threshold must be a finite number");
  if (!(o.max_reach_mm > 0))
    throw InvalidInput(fmt::format("calcification: the reach must be positive, got {} mm", o.max_reach_mm));

  const image::Volume<std::uint8_t> lumen_mask = surface_to_mask(lumen, ct, o.threaded);
  const image::Volume<std::uint8_t> plaque = grow_plaque(lumen_mask, ct, o);
  CalcificationResult out;
  std::vector<double> plaque_values;
  geometry::Aabb box = geometry::Aabb::of(lumen.vertices);
  const Index3 n = ct.size();
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        if (!plaque(i, j, k)) continue;
        plaque_values.push_back(ct(i, j, k));
        const Vec3 p = ct.index_to_world(Vec3(double(i), double(j), double(k)));
        box.extend(p);
      }
  out.plaque_voxels = static_cast<std::int64_t>(plaque_values.size());
  out.plaque_volume_mm3 = double(out.plaque_voxels) * ct.spacing().prod();
  if (plaque_values.empty()) {
    out.surface = lumen;
    return out;
  }

  // Non-plaque voxels brighter than the threshold are clamped below it, so only
  // the plaque (and the lumen, through its own distance) can be inside. The
  // intensity field is scaled to about mm near the plaque's rim: (median plaque
  // − threshold) over one voxel.
  const double scale = std::max(1.0, median(plaque_values) - o.threshold);
  const double h = ct.spacing().minCoeff();
  image::Volume<float> plaque_image = ct;
  for (std::size_t li = 0; li < plaque_image.voxel_count(); ++li)
    if (!plaque.data()[li] && plaque_image.data()[li] > o.threshold)
      plaque_image.data()[li] = static_cast<float>(o.threshold - 0.5 * scale);
  // Bridges: a lumen voxel face-adjacent to plaque counts as bright, so a piece whose
  // intensity only just exceeds the threshold still joins the lumen instead of floating
  // beside it (the lumen's own surface may pass closer to its voxel centre than the
  // plaque's threshold crossing reaches).
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        if (!plaque(i, j, k)) continue;
        for (const auto& d : kFaceSteps) {
          const std::int64_t a = i + d[0], b = j + d[1], c = k + d[2];
          if (ct.contains(a, b, c) && lumen_mask(a, b, c))
            plaque_image(a, b, c) = std::max(plaque_image(a, b, c), static_cast<float>(o.threshold + 0.5 * scale));
        }
      }

  const double margin = 3.0 * ct.spacing().maxCoeff();
  box = box.inflated(margin);
  const Vec3 &lo = box.min, &hi = box.max;
  Index3 size;
  for (int a = 0; a < 3; ++a) size[a] = static_cast<std::int64_t>(std::ceil((hi[a] - lo[a]) / h)) + 1;
  meshing::SignedDistanceOptions sd;
  sd.band_mm = 2.0 * h;
  sd.threaded = o.threaded;
  image::Volume<float> field = meshing::signed_distance(lumen, image::Volume<float>(size, Vec3::Constant(h), lo), sd);
  parallel_for(
      static_cast<std::size_t>(size[2]),
      [&](std::size_t kk) {
        const auto k = static_cast<std::int64_t>(kk);
        for (std::int64_t j = 0; j < size[1]; ++j)
          for (std::int64_t i = 0; i < size[0]; ++i) {
            const Vec3 p = field.index_to_world(Vec3(double(i), double(j), double(k)));
            const double c = (o.threshold - plaque_image.sample(p)) * ct.spacing().maxCoeff() / scale;
            field(i, j, k) = std::min(field(i, j, k), static_cast<float>(c));
          }
      },
      o.threaded, 1);
  // Pieces of plaque are joined to the lumen (bridges above), so a separate component smaller
  // than min_voxels voxels can only be a speck of the field.
  const geometry::TriangleMesh level =
      keep_components(meshing::marching_cubes(field, {.iso_value = 0.0f, .threaded = o.threaded}),
                      double(std::max<std::int64_t>(o.min_voxels, 1)) * ct.spacing().prod());
  meshing::RemeshOptions ro;
  ro.target_edge_mm = h;
  ro.iterations = 3;
  out.surface = meshing::remesh(level, ro);
  // The marching-cubes level is free of self-intersections by construction; the remesher's
  // moves are not checked against distant parts, so keep the level when they met.
  if (geometry::has_self_intersections(out.surface)) out.surface = level;
  return out;
}

CalcificationResult add_calcification(BalloonResult &result, const image::Volume<float> &ct,
                                      const CalcificationOptions &options) {
  const IntensityModel &model = result.report.model;
  const double band_top = model.reference + model.tolerance;
  if (!model.accept_brighter && options.threshold <= band_top)
    throw InvalidInput(fmt::format("calcification: the threshold {:g} lies inside the lumen's accepted band (up to "
                                   "{:g}): give a threshold above it, or contrast would count as plaque",
                                   options.threshold, band_top));
  CalcificationResult out = add_calcification(result.surface, ct, options);
  result.surface = std::move(out.surface);
  out.surface = {};
  set_surface_figures(result.report, geometry::check_mesh(result.surface),
                      static_cast<std::int64_t>(geometry::self_intersections(result.surface).size()));
  return out;
}

}  // namespace ido::segment

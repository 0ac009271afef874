// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ido/core/math.h"
#include "ido/geometry/aabb.h"
#include "ido/image/volume.h"

namespace ido::image {

/// A box of voxel indices, inclusive on both ends: lo[a] ≤ index ≤ hi[a] on each axis. The
/// index-space counterpart of geometry::Aabb: the voxels a world box, a ball or a set of
/// voxels covers on a grid. Empty when hi < lo on some axis.
struct IndexBox {
  Index3 lo{0, 0, 0};
  Index3 hi{-1, -1, -1};

  /// The box of no voxel, which extend() grows.
  [[nodiscard]] static IndexBox none() noexcept {
    constexpr auto big = std::numeric_limits<std::int64_t>::max(), small = std::numeric_limits<std::int64_t>::min();
    return {{big, big, big}, {small, small, small}};
  }
  /// Every voxel of a grid of @p size.
  [[nodiscard]] static IndexBox of_grid(const Index3& size) noexcept {
    return {{0, 0, 0}, {size[0] - 1, size[1] - 1, size[2] - 1}};
  }
  /// The voxels whose centres (integer indices) lie in the continuous-index box
  /// [@p lo_index, @p hi_index], clipped to a grid of @p size.
  [[nodiscard]] static IndexBox of_centres(const Vec3& lo_index, const Vec3& hi_index, const Index3& size) {
    IndexBox b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(lo_index[a])));
      b.hi[a] = std::min<std::int64_t>(size[a] - 1, static_cast<std::int64_t>(std::floor(hi_index[a])));
    }
    return b;
  }

  [[nodiscard]] bool empty() const noexcept { return hi[0] < lo[0] || hi[1] < lo[1] || hi[2] < lo[2]; }
  /// Voxels along each axis (zeros when empty).
  [[nodiscard]] Index3 extent() const noexcept {
    if (empty()) return {0, 0, 0};
    return {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  }
  [[nodiscard]] bool contains(std::int64_t i, std::int64_t j, std::int64_t k) const noexcept {
    return i >= lo[0] && i <= hi[0] && j >= lo[1] && j <= hi[1] && k >= lo[2] && k <= hi[2];
  }
  /// Grows the box to hold voxel @p p.
  void extend(const Index3& p) noexcept {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  /// The box grown by @p voxels on every side, clipped to a grid of @p size.
  [[nodiscard]] IndexBox grown(std::int64_t voxels, const Index3& size) const noexcept {
    IndexBox b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::max<std::int64_t>(0, lo[a] - voxels);
      b.hi[a] = std::min<std::int64_t>(size[a] - 1, hi[a] + voxels);
    }
    return b;
  }
  /// Calls @p f(i, j, k) for every voxel of the box, i fastest, then j, then k (storage order).
  template <class F>
  void for_each(F&& f) const {
    for (std::int64_t k = lo[2]; k <= hi[2]; ++k)
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
        for (std::int64_t i = lo[0]; i <= hi[0]; ++i) f(i, j, k);
  }
};

/// The voxels of @p v whose centres lie in the world box @p world_mm (for a grid rotated
/// against the world axes: in the index-space bounds of the box's eight corners).
template <class T>
[[nodiscard]] IndexBox voxels_in_box(const Volume<T>& v, const geometry::Aabb& world_mm) {
  const geometry::Aabb idx = v.index_bounds(world_mm);
  return IndexBox::of_centres(idx.min, idx.max, v.size());
}

/// Calls @p f(i, j, k) for every voxel of @p v whose centre lies within @p radius_mm of
/// @p centre_mm (‖centre − x‖ ≤ radius, the norm compared, not its square), in storage order.
/// The candidates are the index-space box of the ball: |Δindex_a| ≤ radius · ‖row a of the
/// world-to-index map‖, exact for any grid direction.
template <class T, class F>
void for_each_voxel_in_ball(const Volume<T>& v, const Vec3& centre_mm, double radius_mm, F&& f) {
  const Vec3 c = v.world_to_index(centre_mm);
  Vec3 reach;
  for (int a = 0; a < 3; ++a) reach[a] = radius_mm * v.world_to_index_matrix().row(a).norm();
  IndexBox::of_centres(c - reach, c + reach, v.size()).for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) {
    if ((v.index_to_world(Vec3(double(i), double(j), double(k))) - centre_mm).norm() <= radius_mm) f(i, j, k);
  });
}

}  // namespace ido::image

// SPDX-License-Identifier: Apache-2.0
// Physical-space resampling (the project's own implementation of textbook trilinear and
// nearest-neighbour interpolation).
#include "ido/image/resample.h"

#include <algorithm>
#include <cmath>

#include "ido/core/error.h"
#include "ido/core/parallel.h"

namespace ido::image {
namespace {

/// Calls fn(target_voxel_linear_index, source_continuous_index) for every target voxel.
/// The composition of target index → world → source index is one affine map A·x + b.
template <class T, class Fn>
void for_each_target(const Volume<T>& src, const GridGeometry& grid, bool threaded, Fn fn) {
  const Mat3 a = src.world_to_index_matrix() * grid.direction * grid.spacing_mm.asDiagonal();
  const Vec3 b = src.world_to_index(grid.origin_mm);
  const std::int64_t nx = grid.size[0], ny = grid.size[1];
  parallel_for_ranges(
      static_cast<std::size_t>(ny * grid.size[2]),
      [&](std::size_t rb, std::size_t re) {
        for (std::size_t r = rb; r < re; ++r) {
          const std::int64_t j = static_cast<std::int64_t>(r) % ny;
          const std::int64_t k = static_cast<std::int64_t>(r) / ny;
          const Vec3 row0 = b + a.col(1) * double(j) + a.col(2) * double(k);
          for (std::int64_t i = 0; i < nx; ++i)
            fn(r * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i),
               Vec3(row0 + a.col(0) * double(i)));
        }
      },
      threaded, 16);
}

Volume<std::uint8_t> make_uint8(const GridGeometry& g) {
  return Volume<std::uint8_t>(g.size, g.spacing_mm, g.origin_mm, g.direction, 0);
}

}  // namespace

Volume<float> resample_linear(const Volume<float>& src, const GridGeometry& grid,
                              const ResampleOptions& options) {
  if (src.empty()) throw InvalidInput("resample_linear: empty source volume");
  Volume<float> out(grid.size, grid.spacing_mm, grid.origin_mm, grid.direction, 0.f);
  float* dst = out.data().data();
  for_each_target(src, grid, options.threaded, [&](std::size_t n, const Vec3& idx) {
    // Snap indices that are integers up to rounding so identical grids copy exactly.
    Vec3 x = idx;
    for (int a = 0; a < 3; ++a) {
      const double r = std::round(x[a]);
      if (std::abs(x[a] - r) < 1e-9) x[a] = r;
    }
    dst[n] = static_cast<float>(src.sample_index(x, Boundary::Constant, options.outside_value));
  });
  return out;
}

Volume<std::uint8_t> resample_nearest(const Volume<std::uint8_t>& src, const GridGeometry& grid,
                                      const ResampleOptions& options) {
  if (src.empty()) throw InvalidInput("resample_nearest: empty source volume");
  Volume<std::uint8_t> out = make_uint8(grid);
  const auto outside = static_cast<std::uint8_t>(std::clamp(options.outside_value, 0.0, 255.0));
  std::uint8_t* dst = out.data().data();
  const Index3 ns = src.size();
  for_each_target(src, grid, options.threaded, [&](std::size_t n, const Vec3& idx) {
    std::int64_t ii[3];
    for (int a = 0; a < 3; ++a) {
      // 1e-9 voxel tolerance so centres that coincide up to rounding pick the same voxel.
      ii[a] = static_cast<std::int64_t>(std::floor(idx[a] + 0.5 + 1e-9));
      if (ii[a] < 0 || ii[a] >= ns[a]) {
        dst[n] = outside;
        return;
      }
    }
    dst[n] = src(ii[0], ii[1], ii[2]);
  });
  return out;
}

}  // namespace ido::image

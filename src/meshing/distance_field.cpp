// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/distance_field.h"

#include <cmath>
#include <limits>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"

namespace ido::meshing {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// One-dimensional squared distance transform of sampled function f (n samples spaced
/// @p step mm apart): d[p] = min_q ((p − q)·step)² + f[q]. Lower envelope of parabolas,
/// Felzenszwalb & Huttenlocher 2012, section 3; samples with f = +inf are left out.
/// v, z are scratch of sizes n and n + 1.
void squared_distance_1d(const double* f, double* d, std::int64_t n, double step,
                         std::vector<std::int64_t>& v, std::vector<double>& z) {
  std::int64_t k = -1;
  auto intersect = [&](std::int64_t q, std::int64_t r) {
    // abscissa (in samples) where the parabolas rooted at q and r meet.
    const double fq = f[q] / (step * step), fr = f[r] / (step * step);
    return ((fq + double(q) * double(q)) - (fr + double(r) * double(r))) / (2.0 * double(q - r));
  };
  for (std::int64_t q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    double s = intersect(q, v[k]);
    while (s <= z[k]) {
      --k;
      if (k < 0) break;
      s = intersect(q, v[k]);
    }
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInf;
  }
  if (k < 0) {
    for (std::int64_t p = 0; p < n; ++p) d[p] = kInf;
    return;
  }
  std::int64_t j = 0;
  for (std::int64_t p = 0; p < n; ++p) {
    while (z[j + 1] < double(p)) ++j;
    const double dx = double(p - v[j]) * step;
    d[p] = dx * dx + f[v[j]];
  }
}

/// Squared Euclidean distance (mm²) from every voxel centre to the nearest voxel centre
/// where @p inside(value) holds, by three separable 1D passes.
template <class Pred>
std::vector<double> squared_edt(const image::Volume<std::uint8_t>& mask, Pred inside,
                                bool threaded) {
  const std::int64_t nx = mask.size(0), ny = mask.size(1), nz = mask.size(2);
  std::vector<double> g(mask.voxel_count());
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = inside(mask.data()[i]) ? 0.0 : kInf;
  const Vec3& sp = mask.spacing();
  const std::int64_t dims[3] = {nx, ny, nz};
  const std::int64_t strides[3] = {1, nx, nx * ny};
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t n = dims[axis];
    const std::int64_t stride = strides[axis];
    const std::int64_t a1 = (axis == 0) ? 1 : 0;
    const std::int64_t a2 = (axis == 2) ? 1 : 2;
    const std::int64_t lines = dims[a1] * dims[a2];
    parallel_for_ranges(
        static_cast<std::size_t>(lines),
        [&](std::size_t b, std::size_t e) {
          std::vector<double> f(static_cast<std::size_t>(n)), d(static_cast<std::size_t>(n));
          std::vector<std::int64_t> v(static_cast<std::size_t>(n));
          std::vector<double> z(static_cast<std::size_t>(n) + 1);
          for (std::size_t line = b; line < e; ++line) {
            const std::int64_t u = std::int64_t(line) % dims[a1];
            const std::int64_t w = std::int64_t(line) / dims[a1];
            const std::int64_t base = u * strides[a1] + w * strides[a2];
            for (std::int64_t p = 0; p < n; ++p) f[std::size_t(p)] = g[std::size_t(base + p * stride)];
            squared_distance_1d(f.data(), d.data(), n, sp[axis], v, z);
            for (std::int64_t p = 0; p < n; ++p) g[std::size_t(base + p * stride)] = d[std::size_t(p)];
          }
        },
        threaded, 16);
  }
  return g;
}

void require_mask(const image::Volume<std::uint8_t>& mask) {
  if (mask.empty()) throw InvalidInput("distance transform: the mask is empty (no voxels)");
}

}  // namespace

image::Volume<float> distance_to_mask(const image::Volume<std::uint8_t>& mask,
                                      const DistanceFieldOptions& options) {
  require_mask(mask);
  const auto g = squared_edt(mask, [](std::uint8_t x) { return x != 0; }, options.threaded);
  auto out = mask.like<float>();
  for (std::size_t i = 0; i < g.size(); ++i) out.data()[i] = static_cast<float>(std::sqrt(g[i]));
  return out;
}

image::Volume<float> signed_distance_from_mask(const image::Volume<std::uint8_t>& mask,
                                               const DistanceFieldOptions& options) {
  require_mask(mask);
  const auto to_inside = squared_edt(mask, [](std::uint8_t x) { return x != 0; }, options.threaded);
  const auto to_outside =
      squared_edt(mask, [](std::uint8_t x) { return x == 0; }, options.threaded);
  auto out = mask.like<float>();
  for (std::size_t i = 0; i < to_inside.size(); ++i) {
    out.data()[i] = mask.data()[i] != 0 ? -static_cast<float>(std::sqrt(to_outside[i]))
                                        : static_cast<float>(std::sqrt(to_inside[i]));
  }
  return out;
}

}  // namespace ido::meshing

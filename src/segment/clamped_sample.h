// SPDX-License-Identifier: Apache-2.0
// Private to the segment module: the trilinear sampling the balloon does millions of times.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"

namespace ido::segment::detail {

/// The same value as @p volume.sample(world_mm) with Boundary::Clamp (the same operations in
/// the same order, so bit-identical), without its three calls to floor(): after the clamp the
/// continuous index is ≥ 0, where truncation is floor. World millimetres in, the volume's
/// units out.
inline double sample_clamped(const image::Volume<float>& volume, const Vec3& world_mm) noexcept {
  const std::vector<float>& data = volume.data();
  if (data.empty()) return 0.0;
  const Vec3 index = volume.world_to_index(world_mm);
  double f[3];
  std::int64_t i0[3], i1[3];
  for (int a = 0; a < 3; ++a) {
    const std::int64_t n = volume.size(a);
    const double hi = double(n - 1);
    double x = index[a];
    if (!(x >= 0.0 && x <= hi)) x = std::clamp(std::isnan(x) ? 0.0 : x, 0.0, hi);
    i0[a] = std::min<std::int64_t>(static_cast<std::int64_t>(x), std::max<std::int64_t>(n - 2, 0));
    f[a] = x - double(i0[a]);
    i1[a] = std::min(i0[a] + 1, n - 1);
  }
  const std::int64_t sy = volume.size(0), sz = volume.size(0) * volume.size(1);
  auto v = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return static_cast<double>(data[static_cast<std::size_t>(i + sy * j + sz * k)]);
  };
  const double c00 = v(i0[0], i0[1], i0[2]) * (1 - f[0]) + v(i1[0], i0[1], i0[2]) * f[0];
  const double c10 = v(i0[0], i1[1], i0[2]) * (1 - f[0]) + v(i1[0], i1[1], i0[2]) * f[0];
  const double c01 = v(i0[0], i0[1], i1[2]) * (1 - f[0]) + v(i1[0], i0[1], i1[2]) * f[0];
  const double c11 = v(i0[0], i1[1], i1[2]) * (1 - f[0]) + v(i1[0], i1[1], i1[2]) * f[0];
  const double c0 = c00 * (1 - f[1]) + c10 * f[1];
  const double c1 = c01 * (1 - f[1]) + c11 * f[1];
  return c0 * (1 - f[2]) + c1 * f[2];
}

}  // namespace ido::segment::detail

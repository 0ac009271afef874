// SPDX-License-Identifier: Apache-2.0
// A random mask on a small anisotropic grid, for tests that check a mask ↔ surface round trip.
#pragma once
#include <cstdint>
#include <random>

#include "ido/image/volume.h"

namespace ido::test {

/// A mask of 1..@p max_dim voxels per axis (spacing 1 × 0.8 × 1.3 mm), each voxel inside with
/// probability @p fill.
inline image::Volume<std::uint8_t> random_mask(std::mt19937& rng, int max_dim, double fill) {
  std::uniform_int_distribution<int> dim(1, max_dim);
  std::bernoulli_distribution b(fill);
  image::Volume<std::uint8_t> m({dim(rng), dim(rng), dim(rng)}, Vec3(1.0, 0.8, 1.3));
  for (auto& x : m.data()) x = b(rng);
  return m;
}

}  // namespace ido::test

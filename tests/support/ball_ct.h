// SPDX-License-Identifier: Apache-2.0
// A small synthetic CT shared by the tests that segment one ball (the window's tests).
#pragma once
#include <cstdint>

#include "ido/image/volume.h"

namespace ido::test {

/// A 28 × 32 × 26 CT (anisotropic voxels 1.1 × 1.0 × 1.2 mm, origin off zero) of a ball of
/// radius 9 mm around voxel (14, 16, 13): 350 HU in 40 HU.
inline image::Volume<float> ball_ct() {
  image::Volume<float> ct({28, 32, 26}, Vec3(1.1, 1.0, 1.2), Vec3(-12, 4, 30));
  const Vec3 centre = ct.index_to_world(Vec3(14, 16, 13));
  for (std::int64_t k = 0; k < ct.size(2); ++k)
    for (std::int64_t j = 0; j < ct.size(1); ++j)
      for (std::int64_t i = 0; i < ct.size(0); ++i)
        ct(i, j, k) = (ct.index_to_world(Vec3(double(i), double(j), double(k))) - centre).norm() < 9.0 ? 350.f : 40.f;
  return ct;
}

}  // namespace ido::test

// SPDX-License-Identifier: Apache-2.0
// A program outside the ido tree, built against the installed package.
#include <cstdio>

#include "ido/image/volume.h"

int main() {
  ido::image::Volume<float> v({4, 4, 4}, ido::Vec3(2.5, 2.5, 2.5));
  const ido::Vec3 w = v.index_to_world(ido::Vec3(5, 0, 0));
  std::printf("voxel-centre %.1f\n", w.x());
  return w.x() == 12.5 ? 0 : 1;
}

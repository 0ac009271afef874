// SPDX-License-Identifier: Apache-2.0
#include "ido/image/volume.h"

#include <cstdint>

namespace ido::image {
// The voxel types the toolkit uses, compiled once here.
template class Volume<float>;
template class Volume<double>;
template class Volume<std::int16_t>;
template class Volume<std::uint8_t>;
}  // namespace ido::image

// SPDX-License-Identifier: Apache-2.0
#include "support/png_read.h"

#include <png.h>

namespace ido::test {

Png read_png(const std::filesystem::path& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  Png out;
  if (!png_image_begin_read_from_file(&img, path.c_str())) return out;
  img.format = PNG_FORMAT_RGBA;
  out.rgba.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.rgba.data(), 0, nullptr)) return {};
  out.w = int(img.width);
  out.h = int(img.height);
  return out;
}

}  // namespace ido::test

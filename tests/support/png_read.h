// SPDX-License-Identifier: Apache-2.0
#pragma once
// Reading PNG files back in tests (libpng's simplified API), independent of ido's own writer.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace ido::test {

/// An RGBA picture, rows top to bottom.
struct Png {
  int w = 0, h = 0;
  std::vector<std::uint8_t> rgba;
  [[nodiscard]] const std::uint8_t* at(int x, int y) const {
    return rgba.data() + 4 * (std::size_t(y) * std::size_t(w) + std::size_t(x));
  }
  /// Pure white, the renderer's background.
  [[nodiscard]] bool background(int x, int y) const {
    const auto* p = at(x, y);
    return p[0] == 255 && p[1] == 255 && p[2] == 255;
  }
};

/// Reads @p path; w = h = 0 and no pixels when it is not a readable PNG.
[[nodiscard]] Png read_png(const std::filesystem::path& path);

}  // namespace ido::test

// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the TetGen parser: the input is split at the first NUL byte (or in
// the middle) into the .node and the .ele text.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "../src/io/parsers.h"
#include "ido/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto cut = bytes.find('\0');
  if (cut == std::string_view::npos) cut = size / 2;
  const std::string_view node = bytes.substr(0, cut);
  const std::string_view ele = cut < size ? bytes.substr(cut + 1) : std::string_view{};
  try {
    (void)ido::io::detail::parse_tetgen(node, "fuzz.node", ele, "fuzz.ele");
  } catch (const ido::Error&) {
  }
  return 0;
}

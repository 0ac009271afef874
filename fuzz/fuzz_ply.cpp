// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the PLY parser: any bytes must parse or throw ido::Error, never crash.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "../src/io/parsers.h"
#include "ido/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)ido::io::detail::parse_ply(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ply");
  } catch (const ido::Error&) {
  }
  return 0;
}

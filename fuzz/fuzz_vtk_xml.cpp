// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the VTK XML parsers (.vtu, .vtp) and the .pvd index: any bytes must
// parse or throw ido::Error, never crash.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "../src/io/parsers.h"
#include "ido/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    (void)ido::io::detail::parse_vtu(bytes, "fuzz.vtu");
  } catch (const ido::Error&) {
  }
  try {
    (void)ido::io::detail::parse_vtp(bytes, "fuzz.vtp");
  } catch (const ido::Error&) {
  }
  try {
    (void)ido::io::detail::parse_pvd(bytes, "fuzz.pvd");
  } catch (const ido::Error&) {
  }
  return 0;
}

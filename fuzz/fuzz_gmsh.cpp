// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the Gmsh .msh parser (tetrahedra and triangles).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "../src/io/parsers.h"
#include "ido/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    (void)ido::io::detail::parse_gmsh_tets(bytes, "fuzz.msh");
  } catch (const ido::Error&) {
  }
  try {
    (void)ido::io::detail::parse_gmsh_triangles(bytes, "fuzz.msh");
  } catch (const ido::Error&) {
  }
  return 0;
}

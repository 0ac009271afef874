// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: scene parsing must either build a world or throw ido::Error — never
// crash. Mesh files are resolved in a folder that does not exist, so only generated meshes
// (bounded in size by the parser) are built.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ido/core/error.h"
#include "ido/io/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto scene = ido::io::parse_scene(
        std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json", "/nonexistent-ido-fuzz");
    (void)scene;
  } catch (const ido::Error&) {
  }
  return 0;
}

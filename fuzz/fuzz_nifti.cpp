// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the NIfTI-1 header check that runs before ITK reads a .nii/.nii.gz
// (src/io/nifti_header.h): any bytes must parse or throw ido::Error, never crash; a parsed
// header's declared sizes must be consistent (no overflow wraps to a small count).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "../src/io/nifti_header.h"
#include "ido/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto h = ido::io::detail::parse_nifti_header(std::string_view(reinterpret_cast<const char*>(data), size),
                                                       "fuzz.nii");
    if (h.voxel_offset < 348 || h.bytes_per_voxel <= 0 || h.voxel_count == 0) std::abort();
    if (h.voxel_bytes != UINT64_MAX && h.voxel_bytes / static_cast<std::uint64_t>(h.bytes_per_voxel) != h.voxel_count)
      std::abort();
  } catch (const ido::Error&) {
  }
  return 0;
}

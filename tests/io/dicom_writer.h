// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <filesystem>
#include <string>

namespace ido::test {
/// Writes a tiny int16 DICOM series (@p slices files of 4×3 pixels) with ITK's GDCMImageIO
/// into @p dir, under Series Instance UID @p series_uid, file names prefixed by @p prefix.
void write_tiny_dicom_series(const std::filesystem::path& dir, const std::string& series_uid,
                             const std::string& prefix, int slices);
}  // namespace ido::test

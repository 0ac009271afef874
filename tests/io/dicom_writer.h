// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace ido::test {
/// Writes a tiny int16 DICOM series (@p slices files of 4×3 pixels) with ITK's GDCMImageIO
/// into @p dir, under Series Instance UID @p series_uid, file names prefixed by @p prefix.
void write_tiny_dicom_series(const std::filesystem::path& dir, const std::string& series_uid,
                             const std::string& prefix, int slices);

/// The voxels of the single series in @p dir as ITK's ImageSeriesReader decodes them, one
/// slice after another (x fastest), with its size: the oracle for ido's parallel reader.
struct ItkSeries {
  std::size_t nx = 0, ny = 0, nz = 0;
  std::vector<float> voxels;
};
ItkSeries read_series_with_itk(const std::filesystem::path& dir);
}  // namespace ido::test

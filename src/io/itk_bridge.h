// SPDX-License-Identifier: Apache-2.0
// Private to ido::io. ITK 5.2 ships its own Eigen 3.3 whose headers clash with the system
// Eigen 3.4 that ido's public headers include, so ITK lives in one translation unit
// (itk_bridge.cpp) that sees no ido header with Eigen; this header passes plain data.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace ido::io::detail {

/// Grid placement of a volume in ITK's terms (LPS, mm); direction row-major.
struct GridHeader {
  std::array<std::int64_t, 3> size{};
  std::array<double, 3> spacing{};
  std::array<double, 3> origin{};
  std::array<double, 9> direction{};
};

/// A volume read by ITK, converted to float.
struct RawVolume {
  GridHeader grid;
  std::vector<float> voxels;
  std::string format;
  std::string pixel_type;
  int components = 1;
  std::string series_uid;
};

enum class VolumeKind { Nifti, Nrrd, Meta, Unknown };
enum class PixelKind { Float32, UInt8, Int16 };

/// The one spacing rule of every volume reader (defined in volume_io.cpp, called by the
/// readers before they allocate and again on every volume read): each spacing positive and
/// finite. @throws ido::IoError "PATH: spacing 1 × 0 × 1 mm is not positive and finite".
void check_volume_spacing(const std::string& path, const std::array<double, 3>& spacing_mm);

/// Reads a volume file of the given kind. @throws ido::IoError.
RawVolume itk_read_file(const std::string& path, VolumeKind kind);
/// Reads the single DICOM series of a folder. @throws ido::IoError (none, several, bad).
RawVolume itk_read_dicom_folder(const std::string& dir);
/// Writes voxels to @p file_name (the temporary name); @p shown_path names errors.
void itk_write(const std::string& file_name, const std::string& shown_path, VolumeKind kind,
               bool compress, const GridHeader& grid, const void* voxels, PixelKind pixel);

}  // namespace ido::io::detail

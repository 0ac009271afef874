// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <string>

#include "ido/image/volume.h"

namespace ido::io {

/// What a volume file holds before conversion to float.
struct VolumeFileInfo {
  std::string format;        ///< "NIfTI", "NRRD", "MetaImage", "DICOM"
  std::string pixel_type;    ///< the stored component type in ITK's names, e.g. "short", "float"
  int components = 1;        ///< components per voxel (only 1 is accepted by read_volume)
  std::string series_uid;    ///< DICOM only
};

/// Reads a 3D scalar volume: NIfTI (.nii, .nii.gz), NRRD (.nrrd, .nhdr), MetaImage (.mha,
/// .mhd), or a folder holding one DICOM series (compressed transfer syntaxes included).
/// Spacing, origin and direction are kept (ITK's LPS world frame, mm). Intensities are
/// converted to float (CT in Hounsfield units after DICOM rescale).
/// @throws ido::IoError naming the path and the problem (missing file, unknown format,
///         not 3D, several DICOM series in one folder, ...).
[[nodiscard]] image::Volume<float> read_volume(const std::filesystem::path& path,
                                               VolumeFileInfo* info = nullptr);

/// Writes a volume; the format follows the extension (.nii, .nii.gz, .nrrd, .mha). Split
/// header/data forms (.nhdr, .mhd) are refused: one file is renamed into place atomically
/// (temporary file + rename), two could not be.
/// @throws ido::IoError for an unknown or split-header extension, or a failed write.
void write_volume(const std::filesystem::path& path, const image::Volume<float>& volume);
void write_volume(const std::filesystem::path& path, const image::Volume<std::uint8_t>& volume);
void write_volume(const std::filesystem::path& path, const image::Volume<std::int16_t>& volume);

/// Writes @p volume in the stored pixel type of the file it came from (@p source, as filled
/// by read_volume): uint8 or int16 when the source held such integers (or int8/uint16 whose
/// values all fit int16) and every voxel is an integer in range; float otherwise. Used to
/// convert e.g. an int16 DICOM series to an int16 NIfTI without doubling its size.
void write_volume_as_stored(const std::filesystem::path& path, const image::Volume<float>& volume,
                            const VolumeFileInfo& source);

/// True if @p path names something read_volume can try (a known volume extension or a
/// folder).
[[nodiscard]] bool looks_like_volume(const std::filesystem::path& path);

}  // namespace ido::io

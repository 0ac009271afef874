// SPDX-License-Identifier: Apache-2.0
// Private to ido::io (and the fuzz targets): the checks ido makes on a NIfTI file itself,
// around ITK's reader. ITK 5.2's NIfTI reader (niftilib) fills missing voxel bytes with
// zeros without an error and replaces a spacing of 0, -1 or NaN by 1; it reads NIfTI-1 only.
// This code reads the 348-byte header (through zlib, so .nii and .nii.gz alike) and counts
// the bytes a file really holds, so that such files are refused by name. No ITK here.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace ido::io::detail {

/// The fields of a NIfTI-1 header that ido checks.
struct NiftiHeader {
  bool big_endian = false;
  std::array<std::int64_t, 8> dim{};      ///< dim[0] axes, then the size along each
  int datatype = 0;                       ///< NIfTI DT_* code
  int bytes_per_voxel = 0;                ///< from the datatype
  std::array<double, 8> pixdim{};         ///< pixdim[1..3]: spacing in the file's units
  std::uint64_t voxel_offset = 0;         ///< where the voxels start (vox_offset, at least 352)
  std::uint64_t voxel_count = 0;          ///< saturates at UINT64_MAX
  std::uint64_t voxel_bytes = 0;          ///< voxel_count × bytes_per_voxel, saturating
  double scl_slope = 0.0;
  double scl_inter = 0.0;
};

/// Number of header bytes parse_nifti_header looks at (a NIfTI-2 header's size).
inline constexpr std::size_t kNiftiHeaderReadBytes = 540;

/// Parses and checks the start of a (decompressed) NIfTI file: header size 348 in either
/// byte order (540 is NIfTI-2: refused by name), single-file magic "n+1", 1 to 7 axes of
/// positive size, a known datatype, a finite vox_offset. Spacing is not judged here (the
/// volume reader checks every format's spacing in one place).
/// @throws ido::IoError naming @p name and the problem.
NiftiHeader parse_nifti_header(std::string_view bytes, const std::string& name);

/// Reads and parses the header of @p path (.nii or .nii.gz). @throws ido::IoError.
NiftiHeader read_nifti_header(const std::string& path);

/// True when @p path holds a gzip stream (by its first two bytes, whatever its name).
[[nodiscard]] bool nifti_is_gzip(const std::string& path);

/// True for float32 and float64 data, whose non-finite values niftilib silently turns into 0.
[[nodiscard]] bool nifti_is_float(const NiftiHeader& header);

/// What check_nifti_voxels found among float voxels (none for integer data).
struct NiftiVoxelScan {
  std::uint64_t non_finite = 0;        ///< NaN or ±inf values
  std::uint64_t first_non_finite = 0;  ///< linear index of the first one
};

/// Checks that @p path holds all of the voxel bytes @p header declares: the file size of a
/// .nii, the decompressed length of a .nii.gz (streamed through zlib a few hundred KiB at a
/// time up to the last byte needed; a stream cut short or corrupt is reported as such). With
/// @p scan_floats and float data, every value is streamed and the non-finite ones counted.
/// @throws ido::IoError naming @p path, the bytes found and the bytes declared.
NiftiVoxelScan check_nifti_voxels(const std::string& path, const NiftiHeader& header, bool scan_floats);

/// Checks a MetaImage whose voxels are zlib-compressed inside the file (CompressedData =
/// True, ElementDataFile = LOCAL): MetaIO reports a stream that does not inflate only on
/// stderr ("Uncompress failed") and hands back whatever its buffer held. The stream, which
/// starts after the ElementDataFile line, is inflated a few hundred KiB at a time up to
/// @p voxel_bytes. @throws ido::IoError naming @p path when it is damaged or holds fewer.
void check_meta_zlib_voxels(const std::string& path, std::uint64_t voxel_bytes);

/// How the voxels of a detached data file are stored.
enum class DataEncoding { Raw, Zlib, Gzip };

/// The voxel file of a header/data pair (a MetaImage .mhd with ElementDataFile = x.raw, an
/// NRRD .nhdr with "data file: x.raw"), as its header names it.
struct DetachedData {
  std::string file;                        ///< resolved against the header's folder
  DataEncoding encoding = DataEncoding::Raw;
  std::int64_t skip_bytes = 0;             ///< bytes before the voxels; -1: the voxels end the file
};

/// Reads the data file, encoding and byte skip of an NRRD header (.nhdr, or a .nrrd naming a
/// data file), or nothing when its voxels follow the header in the same file, are split over
/// several files (LIST, a format string) or use an encoding left to the reader (ascii, hex,
/// bzip2). Only the header text is read (up to its blank line, at most 64 KiB).
[[nodiscard]] std::optional<DetachedData> nrrd_detached_data(const std::string& header_path);

/// Checks that the data file of a header/data pair exists and is a regular file (before the
/// reader, which would word it as a bad header). @throws ido::IoError naming @p header_path.
void check_detached_file(const std::string& header_path, const DetachedData& data);

/// Checks the data file of a header/data pair before ITK reads it (ITK reads a short raw
/// file or a short compressed stream with the missing voxels left as whatever the buffer
/// held, or fails with its internals): it exists, is a regular file, and holds @p voxel_bytes
/// after the skip (raw), or its stream inflates to at least @p voxel_bytes (zlib, gzip).
/// @throws ido::IoError naming @p header_path, the data file, the bytes found and declared.
void check_detached_voxels(const std::string& header_path, const DetachedData& data, std::uint64_t voxel_bytes);

}  // namespace ido::io::detail

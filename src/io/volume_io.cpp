// SPDX-License-Identifier: Apache-2.0
// Volume files: extension dispatch, checks and conversion to image::Volume. ITK itself is
// confined to itk_bridge.cpp (see itk_bridge.h).
#include "ido/io/volume_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <system_error>

#include <fmt/format.h>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "itk_bridge.h"
#include "nifti_header.h"

namespace ido::io {
namespace fs = std::filesystem;
using detail::VolumeKind;

namespace {

/// Whether the file name ends with @p suffix (case-insensitive).
bool ends_with(const fs::path& path, std::string_view suffix) {
  std::string name = path.filename().string();
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return name.size() >= suffix.size() &&
         name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

VolumeKind kind_of(const fs::path& path) {
  if (ends_with(path, ".nii") || ends_with(path, ".nii.gz")) return VolumeKind::Nifti;
  if (ends_with(path, ".nrrd") || ends_with(path, ".nhdr")) return VolumeKind::Nrrd;
  if (ends_with(path, ".mha") || ends_with(path, ".mhd")) return VolumeKind::Meta;
  return VolumeKind::Unknown;
}

[[noreturn]] void throw_non_finite(const std::string& path, std::uint64_t bad, std::uint64_t total, std::uint64_t first,
                                   const Index3& size) {
  const auto nx = static_cast<std::uint64_t>(std::max<std::int64_t>(size[0], 1));
  const auto ny = static_cast<std::uint64_t>(std::max<std::int64_t>(size[1], 1));
  throw IoError(path, fmt::format("{} of {} voxels are not finite (NaN or infinite), the first at voxel ({}, {}, {})", bad,
                                  total, first % nx, first / nx % ny, first / (nx * ny)));
}

/// The checks every reader's volume goes through before a caller sees it (one place, so the
/// formats agree): a positive finite spacing, a finite origin, a non-singular direction,
/// finite voxels.
image::Volume<float> to_volume(detail::RawVolume raw, const std::string& path) {
  Index3 size{raw.grid.size[0], raw.grid.size[1], raw.grid.size[2]};
  Vec3 spacing(raw.grid.spacing[0], raw.grid.spacing[1], raw.grid.spacing[2]);
  Vec3 origin(raw.grid.origin[0], raw.grid.origin[1], raw.grid.origin[2]);
  Mat3 dir;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) dir(a, b) = raw.grid.direction[static_cast<std::size_t>(a * 3 + b)];
  detail::check_volume_spacing(path, raw.grid.spacing);
  if (!origin.allFinite()) throw IoError(path, "origin is not finite");
  if (!dir.allFinite() || std::abs(dir.determinant()) < 1e-6)
    throw IoError(path, "direction matrix is singular or not finite");
  // Bit test (exponent all ones: NaN or ±inf), which vectorises; a NaN read as a number would
  // pass every threshold downstream.
  std::uint64_t bad = 0;
  for (const float v : raw.voxels) bad += (std::bit_cast<std::uint32_t>(v) & 0x7f800000u) == 0x7f800000u;
  if (bad > 0) {
    std::uint64_t first = 0;
    while (std::isfinite(raw.voxels[first])) ++first;
    throw_non_finite(path, bad, raw.voxels.size(), first, size);
  }
  try {
    // The constructor checks the voxel count against the size (InvalidInput, named below).
    return image::Volume<float>(size, std::move(raw.voxels), spacing, origin, dir);
  } catch (const InvalidInput& e) {
    throw IoError(path, e.what());
  }
}

/// A NIfTI file read through ITK, with the checks ITK's reader (niftilib) leaves out: it
/// zero-fills missing voxel bytes, turns NaN and infinite floats into 0 and a spacing of 0,
/// -1 or NaN into 1 (nifti_header.h). The spacing is judged from the header before ITK reads.
detail::RawVolume read_nifti(const std::string& path) {
  const detail::NiftiHeader header = detail::read_nifti_header(path);
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  for (std::int64_t a = 1; a <= std::min<std::int64_t>(header.dim[0], 3); ++a)
    spacing[static_cast<std::size_t>(a - 1)] = header.pixdim[static_cast<std::size_t>(a)];
  detail::check_volume_spacing(path, spacing);
  const bool gz = detail::nifti_is_gzip(path);
  // ITK's NIfTI reader takes a gzip stream only from a .nii.gz (it reads plain bytes from
  // either name).
  if (gz && !ends_with(path, ".gz")) throw IoError(path, "is gzip-compressed but not named .nii.gz (rename it)");
  const bool is_float = detail::nifti_is_float(header);
  // An uncompressed file's length is known up front; a gzip stream's only by decompressing it.
  if (!gz) (void)detail::check_nifti_voxels(path, header, /*scan_floats=*/false);
  detail::RawVolume raw = detail::itk_read_file(path, VolumeKind::Nifti);
  // niftilib leaves stored 0 (after ITK's rescaling: 0 or scl_inter) where a short stream
  // ended — at the end of the voxels — and in place of every NaN or infinite float. Only when
  // such values are there is the file streamed a second time (counting its bytes, and its
  // non-finite floats); a scan without them was read whole and costs nothing more.
  const float zero_fill = static_cast<float>(header.scl_inter);
  auto is_fill = [&](float v) { return v == 0.0f || v == zero_fill; };
  const bool suspect = is_float ? std::any_of(raw.voxels.begin(), raw.voxels.end(), is_fill)
                                : gz && !raw.voxels.empty() && is_fill(raw.voxels.back());
  if (suspect) {
    const auto scan = detail::check_nifti_voxels(path, header, /*scan_floats=*/true);
    if (scan.non_finite > 0)
      throw_non_finite(path, scan.non_finite, header.voxel_count, scan.first_non_finite,
                       Index3{header.dim[1], header.dim[0] >= 2 ? header.dim[2] : 1, header.dim[0] >= 3 ? header.dim[3] : 1});
  }
  return raw;
}

}  // namespace

namespace detail {
void check_volume_spacing(const std::string& path, const std::array<double, 3>& s) {
  for (const double v : s)
    if (!(v > 0.0) || !std::isfinite(v))
      throw IoError(path, fmt::format("spacing {} × {} × {} mm is not positive and finite", s[0], s[1], s[2]));
}
}  // namespace detail

namespace {

template <class T>
void write_any(const fs::path& path, const image::Volume<T>& volume, detail::PixelKind pixel) {
  const VolumeKind kind = kind_of(path);
  if (kind == VolumeKind::Unknown)
    throw IoError(path.string(), "unknown volume extension (write .nii, .nii.gz, .nrrd or .mha)");
  // A header/data pair would leave its data file under the temporary name: only the
  // single-file variants are written.
  if (ends_with(path, ".mhd") || ends_with(path, ".nhdr"))
    throw IoError(path.string(), "split header/data files are not written; use .mha or .nrrd");
  if (volume.empty()) throw InvalidInput(path.string() + ": cannot write an empty volume");
  detail::GridHeader grid;
  for (int a = 0; a < 3; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    grid.size[ua] = volume.size()[ua];
    grid.spacing[ua] = volume.spacing()[a];
    grid.origin[ua] = volume.origin()[a];
    for (int b = 0; b < 3; ++b) grid.direction[static_cast<std::size_t>(a * 3 + b)] = volume.direction()(a, b);
  }
  // NIfTI compresses by its .gz extension; MetaImage gets zlib (VTK reads it). NRRD stays
  // raw so that every NRRD reader (vtkNrrdReader included) opens it.
  const bool compress = kind == VolumeKind::Meta || ends_with(path, ".gz");
  write_path_atomically(path, [&](const fs::path& tmp) {
    detail::itk_write(tmp.string(), path.string(), kind, compress, grid, volume.data().data(), pixel);
  });
}

}  // namespace

image::Volume<float> read_volume(const fs::path& path, VolumeFileInfo* info) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) throw IoError(path.string(), "no such file or folder");
  detail::RawVolume raw;
  if (fs::is_directory(status)) {
    raw = detail::itk_read_dicom_folder(path.string());
  } else {
    const VolumeKind kind = kind_of(path);
    if (kind == VolumeKind::Unknown)
      throw IoError(path.string(), "unknown volume extension (expected .nii, .nii.gz, .nrrd, "
                                   ".nhdr, .mha, .mhd or a DICOM folder)");
    // A device or pipe (/dev/zero named x.nii) never ends: only regular files are read.
    if (!fs::is_regular_file(status))
      throw IoError(path.string(), "is not a regular file (a device, pipe or socket)");
    raw = kind == VolumeKind::Nifti ? read_nifti(path.string()) : detail::itk_read_file(path.string(), kind);
  }
  if (info) *info = {raw.format, raw.pixel_type, raw.components, raw.series_uid};
  return to_volume(std::move(raw), path.string());
}

void write_volume(const fs::path& path, const image::Volume<float>& volume) {
  write_any(path, volume, detail::PixelKind::Float32);
}
void write_volume(const fs::path& path, const image::Volume<std::uint8_t>& volume) {
  write_any(path, volume, detail::PixelKind::UInt8);
}
void write_volume(const fs::path& path, const image::Volume<std::int16_t>& volume) {
  write_any(path, volume, detail::PixelKind::Int16);
}

void write_volume_as_stored(const fs::path& path, const image::Volume<float>& volume,
                            const VolumeFileInfo& source) {
  const std::string& t = source.pixel_type;
  const bool to_u8 = t == "unsigned_char";
  const bool to_i16 = t == "short" || t == "char" || t == "unsigned_short";
  auto all_integral_in = [&](double lo, double hi) {
    return std::all_of(volume.data().begin(), volume.data().end(),
                       [&](float v) { return v >= lo && v <= hi && v == std::floor(v); });
  };
  if (to_u8 && all_integral_in(0, 255)) {
    auto out = volume.like<std::uint8_t>();
    std::transform(volume.data().begin(), volume.data().end(), out.data().begin(),
                   [](float v) { return static_cast<std::uint8_t>(v); });
    return write_volume(path, out);
  }
  if ((to_i16 || to_u8) && all_integral_in(-32768, 32767)) {
    auto out = volume.like<std::int16_t>();
    std::transform(volume.data().begin(), volume.data().end(), out.data().begin(),
                   [](float v) { return static_cast<std::int16_t>(v); });
    return write_volume(path, out);
  }
  write_volume(path, volume);
}

bool looks_like_volume(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return true;
  return kind_of(path) != VolumeKind::Unknown;
}

}  // namespace ido::io

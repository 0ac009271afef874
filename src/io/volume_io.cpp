// SPDX-License-Identifier: Apache-2.0
// Volume files: extension dispatch, checks and conversion to image::Volume. ITK itself is
// confined to itk_bridge.cpp (see itk_bridge.h).
#include "ido/io/volume_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <system_error>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "itk_bridge.h"

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

image::Volume<float> to_volume(detail::RawVolume raw, const std::string& path) {
  Index3 size{raw.grid.size[0], raw.grid.size[1], raw.grid.size[2]};
  Vec3 spacing(raw.grid.spacing[0], raw.grid.spacing[1], raw.grid.spacing[2]);
  Vec3 origin(raw.grid.origin[0], raw.grid.origin[1], raw.grid.origin[2]);
  Mat3 dir;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) dir(a, b) = raw.grid.direction[static_cast<std::size_t>(a * 3 + b)];
  if (!dir.allFinite() || std::abs(dir.determinant()) < 1e-6)
    throw IoError(path, "direction matrix is singular or not finite");
  try {
    // The constructor checks the voxel count against the size (InvalidInput, named below).
    return image::Volume<float>(size, std::move(raw.voxels), spacing, origin, dir);
  } catch (const InvalidInput& e) {
    throw IoError(path, e.what());
  }
}

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
  if (!fs::exists(path, ec)) throw IoError(path.string(), "no such file or folder");
  detail::RawVolume raw;
  if (fs::is_directory(path, ec)) {
    raw = detail::itk_read_dicom_folder(path.string());
  } else {
    const VolumeKind kind = kind_of(path);
    if (kind == VolumeKind::Unknown)
      throw IoError(path.string(), "unknown volume extension (expected .nii, .nii.gz, .nrrd, "
                                   ".nhdr, .mha, .mhd or a DICOM folder)");
    raw = detail::itk_read_file(path.string(), kind);
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

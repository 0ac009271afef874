// SPDX-License-Identifier: Apache-2.0
// The only file of ido that includes ITK (see itk_bridge.h for why it is isolated). The
// ImageIO object is chosen by extension, or GDCM for a folder, so nothing depends on
// ITK's factory auto-registration.
#include "itk_bridge.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImage.h>
#include <itkImageFileReader.h>
#include <itkImageFileWriter.h>
#include <itkImageIOBase.h>
#include <itkImageSeriesReader.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include "ido/core/error.h"

namespace ido::io::detail {
namespace {

const char* format_name(VolumeKind kind) {
  switch (kind) {
    case VolumeKind::Nifti: return "NIfTI";
    case VolumeKind::Nrrd: return "NRRD";
    case VolumeKind::Meta: return "MetaImage";
    case VolumeKind::Unknown: break;
  }
  return "unknown";
}

itk::ImageIOBase::Pointer make_io(VolumeKind kind) {
  switch (kind) {
    case VolumeKind::Nifti: return itk::NiftiImageIO::New().GetPointer();
    case VolumeKind::Nrrd: return itk::NrrdImageIO::New().GetPointer();
    case VolumeKind::Meta: return itk::MetaImageIO::New().GetPointer();
    case VolumeKind::Unknown: break;
  }
  return nullptr;
}

/// ITK prints warnings through its output window; the library must stay silent.
void silence_itk() {
  static const bool done = [] {
    itk::Object::GlobalWarningDisplayOff();
    return true;
  }();
  (void)done;
}

/// ITK's description of an exception, trimmed.
std::string itk_problem(const itk::ExceptionObject& e) {
  std::string d = e.GetDescription();
  while (!d.empty() && (d.back() == '\n' || d.back() == ' ')) d.pop_back();
  // One line: the CLI reports errors as a single line.
  for (auto& c : d)
    if (c == '\n' || c == '\r') c = ' ';
  return d.empty() ? std::string("ITK could not process the file") : d;
}

using FloatImage = itk::Image<float, 3>;

RawVolume from_itk(const FloatImage* img) {
  RawVolume out;
  const auto sz = img->GetLargestPossibleRegion().GetSize();
  for (unsigned a = 0; a < 3; ++a) {
    out.grid.size[a] = static_cast<std::int64_t>(sz[a]);
    out.grid.spacing[a] = img->GetSpacing()[a];
    out.grid.origin[a] = img->GetOrigin()[a];
    for (unsigned b = 0; b < 3; ++b) out.grid.direction[a * 3 + b] = img->GetDirection()(a, b);
  }
  const std::size_t n = static_cast<std::size_t>(sz[0]) * sz[1] * sz[2];
  out.voxels.assign(img->GetBufferPointer(), img->GetBufferPointer() + n);
  return out;
}

std::string component_name(itk::IOComponentEnum c) {
  return itk::ImageIOBase::GetComponentTypeAsString(c);
}

template <class T>
void write_typed(const std::string& file_name, const std::string& shown, VolumeKind kind,
                 bool compress, const GridHeader& grid, const T* voxels) {
  using Image = itk::Image<T, 3>;
  auto img = Image::New();
  typename Image::RegionType region;
  typename Image::SizeType size;
  typename Image::SpacingType spacing;
  typename Image::PointType origin;
  typename Image::DirectionType dir;
  for (unsigned a = 0; a < 3; ++a) {
    size[a] = static_cast<itk::SizeValueType>(grid.size[a]);
    spacing[a] = grid.spacing[a];
    origin[a] = grid.origin[a];
    for (unsigned b = 0; b < 3; ++b) dir(a, b) = grid.direction[a * 3 + b];
  }
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(spacing);
  img->SetOrigin(origin);
  img->SetDirection(dir);
  img->Allocate();
  const std::size_t n = static_cast<std::size_t>(grid.size[0] * grid.size[1] * grid.size[2]);
  std::copy(voxels, voxels + n, img->GetBufferPointer());
  auto writer = itk::ImageFileWriter<Image>::New();
  writer->SetImageIO(make_io(kind));
  writer->SetFileName(file_name);
  writer->SetInput(img);
  writer->SetUseCompression(compress);
  try {
    writer->Update();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(shown, "cannot write: " + itk_problem(e));
  }
}

}  // namespace

RawVolume itk_read_file(const std::string& path, VolumeKind kind) {
  silence_itk();
  auto io = make_io(kind);
  io->SetFileName(path);
  try {
    if (!io->CanReadFile(path.c_str()))
      throw IoError(path, fmt::format("not a readable {} file (bad header or magic)", format_name(kind)));
    io->ReadImageInformation();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(path, itk_problem(e));
  }
  const unsigned dims = io->GetNumberOfDimensions();
  for (unsigned d = 3; d < dims; ++d)
    if (io->GetDimensions(d) > 1)
      throw IoError(path, fmt::format("{}D image with {} samples along axis {}; expected a 3D volume",
                                      dims, io->GetDimensions(d), d));
  if (io->GetNumberOfComponents() != 1)
    throw IoError(path, fmt::format("{} components per voxel; expected a scalar volume",
                                    io->GetNumberOfComponents()));
  // ITK reads a too-short uncompressed file without complaint: check its size first.
  bool uncompressed = false;
  if (kind == VolumeKind::Nifti) {
    uncompressed = path.size() < 3 || path.compare(path.size() - 3, 3, ".gz") != 0;
  } else if (kind == VolumeKind::Meta) {
    auto* meta = dynamic_cast<itk::MetaImageIO*>(io.GetPointer());
    uncompressed = meta && !meta->GetMetaImagePointer()->CompressedData() &&
                   std::string(meta->GetMetaImagePointer()->ElementDataFileName()) == "LOCAL";
  }
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  // A single-file NIfTI-1 header takes at least 352 bytes before the voxels.
  const std::uintmax_t header_bytes = kind == VolumeKind::Nifti ? 352 : 0;
  const auto voxel_bytes = static_cast<std::uintmax_t>(io->GetImageSizeInBytes());
  if (uncompressed && !ec && file_size < header_bytes + voxel_bytes)
    throw IoError(path, fmt::format("file has {} bytes, too few for the {} bytes of voxels its header declares (truncated?)",
                                    file_size, voxel_bytes));
  auto reader = itk::ImageFileReader<FloatImage>::New();
  reader->SetImageIO(io);
  reader->SetFileName(path);
  try {
    reader->Update();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(path, "cannot read voxels: " + itk_problem(e));
  }
  RawVolume out = from_itk(reader->GetOutput());
  out.format = format_name(kind);
  out.pixel_type = component_name(io->GetComponentType());
  out.components = 1;
  return out;
}

RawVolume itk_read_dicom_folder(const std::string& dir) {
  silence_itk();
  auto names = itk::GDCMSeriesFileNames::New();
  // Series are told apart by their Series Instance UID only; extra details (e.g. slice
  // orientation) would split one acquisition in two.
  names->SetUseSeriesDetails(false);
  names->SetDirectory(dir);
  std::vector<std::string> uids;
  try {
    uids = names->GetSeriesUIDs();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(dir, "cannot scan for DICOM files: " + itk_problem(e));
  }
  if (uids.empty()) throw IoError(dir, "folder holds no DICOM series");
  if (uids.size() > 1) {
    std::string list;
    for (const auto& u : uids) list += (list.empty() ? "" : ", ") + u;
    throw IoError(dir, fmt::format("folder holds {} DICOM series ({}); give a folder with one",
                                   uids.size(), list));
  }
  const auto files = names->GetFileNames(uids.front());
  if (files.empty()) throw IoError(dir, "DICOM series has no readable slices");
  auto gdcm = itk::GDCMImageIO::New();
  auto reader = itk::ImageSeriesReader<FloatImage>::New();
  reader->SetImageIO(gdcm);
  reader->SetFileNames(files);
  try {
    reader->Update();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(dir, "cannot read DICOM series: " + itk_problem(e));
  }
  if (gdcm->GetNumberOfComponents() != 1)
    throw IoError(dir, fmt::format("DICOM series has {} components per voxel, expected 1",
                                   gdcm->GetNumberOfComponents()));
  // GDCMImageIO applies Rescale Slope / Intercept when the output is float: CT is in HU.
  RawVolume out = from_itk(reader->GetOutput());
  out.format = "DICOM";
  out.pixel_type = component_name(gdcm->GetComponentType());
  out.series_uid = uids.front();
  return out;
}

void itk_write(const std::string& file_name, const std::string& shown_path, VolumeKind kind,
               bool compress, const GridHeader& grid, const void* voxels, PixelKind pixel) {
  silence_itk();
  switch (pixel) {
    case PixelKind::Float32:
      write_typed(file_name, shown_path, kind, compress, grid, static_cast<const float*>(voxels));
      break;
    case PixelKind::UInt8:
      write_typed(file_name, shown_path, kind, compress, grid, static_cast<const std::uint8_t*>(voxels));
      break;
    case PixelKind::Int16:
      write_typed(file_name, shown_path, kind, compress, grid, static_cast<const std::int16_t*>(voxels));
      break;
  }
}

}  // namespace ido::io::detail

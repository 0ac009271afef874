// SPDX-License-Identifier: Apache-2.0
// The only file of ido that includes ITK (see itk_bridge.h for why it is isolated). The
// ImageIO object is chosen by extension, or GDCM for a folder, so nothing depends on
// ITK's factory auto-registration.
#include "itk_bridge.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <regex>
#include <set>

#include <fmt/format.h>
#include <gdcmExplicitDataElement.h>
#include <gdcmImplicitDataElement.h>
#include <gdcmReader.h>
#include <gdcmTrace.h>
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
#include <nifti1_io.h>

#include "ido/core/error.h"
#include "ido/core/memory.h"
#include "ido/core/parallel.h"
#include "ido/io/memory_budget.h"
#include "nifti_header.h"

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

/// ITK prints warnings through its output window, and niftilib its own to stderr ("++ WARNING:
/// nifti_read_buffer ..."); the library must stay silent (its checks report instead).
void silence_itk() {
  static const bool done = [] {
    itk::Object::GlobalWarningDisplayOff();
    nifti_set_debug_level(0);
    // GDCM warns on stderr (e.g. "Incomplete Pixel Data found"); ido checks and words it.
    gdcm::Trace::WarningOff();
    return true;
  }();
  (void)done;
}

/// ITK's description of an exception as one line in plain words: without ITK's
/// "ITK ERROR: NrrdImageIO(0x55d0…): " prefix, and for a teem (NRRD) error chain
/// ("[nrrd] nrrdLoad: trouble …\n[nrrd] _nrrdReadNrrdParse_sizes: couldn't parse …") only
/// its last link, the cause, without the function name.
std::string itk_problem(const itk::ExceptionObject& e) {
  static const std::regex kPrefix(R"((ITK ERROR: )?\w+ ?\(0x[0-9a-fA-F]+\): )");
  static const std::regex kTeem(R"(\[\w+\] \w+: )");
  std::string d = std::regex_replace(e.GetDescription(), kPrefix, "");
  if (d.find("[nrrd]") != std::string::npos || d.find("[air]") != std::string::npos) {
    std::string last;
    std::size_t pos = 0;
    while (pos < d.size()) {
      const auto end = std::min(d.find('\n', pos), d.size());
      std::string line = d.substr(pos, end - pos);
      if (std::regex_search(line, kTeem)) last = std::regex_replace(line, kTeem, "");
      pos = end + 1;
    }
    if (!last.empty()) d = last;
  }
  while (!d.empty() && (d.back() == '\n' || d.back() == ' ' || d.back() == ':')) d.pop_back();
  // One line: the CLI reports errors as a single line.
  for (auto& c : d)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return d.empty() ? std::string("ITK could not process the file") : d;
}

using FloatImage = itk::Image<float, 3>;

// The grid of @p img, no voxels.
RawVolume from_itk_header(const FloatImage* img) {
  RawVolume out;
  const auto sz = img->GetLargestPossibleRegion().GetSize();
  for (unsigned a = 0; a < 3; ++a) {
    out.grid.size[a] = static_cast<std::int64_t>(sz[a]);
    out.grid.spacing[a] = img->GetSpacing()[a];
    out.grid.origin[a] = img->GetOrigin()[a];
    for (unsigned b = 0; b < 3; ++b) out.grid.direction[a * 3 + b] = img->GetDirection()(a, b);
  }
  return out;
}

RawVolume from_itk(const FloatImage* img) {
  RawVolume out = from_itk_header(img);
  const auto sz = img->GetLargestPossibleRegion().GetSize();
  const std::size_t n = static_cast<std::size_t>(sz[0]) * sz[1] * sz[2];
  reserve_advised(out.voxels, n);  // written once, below
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

namespace {

/// Refuses a grid whose float voxels would exceed the memory budget, before ITK allocates.
void check_grid_budget(const std::string& path, std::uint64_t nx, std::uint64_t ny, std::uint64_t nz) {
  check_memory_budget(path, saturating_product({nx, ny, nz, sizeof(float)}),
                      fmt::format("{}×{}×{} voxels", nx, ny, nz));
}

RawVolume read_file(const std::string& path, VolumeKind kind) {
  // teem opens an NRRD's data file while reading the header: a missing one is told here.
  std::optional<DetachedData> nrrd_data;
  if (kind == VolumeKind::Nrrd) {
    nrrd_data = nrrd_detached_data(path);
    if (nrrd_data) check_detached_file(path, *nrrd_data);
  }
  auto io = make_io(kind);
  io->SetFileName(path);
  try {
    if (!io->CanReadFile(path.c_str()))
      throw IoError(path, fmt::format("not a readable {} file (bad header or magic)", format_name(kind)));
    io->ReadImageInformation();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(path, fmt::format("bad {} header: {}", format_name(kind), itk_problem(e)));
  }
  if (io->GetComponentType() == itk::IOComponentEnum::UNKNOWNCOMPONENTTYPE)
    throw IoError(path, "unknown or unsupported voxel type (ElementType / type field)");
  const unsigned dims = io->GetNumberOfDimensions();
  if (dims < 1) throw IoError(path, "the header declares no image axes");
  for (unsigned d = 3; d < dims; ++d)
    if (io->GetDimensions(d) > 1)
      throw IoError(path, fmt::format("{}D image with {} samples along axis {}; expected a 3D volume",
                                      dims, io->GetDimensions(d), d));
  if (io->GetNumberOfComponents() != 1)
    throw IoError(path, fmt::format("{} components per voxel; expected a scalar volume",
                                    io->GetNumberOfComponents()));
  std::uint64_t n[3] = {1, 1, 1};
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  for (unsigned d = 0; d < std::min(dims, 3u); ++d) {
    n[d] = io->GetDimensions(d);
    spacing[d] = io->GetSpacing(d);
  }
  // Before ITK's reader, which refuses a spacing of 0 in words of its own.
  check_volume_spacing(path, spacing);
  check_grid_budget(path, n[0], n[1], n[2]);
  // ITK reads a too-short uncompressed MetaImage without complaint: check its size first
  // (NIfTI files are checked by volume_io.cpp through nifti_header.h).
  // A compressed one whose stream does not inflate is read as whatever MetaIO's buffer held
  // (it only prints "Uncompress failed"): inflate it first (nifti_header.h).
  // A header/data pair (.mhd + .raw, .nhdr + .raw): the data file must hold what the header
  // declares (ITK fails on it with its internals, or reads a short one without a word).
  bool uncompressed = false, compressed_here = false;
  std::optional<DetachedData> detached;
  if (kind == VolumeKind::Meta) {
    auto* meta = dynamic_cast<itk::MetaImageIO*>(io.GetPointer());
    const std::string data_file = meta ? meta->GetMetaImagePointer()->ElementDataFileName() : "LOCAL";
    const bool local = data_file == "LOCAL";
    uncompressed = local && !meta->GetMetaImagePointer()->CompressedData();
    compressed_here = local && meta->GetMetaImagePointer()->CompressedData();
    // One data file (not a LIST of slices nor a numbered pattern).
    if (meta && !local && !data_file.empty() && data_file.rfind("LIST", 0) != 0 &&
        data_file.find('%') == std::string::npos && data_file.find(' ') == std::string::npos) {
      std::filesystem::path p(data_file);
      if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
      const int header_size = meta->GetMetaImagePointer()->HeaderSize();
      detached = DetachedData{p.string(), meta->GetMetaImagePointer()->CompressedData() ? DataEncoding::Zlib : DataEncoding::Raw,
                              header_size};
    }
  } else {
    detached = nrrd_data;
  }
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  const auto voxel_bytes = static_cast<std::uintmax_t>(io->GetImageSizeInBytes());
  if (detached) check_detached_voxels(path, *detached, voxel_bytes);
  if (compressed_here) check_meta_zlib_voxels(path, voxel_bytes);
  if (uncompressed && !ec && file_size < voxel_bytes)
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

}  // namespace

RawVolume itk_read_file(const std::string& path, VolumeKind kind) {
  silence_itk();
  try {
    return read_file(path, kind);
  } catch (const itk::ExceptionObject& e) {
    // Any ITK call not wrapped above (e.g. a size query on an odd header): still one line.
    throw IoError(path, itk_problem(e));
  }
}

namespace {

const gdcm::Tag kPixelDataTag(0x7fe0, 0x0010);
const gdcm::Tag kSeriesUidTag(0x0020, 0x000e);

/// GDCM reads a slice whose pixel data is cut short with the missing pixels as 0 (it only
/// warns on stderr): the file must hold every byte its elements declare. Reads the file
/// with GDCM (headers and the pixel bytes, not decoded). Thread-safe.
/// @throws ido::IoError naming @p file.
void check_dicom_slice_bytes(const std::string& file) {
  gdcm::Reader reader;
  reader.SetFileName(file.c_str());
  if (!reader.Read()) return;  // left to ITK's reader, which words its own error
  const gdcm::File& f = reader.GetFile();
  const gdcm::DataSet& ds = f.GetDataSet();
  if (!ds.FindDataElement(kPixelDataTag)) throw IoError(file, "DICOM slice has no pixel data");
  const bool explicit_vr = f.GetHeader().GetDataSetTransferSyntax().GetNegociatedType() == gdcm::TransferSyntax::Explicit;
  // The preamble and meta header, then the data set as encoded.
  const std::uint64_t declared = static_cast<std::uint64_t>(f.GetHeader().GetFullLength()) +
                                 (explicit_vr ? static_cast<std::uint64_t>(ds.GetLength<gdcm::ExplicitDataElement>())
                                              : static_cast<std::uint64_t>(ds.GetLength<gdcm::ImplicitDataElement>()));
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec || size >= declared) return;
  const gdcm::VL pixel_vl = ds.GetDataElement(kPixelDataTag).GetVL();
  const std::uint64_t missing = declared - size;
  if (!pixel_vl.IsUndefined() && missing <= static_cast<std::uint64_t>(pixel_vl))
    throw IoError(file, fmt::format("DICOM pixel data is cut short: {} of its {} bytes are in the file (truncated?)",
                                    static_cast<std::uint64_t>(pixel_vl) - missing, static_cast<std::uint64_t>(pixel_vl)));
  throw IoError(file, fmt::format("DICOM file has {} bytes, {} fewer than its elements declare (truncated?)", size,
                                  missing));
}

/// GDCM's series scan leaves out a file of the series that has no pixel data, so the series
/// would read with a slice missing: any other file in @p dir with the series' UID is refused.
void check_no_slice_left_out(const std::string& dir, const std::string& uid, const std::vector<std::string>& files) {
  std::set<std::filesystem::path> listed;
  for (const auto& f : files) listed.insert(std::filesystem::path(f).lexically_normal());
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file(ec) || listed.count(entry.path().lexically_normal()) > 0) continue;
    gdcm::Reader reader;
    reader.SetFileName(entry.path().c_str());
    if (!reader.ReadUpToTag(kPixelDataTag)) continue;  // not DICOM
    const gdcm::DataSet& ds = reader.GetFile().GetDataSet();
    if (!ds.FindDataElement(kSeriesUidTag)) continue;
    const gdcm::ByteValue* value = ds.GetDataElement(kSeriesUidTag).GetByteValue();
    if (!value) continue;
    std::string its_uid(value->GetPointer(), value->GetLength());
    while (!its_uid.empty() && (its_uid.back() == ' ' || its_uid.back() == '\0')) its_uid.pop_back();
    if (its_uid == uid)
      throw IoError(entry.path().string(), ds.FindDataElement(kPixelDataTag)
                                               ? "DICOM slice of the series cannot be read by the series reader"
                                               : "DICOM slice has no pixel data");
  }
}

RawVolume read_serially(const std::string& dir, itk::ImageSeriesReader<FloatImage>& reader) {
  try {
    reader.Update();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(dir, "cannot read DICOM series: " + itk_problem(e));
  }
  return from_itk(reader.GetOutput());
}

// ITK's ImageSeriesReader decodes one slice after another; a compressed series (JPEG 2000
// spends ≈ 25 ms a 512² slice in OpenJPEG) then reads at one core's speed. Here each slice
// has its own GDCMImageIO and reader, made before the parallel loop (ITK's object factory
// is not touched from the workers), and decodes into its place in one buffer; the grid is
// the series reader's (computed from the headers). The voxels equal ImageSeriesReader's
// (tests/io/volume_io_test.cpp compares them bit for bit).
RawVolume read_slices_in_parallel(const std::string& dir, const std::vector<std::string>& files,
                                  const FloatImage* grid) {
  RawVolume out = from_itk_header(grid);
  const auto nx = static_cast<std::size_t>(out.grid.size[0]);
  const auto ny = static_cast<std::size_t>(out.grid.size[1]);
  if (static_cast<std::size_t>(out.grid.size[2]) != files.size())
    throw IoError(dir, fmt::format("DICOM series of {} files gives {} slices; expected one slice per file",
                                   files.size(), out.grid.size[2]));
  reserve_advised(out.voxels, nx * ny * files.size());
  out.voxels.assign(nx * ny * files.size(), 0.0f);
  using SliceReader = itk::ImageFileReader<FloatImage>;
  std::vector<SliceReader::Pointer> readers(files.size());
  for (std::size_t s = 0; s < files.size(); ++s) {
    readers[s] = SliceReader::New();
    readers[s]->SetImageIO(itk::GDCMImageIO::New());
    readers[s]->SetFileName(files[s]);
  }
  std::vector<std::string> problems(files.size());
  std::vector<char> own(files.size(), 0);
  ido::parallel_for(
      files.size(),
      [&](std::size_t s) {
        try {
          check_dicom_slice_bytes(files[s]);
          readers[s]->Update();
          const FloatImage* slice = readers[s]->GetOutput();
          const auto sz = slice->GetLargestPossibleRegion().GetSize();
          if (sz[0] != nx || sz[1] != ny || sz[2] != 1) {
            problems[s] = fmt::format("slice is {}×{}×{}, the series {}×{}", sz[0], sz[1], sz[2], nx, ny);
          } else {
            std::copy_n(slice->GetBufferPointer(), nx * ny, out.voxels.data() + s * nx * ny);
          }
        } catch (const IoError& e) {
          problems[s] = e.problem();  // ido's own check: already in ido's words
          own[s] = 1;
        } catch (const itk::ExceptionObject& e) {
          problems[s] = itk_problem(e);
        } catch (const std::exception& e) {
          problems[s] = e.what();
        }
        readers[s] = nullptr;  // free the slice as soon as it is copied
      },
      /*threaded=*/true, /*grain=*/1);
  for (std::size_t s = 0; s < files.size(); ++s)
    if (!problems[s].empty())
      throw IoError(files[s], own[s] ? problems[s] : "cannot read DICOM slice: " + problems[s]);
  return out;
}

}  // namespace

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
  check_no_slice_left_out(dir, uids.front(), files);
  if (files.size() == 1) check_dicom_slice_bytes(files.front());
  auto gdcm = itk::GDCMImageIO::New();
  auto reader = itk::ImageSeriesReader<FloatImage>::New();
  reader->SetImageIO(gdcm);
  reader->SetFileNames(files);
  try {
    // The grid (origin, spacing from the slice positions, direction) from the headers only.
    reader->UpdateOutputInformation();
  } catch (const itk::ExceptionObject& e) {
    throw IoError(dir, "cannot read DICOM series: " + itk_problem(e));
  }
  {
    const auto sz = reader->GetOutput()->GetLargestPossibleRegion().GetSize();
    check_grid_budget(dir, sz[0], sz[1], sz[2]);
  }
  if (gdcm->GetNumberOfComponents() != 1)
    throw IoError(dir, fmt::format("DICOM series has {} components per voxel, expected 1",
                                   gdcm->GetNumberOfComponents()));
  // GDCMImageIO applies Rescale Slope / Intercept when the output is float: CT is in HU.
  RawVolume out = files.size() > 1 ? read_slices_in_parallel(dir, files, reader->GetOutput())
                                   : read_serially(dir, *reader);
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

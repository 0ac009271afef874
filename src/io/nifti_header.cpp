// SPDX-License-Identifier: Apache-2.0
#include "nifti_header.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <memory>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "ido/core/error.h"
#include "ido/io/memory_budget.h"
#include "text_parser.h"

namespace ido::io::detail {
namespace {

/// Bytes per voxel of a NIfTI datatype code (nifti1.h DT_*); 0 if unknown or sub-byte.
int datatype_bytes(int code) {
  switch (code) {
    case 2: case 256: return 1;                      // uint8, int8
    case 4: case 512: return 2;                      // int16, uint16
    case 8: case 16: case 768: case 2304: return 4;  // int32, float32, uint32, rgba32
    case 128: return 3;                              // rgb24
    case 32: case 64: case 1024: case 1280: return 8;  // complex64, float64, int64, uint64
    case 1536: case 1792: return 16;                 // float128, complex128
    case 2048: return 32;                            // complex256
    default: return 0;
  }
}

struct GzFile {
  gzFile f = nullptr;
  explicit GzFile(const std::string& path) : f(gzopen(path.c_str(), "rb")) {}
  ~GzFile() {
    if (f) gzclose(f);
  }
  GzFile(const GzFile&) = delete;
  GzFile& operator=(const GzFile&) = delete;
  /// The zlib error after a failed or short read ("" if the stream simply ended).
  std::string error() const {
    int code = Z_OK;
    const char* msg = gzerror(f, &code);
    if (code == Z_OK || code == Z_STREAM_END) return {};
    // zlib prefixes the path ("x.nii.gz: unexpected end of file"); the caller names the file.
    std::string why = msg ? msg : "zlib error";
    if (const auto colon = why.rfind(": "); colon != std::string::npos) why = why.substr(colon + 2);
    return why;
  }
};

/// By content, not by name: a gzip stream starts with 1f 8b (niftilib reads either way).
bool is_gzip_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  in.read(reinterpret_cast<char*>(magic), 2);
  return in.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
}

}  // namespace

NiftiHeader parse_nifti_header(std::string_view bytes, const std::string& name) {
  if (bytes.size() < 4) throw IoError(name, fmt::format("file ends inside the NIfTI header ({} of 348 bytes)", bytes.size()));
  NiftiHeader h;
  const auto size_le = ByteCursor(bytes, name).read<std::int32_t>(false, "header size");
  const auto size_be = ByteCursor(bytes, name).read<std::int32_t>(true, "header size");
  if (size_le == 540 || size_be == 540)
    throw IoError(name, "NIfTI-2 is not supported (ido reads NIfTI-1 through ITK 5.2); convert the file to NIfTI-1");
  if (size_le != 348 && size_be != 348)
    throw IoError(name, fmt::format("not a NIfTI-1 file: the header size field is {}, expected 348", size_le));
  h.big_endian = size_le != 348;
  if (bytes.size() < 348)
    throw IoError(name, fmt::format("file ends inside the NIfTI header ({} of 348 bytes; truncated?)", bytes.size()));
  const std::string_view magic = bytes.substr(344, 4);
  if (magic == std::string_view("ni1\0", 4))
    throw IoError(name, "header says its voxels are in a separate .img file (magic 'ni1'); ido reads single-file .nii");
  if (magic != std::string_view("n+1\0", 4))
    throw IoError(name, "no NIfTI-1 magic 'n+1' at byte 344 (an Analyze 7.5 or damaged header?)");
  auto at = [&](std::size_t offset) { return ByteCursor(bytes, name, offset); };
  auto dims = at(40);
  for (auto& d : h.dim) d = dims.read<std::int16_t>(h.big_endian, "dim");
  if (h.dim[0] < 1 || h.dim[0] > 7)
    throw IoError(name, fmt::format("dim[0] is {}: a NIfTI image has 1 to 7 axes", h.dim[0]));
  h.voxel_count = 1;
  for (std::int64_t a = 1; a <= h.dim[0]; ++a) {
    const auto d = h.dim[static_cast<std::size_t>(a)];
    if (d < 1) throw IoError(name, fmt::format("dim[{}] is {}: sizes must be at least 1", a, d));
    h.voxel_count = saturating_product({h.voxel_count, static_cast<std::uint64_t>(d)});
  }
  auto types = at(70);
  h.datatype = types.read<std::int16_t>(h.big_endian, "datatype");
  h.bytes_per_voxel = datatype_bytes(h.datatype);
  if (h.bytes_per_voxel == 0) throw IoError(name, fmt::format("datatype {} is not a supported NIfTI data type", h.datatype));
  h.voxel_bytes = saturating_product({h.voxel_count, static_cast<std::uint64_t>(h.bytes_per_voxel)});
  auto pix = at(76);
  for (auto& p : h.pixdim) p = pix.read<float>(h.big_endian, "pixdim");
  auto rest = at(108);
  const double vox_offset = rest.read<float>(h.big_endian, "vox_offset");
  h.scl_slope = rest.read<float>(h.big_endian, "scl_slope");
  h.scl_inter = rest.read<float>(h.big_endian, "scl_inter");
  if (!std::isfinite(vox_offset) || vox_offset < 0.0 || vox_offset > 9e18)
    throw IoError(name, fmt::format("vox_offset {} is not a byte offset", vox_offset));
  // As niftilib: the voxels of a single-file NIfTI start at vox_offset, but not inside the header.
  h.voxel_offset = std::max<std::uint64_t>(static_cast<std::uint64_t>(vox_offset), 348);
  return h;
}

NiftiHeader read_nifti_header(const std::string& path) {
  GzFile in(path);
  if (!in.f) throw IoError(path, "cannot open for reading");
  std::string buf(kNiftiHeaderReadBytes, '\0');
  const int n = gzread(in.f, buf.data(), static_cast<unsigned>(buf.size()));
  if (n < 0) throw IoError(path, fmt::format("cannot decompress the NIfTI header: {}", in.error()));
  buf.resize(static_cast<std::size_t>(n));
  if (buf.size() < 348 && !in.error().empty())
    throw IoError(path, fmt::format("gzip stream is cut short inside the NIfTI header ({} of 348 bytes; {})",
                                    buf.size(), in.error()));
  return parse_nifti_header(buf, path);
}

bool nifti_is_gzip(const std::string& path) { return is_gzip_file(path); }

bool nifti_is_float(const NiftiHeader& header) { return header.datatype == 16 || header.datatype == 64; }

NiftiVoxelScan check_nifti_voxels(const std::string& path, const NiftiHeader& header, bool scan_floats) {
  const std::uint64_t needed = header.voxel_offset > UINT64_MAX - header.voxel_bytes
                                   ? UINT64_MAX
                                   : header.voxel_offset + header.voxel_bytes;
  auto short_of = [&](std::uint64_t have, const char* how) {
    return IoError(path, fmt::format("{} {} bytes, too few for the {} bytes of voxels its header declares from byte {} "
                                     "(truncated?)",
                                     how, have, header.voxel_bytes, header.voxel_offset));
  };
  const bool is_float = scan_floats && nifti_is_float(header);
  if (!is_gzip_file(path)) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw IoError(path, "cannot read the file size: " + ec.message());
    if (size < needed) throw short_of(size, "file has");
    if (!is_float) return {};
  }
  GzFile in(path);
  if (!in.f) throw IoError(path, "cannot open for reading");
  gzbuffer(in.f, 1u << 18);
  // Chunks are a multiple of 8 bytes, so after the header every chunk but the last holds
  // whole values.
  std::vector<unsigned char> chunk(std::size_t(1) << 18);
  const int width = header.bytes_per_voxel;
  const bool swap = header.big_endian != (std::endian::native == std::endian::big);
  NiftiVoxelScan scan;
  std::uint64_t total = 0, value_index = 0;
  while (total < needed) {
    // The header is read on its own, so that the voxels start at a chunk's beginning.
    const std::uint64_t until = total < header.voxel_offset ? header.voxel_offset : needed;
    const auto want = static_cast<unsigned>(std::min<std::uint64_t>(chunk.size(), until - total));
    const int n = gzread(in.f, chunk.data(), want);
    if (n > 0 && is_float && total >= header.voxel_offset) {
      const std::size_t values = static_cast<std::size_t>(n) / static_cast<std::size_t>(width);
      for (std::size_t v = 0; v < values; ++v, ++value_index) {
        bool bad = false;
        if (width == 4) {
          std::uint32_t bits;
          std::memcpy(&bits, chunk.data() + v * 4, 4);
          if (swap) bits = __builtin_bswap32(bits);
          bad = (bits & 0x7f800000u) == 0x7f800000u;
        } else {
          std::uint64_t bits;
          std::memcpy(&bits, chunk.data() + v * 8, 8);
          if (swap) bits = __builtin_bswap64(bits);
          bad = (bits & 0x7ff0000000000000ull) == 0x7ff0000000000000ull;
        }
        if (bad && scan.non_finite++ == 0) scan.first_non_finite = value_index;
      }
    }
    if (n > 0) total += static_cast<std::uint64_t>(n);
    if (n < static_cast<int>(want)) {
      const std::string why = in.error();
      if (!why.empty())
        throw IoError(path, fmt::format("gzip stream is cut short or corrupt after {} bytes ({}); its header declares "
                                        "{} bytes of voxels from byte {} (truncated?)",
                                        total, why, header.voxel_bytes, header.voxel_offset));
      throw short_of(total, "decompresses to");
    }
  }
  return scan;
}

namespace {

/// What inflating a stream gave: the bytes produced (at most the wanted count) and, when the
/// stream is damaged, zlib's word for it.
struct Inflated {
  std::uint64_t produced = 0;
  std::string damage;
};

/// Inflates @p in from its current position (window bits as zlib's inflateInit2: 15 zlib,
/// 31 gzip) until @p wanted bytes came out, the stream ended or the input ran out.
Inflated inflate_up_to(std::istream& in, int window_bits, std::uint64_t wanted, const std::string& path) {
  z_stream z{};
  if (inflateInit2(&z, window_bits) != Z_OK) throw IoError(path, "zlib could not start");
  std::vector<unsigned char> input(std::size_t(1) << 16), output(std::size_t(1) << 18);
  Inflated r;
  int rc = Z_OK;
  while (r.produced < wanted && rc != Z_STREAM_END) {
    if (z.avail_in == 0) {
      in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(input.size()));
      z.next_in = input.data();
      z.avail_in = static_cast<uInt>(in.gcount());
      if (z.avail_in == 0) break;  // the file ends
    }
    z.next_out = output.data();
    z.avail_out = static_cast<uInt>(std::min<std::uint64_t>(output.size(), wanted - r.produced));
    rc = inflate(&z, Z_NO_FLUSH);
    r.produced += static_cast<std::uint64_t>(z.next_out - output.data());
    if (rc != Z_OK && rc != Z_STREAM_END) break;
  }
  if (rc != Z_OK && rc != Z_STREAM_END) r.damage = z.msg ? z.msg : (rc == Z_DATA_ERROR ? "invalid data" : "");
  inflateEnd(&z);
  return r;
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trimmed(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return std::string(s.substr(b, e - b + 1));
}

}  // namespace

void check_meta_zlib_voxels(const std::string& path, std::uint64_t voxel_bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open for reading");
  // The header is text lines; the voxels start after the line naming their file.
  std::string head(std::size_t(1) << 16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  const auto key = head.find("ElementDataFile");
  const auto eol = key == std::string::npos ? std::string::npos : head.find('\n', key);
  if (eol == std::string::npos) throw IoError(path, "no ElementDataFile line in the first 64 KiB of the header");
  in.clear();
  in.seekg(static_cast<std::streamoff>(eol + 1));
  const Inflated r = inflate_up_to(in, 15, voxel_bytes, path);
  if (r.produced < voxel_bytes)
    throw IoError(path, fmt::format("compressed voxel data {} after {} of the {} bytes its header declares "
                                    "(truncated?)",
                                    r.damage.empty() ? std::string("ends") : "is damaged (" + r.damage + ")",
                                    r.produced, voxel_bytes));
}

std::optional<DetachedData> nrrd_detached_data(const std::string& header_path) {
  std::ifstream in(header_path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string head(std::size_t(1) << 16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  std::optional<std::string> file;
  std::string encoding = "raw";
  std::int64_t skip = 0;
  std::size_t start = 0;
  while (start < head.size()) {
    const auto eol = head.find('\n', start);
    if (eol == std::string::npos) break;  // a header line cut at 64 KiB: left to the reader
    const std::string line = trimmed(std::string_view(head).substr(start, eol - start));
    start = eol + 1;
    if (line.empty()) break;  // the header ends
    if (line[0] == '#') continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos || line.compare(colon, 2, ":=") == 0) continue;  // magic, key/value pairs
    const std::string field = lower(trimmed(std::string_view(line).substr(0, colon)));
    const std::string value = trimmed(std::string_view(line).substr(colon + 1));
    if (field == "data file" || field == "datafile") file = value;
    else if (field == "encoding") encoding = lower(value);
    else if (field == "byte skip" || field == "byteskip") {
      try {
        skip = std::stoll(value);
      } catch (const std::exception&) {
        return std::nullopt;  // the reader words its own error
      }
    }
  }
  if (!file || file->empty() || file->rfind("LIST", 0) == 0 || file->find(' ') != std::string::npos ||
      file->find('%') != std::string::npos)
    return std::nullopt;
  DetachedData d;
  if (encoding == "raw") d.encoding = DataEncoding::Raw;
  else if (encoding == "gzip" || encoding == "gz") d.encoding = DataEncoding::Gzip;
  else return std::nullopt;
  std::filesystem::path p(*file);
  if (p.is_relative()) p = std::filesystem::path(header_path).parent_path() / p;
  d.file = p.string();
  d.skip_bytes = skip;
  return d;
}

void check_detached_file(const std::string& header_path, const DetachedData& data) {
  std::error_code ec;
  const auto status = std::filesystem::status(data.file, ec);
  if (!std::filesystem::exists(status))
    throw IoError(header_path, fmt::format("its data file '{}' does not exist", data.file));
  if (!std::filesystem::is_regular_file(status))
    throw IoError(header_path, fmt::format("its data file '{}' is not a regular file", data.file));
}

void check_detached_voxels(const std::string& header_path, const DetachedData& data, std::uint64_t voxel_bytes) {
  check_detached_file(header_path, data);
  std::error_code ec;
  const auto size = std::filesystem::file_size(data.file, ec);
  if (ec) throw IoError(header_path, fmt::format("cannot read the size of its data file '{}'", data.file));
  if (data.encoding == DataEncoding::Raw) {
    const std::uint64_t skip = data.skip_bytes > 0 ? static_cast<std::uint64_t>(data.skip_bytes) : 0;
    const std::uint64_t needed = skip > UINT64_MAX - voxel_bytes ? UINT64_MAX : skip + voxel_bytes;
    if (size < needed)
      throw IoError(header_path, fmt::format("data file '{}' has {} bytes, too few for the {} bytes of voxels the header "
                                             "declares{} (truncated?)",
                                             data.file, size, voxel_bytes,
                                             skip > 0 ? fmt::format(" after {} skipped", skip) : std::string()));
    return;
  }
  std::ifstream in(data.file, std::ios::binary);
  if (!in) throw IoError(header_path, fmt::format("cannot open its data file '{}'", data.file));
  if (data.skip_bytes > 0) in.seekg(static_cast<std::streamoff>(data.skip_bytes));
  const Inflated r = inflate_up_to(in, data.encoding == DataEncoding::Gzip ? 15 + 16 : 15, voxel_bytes, header_path);
  if (r.produced < voxel_bytes)
    throw IoError(header_path, fmt::format("compressed data file '{}' {} after {} of the {} bytes of voxels the header "
                                           "declares (truncated?)",
                                           data.file, r.damage.empty() ? std::string("ends") : "is damaged (" + r.damage + ")",
                                           r.produced, voxel_bytes));
}

}  // namespace ido::io::detail

// SPDX-License-Identifier: Apache-2.0
// VTK XML PolyData (.vtp) and UnstructuredGrid (.vtu), following "VTK File Formats"
// (VTK User's Guide, Kitware). Read: DataArrays in ascii, inline base64 binary, and
// appended raw or base64 data, UInt32 or UInt64 block headers, uncompressed or compressed by
// vtkZLibDataCompressor (ParaView's default when saving). Written: inline base64 binary with
// UInt64 headers (exact), or ascii with 17 significant digits.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <ostream>
#include <type_traits>

#include <fmt/format.h>
#include <zlib.h>

#include "ido/core/error.h"
#include "parsers.h"
#include "text_parser.h"
#include "xml_lite.h"

namespace ido::io::detail {
namespace {

constexpr char kB64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Base64 written straight to a stream as bytes arrive, so a large array is never held
/// encoded (or copied) in memory: whole triples are encoded into a small buffer that is flushed
/// every 48 KiB of text; finish() pads the last one or two bytes. The same text as encoding the
/// whole byte string at once.
class Base64Stream {
 public:
  explicit Base64Stream(std::ostream& out) : m_out(out) { m_text.reserve(kFlush + 4); }
  void put(const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      m_pending[m_count++] = b[i];
      if (m_count == 3) {
        quad(m_pending[0], m_pending[1], m_pending[2], 4);
        m_count = 0;
      }
    }
  }
  void finish() {
    if (m_count == 1) quad(m_pending[0], 0, 0, 2);
    if (m_count == 2) quad(m_pending[0], m_pending[1], 0, 3);
    m_count = 0;
    m_out.write(m_text.data(), std::streamsize(m_text.size()));
    m_text.clear();
  }

 private:
  static constexpr std::size_t kFlush = 48 * 1024;
  void quad(unsigned char a, unsigned char b, unsigned char c, int keep) {
    const std::uint32_t n = (std::uint32_t(a) << 16) | (std::uint32_t(b) << 8) | c;
    const char q[4] = {kB64[n >> 18], kB64[(n >> 12) & 63], kB64[(n >> 6) & 63], kB64[n & 63]};
    for (int j = 0; j < 4; ++j) m_text += j < keep ? q[j] : '=';
    if (m_text.size() >= kFlush) {
      m_out.write(m_text.data(), std::streamsize(m_text.size()));
      m_text.clear();
    }
  }
  std::ostream& m_out;
  std::string m_text;
  unsigned char m_pending[3] = {0, 0, 0};
  int m_count = 0;
};

/// Decodes base64, skipping whitespace; false on a character outside the alphabet.
bool base64_decode(std::string_view in, std::string& out) {
  out.clear();
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : in) {
    int v;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    else if (c >= '0' && c <= '9') v = c - '0' + 52;
    else if (c == '+') v = 62;
    else if (c == '/') v = 63;
    else if (c == '=' || c == ' ' || c == '\n' || c == '\r' || c == '\t') continue;
    else return false;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((acc >> bits) & 0xFF);
    }
  }
  return true;
}

struct TypeInfo {
  int size = 0;
  bool is_float = false;
  bool is_signed = false;
};

bool type_info(std::string_view t, TypeInfo& i) {
  if (t == "Float32") i = {4, true, true};
  else if (t == "Float64") i = {8, true, true};
  else if (t == "Int8") i = {1, false, true};
  else if (t == "UInt8") i = {1, false, false};
  else if (t == "Int16") i = {2, false, true};
  else if (t == "UInt16") i = {2, false, false};
  else if (t == "Int32") i = {4, false, true};
  else if (t == "UInt32") i = {4, false, false};
  else if (t == "Int64") i = {8, false, true};
  else if (t == "UInt64") i = {8, false, false};
  else return false;
  return true;
}

double decode_value(const char* p, const TypeInfo& t, bool big_endian) {
  unsigned char b[8];
  std::memcpy(b, p, static_cast<std::size_t>(t.size));
  if (big_endian != (std::endian::native == std::endian::big))
    std::reverse(b, b + t.size);
  if (t.is_float) {
    if (t.size == 4) {
      float f;
      std::memcpy(&f, b, 4);
      return f;
    }
    double d;
    std::memcpy(&d, b, 8);
    return d;
  }
  switch (t.size) {
    case 1: return t.is_signed ? double(std::int8_t(b[0])) : double(b[0]);
    case 2: {
      std::uint16_t u;
      std::memcpy(&u, b, 2);
      return t.is_signed ? double(std::int16_t(u)) : double(u);
    }
    case 4: {
      std::uint32_t u;
      std::memcpy(&u, b, 4);
      return t.is_signed ? double(std::int32_t(u)) : double(u);
    }
    default: {
      std::uint64_t u;
      std::memcpy(&u, b, 8);
      return t.is_signed ? double(std::int64_t(u)) : double(u);
    }
  }
}

/// A whole VTK XML file: the parsed tree plus the appended-data block, if any.
struct VtkDocument {
  std::string_view bytes;
  std::string name;
  std::unique_ptr<XmlNode> root;
  std::string_view appended;  ///< bytes after the '_' marker
  bool appended_base64 = false;
  bool big_endian = false;
  bool zlib = false;  ///< compressor="vtkZLibDataCompressor"
  int header_size = 4;

  [[noreturn]] void fail(const XmlNode& at, const std::string& problem) const {
    throw IoError(name, problem, {.line = line_at(bytes, at.offset), .byte_offset = std::nullopt});
  }
};

VtkDocument open_document(std::string_view bytes, const std::string& name, const char* expected_type) {
  VtkDocument doc;
  doc.bytes = bytes;
  doc.name = name;
  // The appended block may hold raw binary, which is not XML: cut it out before parsing.
  const auto app = bytes.find("<AppendedData");
  std::string xml;
  if (app != std::string_view::npos) {
    const auto gt = bytes.find('>', app);
    const auto underscore = gt == std::string_view::npos ? gt : bytes.find('_', gt);
    if (underscore == std::string_view::npos)
      throw IoError(name, "<AppendedData> without its '_' marker", {.line = line_at(bytes, app), .byte_offset = std::nullopt});
    const auto close = bytes.rfind("</AppendedData>");
    if (close == std::string_view::npos || close < underscore)
      throw IoError(name, "<AppendedData> is not closed (truncated?)", {.line = line_at(bytes, app), .byte_offset = std::nullopt});
    doc.appended = bytes.substr(underscore + 1, close - underscore - 1);
    const std::string tag(bytes.substr(app, gt - app));
    doc.appended_base64 = tag.find("\"base64\"") != std::string::npos;
    xml = std::string(bytes.substr(0, app));
    // Everything up to the appended block, closed again so that it parses; the tail after
    // </AppendedData> only closes VTKFile.
    xml += "</VTKFile>";
  } else {
    xml = std::string(bytes);
  }
  doc.root = parse_xml(xml, name);
  const XmlNode& r = *doc.root;
  if (r.name != "VTKFile") doc.fail(r, fmt::format("root element is <{}>, expected <VTKFile>", r.name));
  const std::string* type = r.attribute("type");
  if (!type || *type != expected_type)
    doc.fail(r, fmt::format("VTKFile type is '{}', expected '{}'", type ? *type : "", expected_type));
  if (const auto* c = r.attribute("compressor"); c && !c->empty()) {
    if (*c != "vtkZLibDataCompressor")
      doc.fail(r, fmt::format("compressor '{}' is not supported (only vtkZLibDataCompressor)", *c));
    doc.zlib = true;
  }
  if (const auto* bo = r.attribute("byte_order")) doc.big_endian = *bo == "BigEndian";
  if (const auto* ht = r.attribute("header_type")) {
    if (*ht == "UInt64") doc.header_size = 8;
    else if (*ht == "UInt32") doc.header_size = 4;
    else doc.fail(r, fmt::format("unknown header_type '{}'", *ht));
  }
  return doc;
}

/// A DataArray's values as doubles. @p expected_tuples × components values must result.
std::vector<double> read_array(const VtkDocument& doc, const XmlNode& a, std::size_t expected_tuples,
                               int* components_out = nullptr) {
  const std::string* type = a.attribute("type");
  TypeInfo ti;
  if (!type || !type_info(*type, ti)) doc.fail(a, fmt::format("DataArray has unsupported type '{}'", type ? *type : ""));
  int comps = 1;
  if (const auto* nc = a.attribute("NumberOfComponents")) {
    std::int64_t v;
    if (!to_int(*nc, v) || v < 1 || v > 64) doc.fail(a, fmt::format("bad NumberOfComponents '{}'", *nc));
    comps = static_cast<int>(v);
  }
  if (components_out) *components_out = comps;
  const std::size_t expected = expected_tuples * static_cast<std::size_t>(comps);
  const std::string* fmt_attr = a.attribute("format");
  const std::string format = fmt_attr ? *fmt_attr : "ascii";
  const std::string array_name = a.attribute("Name") ? *a.attribute("Name") : std::string("(unnamed)");
  std::vector<double> out;
  const std::size_t need = expected * static_cast<std::size_t>(ti.size);
  const auto hs = static_cast<std::size_t>(doc.header_size);
  auto header_value = [&](std::string_view raw, std::size_t i) {
    return decode_value(raw.data() + i * hs, {doc.header_size, false, false}, doc.big_endian);
  };
  auto decode_payload = [&](std::string_view payload) {
    out.resize(expected);
    for (std::size_t i = 0; i < expected; ++i)
      out[i] = decode_value(payload.data() + i * static_cast<std::size_t>(ti.size), ti, doc.big_endian);
  };
  // Uncompressed: one header value (the byte count), then the data.
  auto from_bytes = [&](std::string_view raw, const char* where) {
    if (raw.size() < hs) doc.fail(a, fmt::format("DataArray '{}': {} data shorter than its header", array_name, where));
    const double declared = header_value(raw, 0);
    if (declared != static_cast<double>(need))
      doc.fail(a, fmt::format("DataArray '{}' declares {} bytes, expected {} ({} values of {} bytes)", array_name,
                              declared, need, expected, ti.size));
    if (raw.size() - hs < need)
      doc.fail(a, fmt::format("DataArray '{}': data ends after {} of {} bytes (truncated?)", array_name, raw.size() - hs,
                              need));
    decode_payload(raw.substr(hs, need));
  };
  // zlib-compressed ("VTK File Formats", compressed data): a header of [block count,
  // uncompressed block size, size of the last block (0 = full), compressed size of each
  // block], then the compressed blocks one after another. Decompression is zlib's.
  auto header_count = [&](std::string_view header, const char* where) {
    if (header.size() < 3 * hs)
      doc.fail(a, fmt::format("DataArray '{}': {} compressed header is truncated", array_name, where));
    const double n = header_value(header, 0);
    if (!(n >= 0) || n > 1e9 || n != std::floor(n))
      doc.fail(a, fmt::format("DataArray '{}': bad compressed block count {}", array_name, n));
    return static_cast<std::size_t>(n);
  };
  auto inflate = [&](std::string_view header, std::string_view blocks, const char* where) {
    const std::size_t n = header_count(header, where);
    if (header.size() < (3 + n) * hs)
      doc.fail(a, fmt::format("DataArray '{}': {} compressed header is truncated", array_name, where));
    const double block = header_value(header, 1), last = header_value(header, 2);
    const double total = n == 0 ? 0.0 : block * static_cast<double>(n - 1) + (last > 0 ? last : block);
    if (total != static_cast<double>(need) || (n > 0 && !(block > 0)))
      doc.fail(a, fmt::format("DataArray '{}' declares {} uncompressed bytes, expected {} ({} values of {} bytes)",
                              array_name, total, need, expected, ti.size));
    // zlib inflates at most 1032:1: a declared size beyond that is impossible for the blocks
    // at hand, and is refused before the payload is allocated.
    if (static_cast<double>(need) > 1032.0 * static_cast<double>(blocks.size()) + 1024.0)
      doc.fail(a, fmt::format("DataArray '{}' declares {} uncompressed bytes, more than its {} compressed bytes can hold",
                              array_name, need, blocks.size()));
    std::string payload(need, '\0');
    std::size_t in_pos = 0, out_pos = 0;
    for (std::size_t b = 0; b < n; ++b) {
      const auto csize = static_cast<std::size_t>(header_value(header, 3 + b));
      const auto usize = static_cast<std::size_t>(b + 1 == n && last > 0 ? last : block);
      if (in_pos + csize > blocks.size())
        doc.fail(a, fmt::format("DataArray '{}': compressed block {} ends beyond the data (truncated?)", array_name, b));
      uLongf got = static_cast<uLongf>(usize);
      const int rc = ::uncompress(reinterpret_cast<Bytef*>(payload.data() + out_pos), &got,
                                  reinterpret_cast<const Bytef*>(blocks.data() + in_pos), static_cast<uLong>(csize));
      if (rc != Z_OK || got != usize)
        doc.fail(a, fmt::format("DataArray '{}': compressed block {} does not inflate to {} bytes (zlib: {})", array_name,
                                b, usize, rc == Z_OK ? "short" : zError(rc)));
      in_pos += csize;
      out_pos += usize;
    }
    decode_payload(payload);
  };
  auto b64 = [&](std::string_view text, const char* where) {
    std::string decoded;
    if (!base64_decode(text, decoded)) doc.fail(a, fmt::format("DataArray '{}': invalid base64 {} data", array_name, where));
    return decoded;
  };
  /// Base64 text holding header + data, encoded either as one stream or as two blocks
  /// (always two when compressed: the header's length is known only after its first value).
  auto from_base64 = [&](std::string_view text, const char* where) {
    std::size_t first = 0;
    while (first < text.size() && std::isspace(static_cast<unsigned char>(text[first]))) ++first;
    text.remove_prefix(first);
    if (doc.zlib) {
      const std::string lead = b64(text.substr(0, (hs + 2) / 3 * 4), where);
      const std::size_t n = header_count(lead + std::string(3 * hs, '\0'), where);
      const std::size_t header_chars = ((3 + n) * hs + 2) / 3 * 4;
      if (text.size() < header_chars)
        doc.fail(a, fmt::format("DataArray '{}': {} compressed header is truncated", array_name, where));
      const std::string header = b64(text.substr(0, header_chars), where);
      double compressed = 0;  // the data stream's length; appended arrays follow one another
      for (std::size_t b = 0; b < n; ++b) compressed += header_value(header, 3 + b);
      const auto data_chars = (static_cast<std::size_t>(compressed) + 2) / 3 * 4;
      inflate(header, b64(text.substr(header_chars, data_chars), where), where);
      return;
    }
    const std::size_t header_chars = (hs + 2) / 3 * 4;
    std::string decoded = text.substr(0, header_chars).find('=') != std::string_view::npos
                              ? b64(text.substr(0, header_chars), where) + b64(text.substr(header_chars), where)
                              : b64(text, where);
    from_bytes(decoded, where);
  };
  auto from_raw = [&](std::string_view raw, const char* where) {
    if (!doc.zlib) return from_bytes(raw, where);
    const std::size_t n = header_count(raw, where);
    if (raw.size() < (3 + n) * hs)
      doc.fail(a, fmt::format("DataArray '{}': {} compressed header is truncated", array_name, where));
    inflate(raw.substr(0, (3 + n) * hs), raw.substr((3 + n) * hs), where);
  };
  if (format == "ascii") {
    TextCursor tc(doc.bytes.substr(a.text_begin, a.text_end - a.text_begin), doc.name);
    const std::int64_t base_line = line_at(doc.bytes, a.text_begin) - 1;
    // Each value takes at least two characters (a digit and a separator): reserve no more
    // than the text can hold, whatever the header declares.
    out.reserve(std::min(expected, (a.text_end - a.text_begin) / 2 + 1));
    while (!tc.at_end()) {
      const auto t = tc.next();
      double v;
      if (!to_double(t, v))
        throw IoError(doc.name, fmt::format("DataArray '{}': expected a number, found '{}'", array_name, t.substr(0, 40)),
                      {.line = base_line + tc.line(), .byte_offset = std::nullopt});
      out.push_back(v);
      if (out.size() > expected) break;
    }
    if (out.size() != expected)
      doc.fail(a, fmt::format("DataArray '{}' holds {} values, expected {}", array_name, out.size() > expected ? "more" : std::to_string(out.size()), expected));
  } else if (format == "binary") {
    from_base64(doc.bytes.substr(a.text_begin, a.text_end - a.text_begin), "inline");
  } else if (format == "appended") {
    std::int64_t off = 0;
    const std::string* o = a.attribute("offset");
    if (!o || !to_int(*o, off) || off < 0) doc.fail(a, fmt::format("DataArray '{}' has no valid offset", array_name));
    if (static_cast<std::size_t>(off) > doc.appended.size())
      doc.fail(a, fmt::format("DataArray '{}': offset {} lies beyond the appended data ({} bytes)", array_name, off,
                              doc.appended.size()));
    const std::string_view rest = doc.appended.substr(static_cast<std::size_t>(off));
    if (doc.appended_base64) from_base64(rest.substr(0, rest.find_first_of(" \n\r\t")), "appended");
    else from_raw(rest, "appended");
  } else {
    doc.fail(a, fmt::format("DataArray '{}' has unknown format '{}'", array_name, format));
  }
  return out;
}

std::size_t count_attr(const VtkDocument& doc, const XmlNode& piece, const char* attr, bool required) {
  const std::string* s = piece.attribute(attr);
  if (!s) {
    if (required) doc.fail(piece, fmt::format("<Piece> lacks {}", attr));
    return 0;
  }
  std::int64_t v;
  if (!to_int(*s, v) || v < 0) doc.fail(piece, fmt::format("<Piece> {}='{}' is not a count", attr, *s));
  // Guard allocations: every point or cell needs at least one byte of file.
  if (static_cast<std::uint64_t>(v) > doc.bytes.size() * 4 + 64)
    doc.fail(piece, fmt::format("<Piece> {}={} is larger than the file can hold", attr, v));
  return static_cast<std::size_t>(v);
}

const XmlNode& single_piece(const VtkDocument& doc, const char* dataset) {
  const XmlNode* ds = doc.root->child(dataset);
  if (!ds) doc.fail(*doc.root, fmt::format("no <{}> element", dataset));
  const auto pieces = ds->children_named("Piece");
  if (pieces.size() != 1) doc.fail(*ds, fmt::format("{} <Piece> elements; exactly one is supported", pieces.size()));
  return *pieces.front();
}

std::vector<Vec3> read_points(const VtkDocument& doc, const XmlNode& piece, std::size_t n) {
  const XmlNode* pts = piece.child("Points");
  if (!pts && n > 0) doc.fail(piece, "<Piece> has no <Points>");
  std::vector<Vec3> out(n);
  if (n == 0) return out;
  const XmlNode* arr = pts->child("DataArray");
  if (!arr) doc.fail(*pts, "<Points> has no <DataArray>");
  int comps = 0;
  const auto v = read_array(doc, *arr, n, &comps);
  if (comps != 3) doc.fail(*arr, fmt::format("points have {} components, expected 3", comps));
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    if (!out[i].allFinite())
      invalid(doc.name, fmt::format("point {} has a non-finite coordinate", i), {.line = line_at(doc.bytes, arr->offset), .byte_offset = std::nullopt});
  }
  return out;
}

/// connectivity + offsets of a cell block (Polys, Cells).
struct CellBlock {
  std::vector<double> connectivity;
  std::vector<double> offsets;
};

CellBlock read_cells(const VtkDocument& doc, const XmlNode& block, std::size_t cells, std::size_t points) {
  CellBlock cb;
  const XmlNode* conn = nullptr;
  const XmlNode* offs = nullptr;
  for (const auto* a : block.children_named("DataArray")) {
    const std::string* n = a->attribute("Name");
    if (n && *n == "connectivity") conn = a;
    if (n && *n == "offsets") offs = a;
  }
  if (!conn || !offs) doc.fail(block, fmt::format("<{}> needs 'connectivity' and 'offsets' arrays", block.name));
  cb.offsets = read_array(doc, *offs, cells);
  double prev = 0;
  for (std::size_t c = 0; c < cells; ++c) {
    if (cb.offsets[c] < prev || cb.offsets[c] != std::floor(cb.offsets[c]))
      doc.fail(*offs, fmt::format("offsets decrease or are not integers at cell {}", c));
    prev = cb.offsets[c];
  }
  if (prev > 1e9) doc.fail(*offs, "offsets are implausibly large");
  cb.connectivity = read_array(doc, *conn, static_cast<std::size_t>(prev));
  for (std::size_t i = 0; i < cb.connectivity.size(); ++i) {
    const double v = cb.connectivity[i];
    if (v < 0 || v >= static_cast<double>(points) || v != std::floor(v))
      invalid(doc.name, fmt::format("connectivity entry {} refers to point {}, but there are {} points", i, v, points),
              {.line = line_at(doc.bytes, conn->offset), .byte_offset = std::nullopt});
  }
  return cb;
}

/// Point or cell data arrays, with each value picked through @p keep (source index per
/// output entity).
geometry::FieldMap read_fields(const VtkDocument& doc, const XmlNode* data, std::size_t count,
                               const std::vector<std::size_t>* keep) {
  geometry::FieldMap out;
  if (!data) return out;
  for (const auto* a : data->children_named("DataArray")) {
    const std::string* n = a->attribute("Name");
    const std::string* t = a->attribute("type");
    TypeInfo ti;
    if (!n || !t || !type_info(*t, ti)) continue;  // e.g. String arrays: not fields
    geometry::Field f;
    auto values = read_array(doc, *a, count, &f.components);
    if (keep) {
      const auto c = static_cast<std::size_t>(f.components);
      f.values.reserve(keep->size() * c);
      for (std::size_t src : *keep)
        for (std::size_t k = 0; k < c; ++k) f.values.push_back(values[src * c + k]);
    } else {
      f.values = std::move(values);
    }
    out[*n] = std::move(f);
  }
  return out;
}

// ---- writing ---------------------------------------------------------------------------

class ArrayWriter {
 public:
  ArrayWriter(std::ostream& out, bool ascii) : m_out(out), m_ascii(ascii) {}

  /// A DataArray of @p count values that @p generate hands one at a time to the sink it is
  /// given (put(value), exactly @p count times): written as generated, so neither the caller
  /// nor the writer holds the array. Binary: one base64 stream of a UInt64 byte count
  /// followed by the little-endian values. @throws ido::Error if the generator gives another
  /// count (the header would be wrong).
  template <class T, class Generate>
  void stream(const char* type, const std::string& name, int comps, std::size_t count, Generate&& generate,
              const char* indent, int per_line) {
    static_assert(std::endian::native == std::endian::little, "writer assumes a little-endian host");
    open(type, name, comps, indent);
    std::size_t given = 0;
    if (m_ascii) {
      generate([&](T v) {
        m_out << (given % std::size_t(per_line) ? " " : "\n");
        if constexpr (std::is_floating_point_v<T>)
          m_out << fmt::format("{:.17g}", v);
        else
          m_out << +v;
        ++given;
      });
    } else {
      Base64Stream b64(m_out);
      const std::uint64_t bytes = count * sizeof(T);
      b64.put(&bytes, 8);
      std::array<T, 512> chunk;
      std::size_t m = 0;
      generate([&](T v) {
        chunk[m++] = v;
        ++given;
        if (m == chunk.size()) {
          b64.put(chunk.data(), m * sizeof(T));
          m = 0;
        }
      });
      b64.put(chunk.data(), m * sizeof(T));
      b64.finish();
    }
    if (given != count)
      throw Error(fmt::format("VTK writer: DataArray '{}' was given {} values, its header says {}", name, given, count));
    close(indent);
  }
  /// As stream(), value i being @p value(i).
  template <class T, class F>
  void values(const char* type, const std::string& name, int comps, std::size_t count, F&& value, const char* indent,
              int per_line) {
    stream<T>(
        type, name, comps, count,
        [&](auto&& put) {
          for (std::size_t i = 0; i < count; ++i) put(value(i));
        },
        indent, per_line);
  }

 private:
  void open(const char* type, const std::string& name, int comps, const char* indent) {
    m_out << indent << "<DataArray type=\"" << type << "\" Name=\"" << xml_escape(name) << "\"";
    if (comps != 1) m_out << " NumberOfComponents=\"" << comps << "\"";
    m_out << " format=\"" << (m_ascii ? "ascii" : "binary") << "\">";
    if (!m_ascii) m_out << "\n" << indent << "  ";
  }
  void close(const char* indent) { m_out << "\n" << indent << "</DataArray>\n"; }
  std::ostream& m_out;
  bool m_ascii;
};

/// The points as a Float64 array of 3 components, read from @p pts as written.
void write_points(ArrayWriter& w, const std::vector<Vec3>& pts) {
  w.values<double>("Float64", "Points", 3, pts.size() * 3, [&](std::size_t i) { return pts[i / 3][int(i % 3)]; },
                   "        ", 9);
}

/// Connectivity and offsets of cells of @p n corners each, read from @p cells as written.
template <class Cells>
void write_cells(ArrayWriter& w, const Cells& cells, std::size_t n) {
  w.values<std::int64_t>("Int64", "connectivity", 1, cells.size() * n,
                         [&](std::size_t i) { return std::int64_t(cells[i / n][i % n]); }, "        ", 12);
  w.values<std::int64_t>("Int64", "offsets", 1, cells.size(), [&](std::size_t i) { return std::int64_t((i + 1) * n); },
                         "        ", 12);
}

void write_fields(ArrayWriter& w, std::ostream& out, const char* tag, const geometry::FieldMap& fields) {
  out << "      <" << tag << ">\n";
  for (const auto& entry : fields) {
    const auto& f = entry.second;
    w.values<double>("Float64", entry.first, f.components, f.values.size(), [&](std::size_t i) { return f.values[i]; },
                     "        ", 9);
  }
  out << "      </" << tag << ">\n";
}

/// Point or cell data arrays of a streamed mesh, each generated by @p values(field, put).
void write_fields(ArrayWriter& w, std::ostream& out, const char* tag, const std::vector<StreamedField>& fields,
                  std::size_t count, const std::function<void(std::size_t, const std::function<void(double)>&)>& values) {
  out << "      <" << tag << ">\n";
  for (std::size_t k = 0; k < fields.size(); ++k) {
    const auto& f = fields[k];
    w.stream<double>("Float64", f.name, f.components, count * static_cast<std::size_t>(f.components),
                     [&](auto&& put) { values(k, put); }, "        ", 9);
  }
  out << "      </" << tag << ">\n";
}

void header(std::ostream& out, const char* type) {
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"" << type
      << "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <" << type << ">\n";
}

}  // namespace

geometry::TriangleMesh parse_vtp(std::string_view bytes, const std::string& name) {
  const VtkDocument doc = open_document(bytes, name, "PolyData");
  const XmlNode& piece = single_piece(doc, "PolyData");
  const std::size_t np = count_attr(doc, piece, "NumberOfPoints", true);
  const std::size_t nverts = count_attr(doc, piece, "NumberOfVerts", false);
  const std::size_t nlines = count_attr(doc, piece, "NumberOfLines", false);
  const std::size_t nstrips = count_attr(doc, piece, "NumberOfStrips", false);
  const std::size_t npolys = count_attr(doc, piece, "NumberOfPolys", false);
  geometry::TriangleMesh mesh;
  mesh.vertices = read_points(doc, piece, np);
  std::vector<std::size_t> source_cell;  // VTK cell index of each triangle (verts, lines, strips, polys order)
  const std::size_t first_poly = nverts + nlines + nstrips;
  if (npolys > 0) {
    const XmlNode* polys = piece.child("Polys");
    if (!polys) doc.fail(piece, "NumberOfPolys > 0 but no <Polys>");
    const CellBlock cb = read_cells(doc, *polys, npolys, np);
    std::size_t begin = 0;
    for (std::size_t c = 0; c < npolys; ++c) {
      const auto end = static_cast<std::size_t>(cb.offsets[c]);
      if (end - begin < 3) doc.fail(*polys, fmt::format("polygon {} has {} points, expected at least 3", c, end - begin));
      for (std::size_t k = begin + 1; k + 1 < end; ++k) {
        mesh.triangles.push_back({static_cast<std::int32_t>(cb.connectivity[begin]),
                                  static_cast<std::int32_t>(cb.connectivity[k]),
                                  static_cast<std::int32_t>(cb.connectivity[k + 1])});
        source_cell.push_back(first_poly + c);
      }
      begin = end;
    }
  }
  mesh.point_fields = read_fields(doc, piece.child("PointData"), np, nullptr);
  mesh.cell_fields = read_fields(doc, piece.child("CellData"), first_poly + npolys, &source_cell);
  validate(mesh, name);
  return mesh;
}

namespace {
/// VTK's 3D cell types other than VTK_TETRA (10): voxel, hexahedron, wedge, pyramid, prisms,
/// their quadratic, polyhedral, Lagrange and Bézier forms. A TetMesh cannot hold them, and
/// dropping them would lose volume without a word.
bool is_volume_cell_other_than_tetra(std::int64_t type) {
  switch (type) {
    case 11: case 12: case 13: case 14: case 15: case 16:  // linear
    case 24: case 25: case 26: case 27: case 29: case 32: case 33:  // quadratic
    case 42:  // polyhedron
    case 71: case 72: case 73: case 74:  // Lagrange
    case 78: case 79: case 80: case 81:  // Bézier
      return true;
    default:
      return false;
  }
}
}  // namespace

geometry::TetMesh parse_vtu(std::string_view bytes, const std::string& name) {
  const VtkDocument doc = open_document(bytes, name, "UnstructuredGrid");
  const XmlNode& piece = single_piece(doc, "UnstructuredGrid");
  const std::size_t np = count_attr(doc, piece, "NumberOfPoints", true);
  const std::size_t nc = count_attr(doc, piece, "NumberOfCells", true);
  geometry::TetMesh mesh;
  mesh.vertices = read_points(doc, piece, np);
  std::vector<std::size_t> kept;
  std::vector<std::int64_t> element_lines;
  if (nc > 0) {
    const XmlNode* cells = piece.child("Cells");
    if (!cells) doc.fail(piece, "NumberOfCells > 0 but no <Cells>");
    const CellBlock cb = read_cells(doc, *cells, nc, np);
    const XmlNode* types_node = nullptr;
    for (const auto* a : cells->children_named("DataArray"))
      if (const auto* n = a->attribute("Name"); n && *n == "types") types_node = a;
    if (!types_node) doc.fail(*cells, "<Cells> has no 'types' array");
    const auto types = read_array(doc, *types_node, nc);
    std::size_t begin = 0;
    for (std::size_t c = 0; c < nc; ++c) {
      const auto end = static_cast<std::size_t>(cb.offsets[c]);
      if (is_volume_cell_other_than_tetra(static_cast<std::int64_t>(types[c])))
        doc.fail(*cells, fmt::format("cell {} has VTK type {}, a volume cell that is not a linear tetrahedron "
                                     "(only type 10 is read; split the mesh into tetrahedra first)",
                                     c, static_cast<std::int64_t>(types[c])));
      if (types[c] == 10) {  // VTK_TETRA; lower-dimensional cells (boundary faces, lines) are skipped
        if (end - begin != 4) doc.fail(*cells, fmt::format("tetrahedron {} has {} points, expected 4", c, end - begin));
        mesh.tets.push_back({static_cast<std::int32_t>(cb.connectivity[begin]), static_cast<std::int32_t>(cb.connectivity[begin + 1]),
                             static_cast<std::int32_t>(cb.connectivity[begin + 2]), static_cast<std::int32_t>(cb.connectivity[begin + 3])});
        kept.push_back(c);
      }
      begin = end;
    }
  }
  mesh.point_fields = read_fields(doc, piece.child("PointData"), np, nullptr);
  mesh.cell_fields = read_fields(doc, piece.child("CellData"), nc, &kept);
  validate(mesh, name);
  return mesh;
}

void write_vtp(std::ostream& out, const geometry::TriangleMesh& mesh, bool ascii) {
  ArrayWriter w(out, ascii);
  header(out, "PolyData");
  out << "    <Piece NumberOfPoints=\"" << mesh.vertices.size() << "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" "
      << "NumberOfStrips=\"0\" NumberOfPolys=\"" << mesh.triangles.size() << "\">\n";
  write_fields(w, out, "PointData", mesh.point_fields);
  write_fields(w, out, "CellData", mesh.cell_fields);
  out << "      <Points>\n";
  write_points(w, mesh.vertices);
  out << "      </Points>\n      <Polys>\n";
  write_cells(w, mesh.triangles, 3);
  out << "      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
}

void write_vtu(std::ostream& out, const geometry::TetMesh& mesh, bool ascii) {
  ArrayWriter w(out, ascii);
  header(out, "UnstructuredGrid");
  out << "    <Piece NumberOfPoints=\"" << mesh.vertices.size() << "\" NumberOfCells=\"" << mesh.tets.size() << "\">\n";
  write_fields(w, out, "PointData", mesh.point_fields);
  write_fields(w, out, "CellData", mesh.cell_fields);
  out << "      <Points>\n";
  write_points(w, mesh.vertices);
  out << "      </Points>\n      <Cells>\n";
  write_cells(w, mesh.tets, 4);
  w.values<std::uint8_t>("UInt8", "types", 1, mesh.tets.size(), [](std::size_t) { return std::uint8_t(10); }, "        ",
                         20);
  out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
}

namespace {

/// Points, connectivity and offsets of a streamed mesh whose cells have @p n corners.
template <class Mesh, class Cell>
void write_streamed_geometry(ArrayWriter& w, std::ostream& out, const Mesh& mesh,
                             const std::function<void(const std::function<void(const Cell&)>&)>& cells,
                             std::size_t cell_count, const char* cells_tag) {
  constexpr std::size_t n = std::tuple_size_v<Cell>;
  out << "      <Points>\n";
  w.stream<double>(
      "Float64", "Points", 3, mesh.vertex_count * 3,
      [&](auto&& put) {
        mesh.vertices([&](const Vec3& p) {
          for (int c = 0; c < 3; ++c) put(p[c]);
        });
      },
      "        ", 9);
  out << "      </Points>\n      <" << cells_tag << ">\n";
  w.stream<std::int64_t>(
      "Int64", "connectivity", 1, cell_count * n,
      [&](auto&& put) {
        cells([&](const Cell& t) {
          for (const auto v : t) put(std::int64_t(v));
        });
      },
      "        ", 12);
  w.values<std::int64_t>("Int64", "offsets", 1, cell_count, [](std::size_t i) { return std::int64_t((i + 1) * n); },
                         "        ", 12);
}

}  // namespace

void write_vtu(std::ostream& out, const StreamedTetMesh& mesh, bool ascii) {
  ArrayWriter w(out, ascii);
  header(out, "UnstructuredGrid");
  out << "    <Piece NumberOfPoints=\"" << mesh.vertex_count << "\" NumberOfCells=\"" << mesh.tet_count << "\">\n";
  write_fields(w, out, "PointData", mesh.point_fields, mesh.vertex_count, mesh.point_values);
  write_fields(w, out, "CellData", mesh.cell_fields, mesh.tet_count, mesh.cell_values);
  write_streamed_geometry<StreamedTetMesh, Tet>(w, out, mesh, mesh.tets, mesh.tet_count, "Cells");
  w.values<std::uint8_t>("UInt8", "types", 1, mesh.tet_count, [](std::size_t) { return std::uint8_t(10); }, "        ",
                         20);
  out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
}

void write_vtp(std::ostream& out, const StreamedTriangleMesh& mesh, bool ascii) {
  ArrayWriter w(out, ascii);
  header(out, "PolyData");
  out << "    <Piece NumberOfPoints=\"" << mesh.vertex_count << "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" "
      << "NumberOfStrips=\"0\" NumberOfPolys=\"" << mesh.triangle_count << "\">\n";
  write_fields(w, out, "PointData", mesh.point_fields, mesh.vertex_count, mesh.point_values);
  write_fields(w, out, "CellData", mesh.cell_fields, mesh.triangle_count, mesh.cell_values);
  write_streamed_geometry<StreamedTriangleMesh, Tri>(w, out, mesh, mesh.triangles, mesh.triangle_count, "Polys");
  out << "      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
}

}  // namespace ido::io::detail

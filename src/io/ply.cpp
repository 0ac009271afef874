// SPDX-License-Identifier: Apache-2.0
// PLY (Turk, "The PLY Polygon File Format", 1994): ASCII and binary little / big endian.
// Reads the x, y, z properties of `vertex` and the index list of `face` (vertex_indices
// or vertex_index); other properties and elements are parsed and skipped; polygons are
// split into a fan.
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "parsers.h"
#include "text_parser.h"

namespace ido::io::detail {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool ply_type(std::string_view s, PlyType& t) {
  if (s == "char" || s == "int8") t = PlyType::Int8;
  else if (s == "uchar" || s == "uint8") t = PlyType::UInt8;
  else if (s == "short" || s == "int16") t = PlyType::Int16;
  else if (s == "ushort" || s == "uint16") t = PlyType::UInt16;
  else if (s == "int" || s == "int32") t = PlyType::Int32;
  else if (s == "uint" || s == "uint32") t = PlyType::UInt32;
  else if (s == "float" || s == "float32") t = PlyType::Float32;
  else if (s == "double" || s == "float64") t = PlyType::Float64;
  else return false;
  return true;
}

struct Property {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
  PlyType type = PlyType::Float32;
};

struct Element {
  std::string name;
  std::int64_t count = 0;
  std::vector<Property> properties;
  std::int64_t line = 0;
};

enum class Encoding { Ascii, BinaryLe, BinaryBe };

double read_binary(ByteCursor& in, PlyType t, bool be, std::string_view what) {
  switch (t) {
    case PlyType::Int8: return in.read<std::int8_t>(be, what);
    case PlyType::UInt8: return in.read<std::uint8_t>(be, what);
    case PlyType::Int16: return in.read<std::int16_t>(be, what);
    case PlyType::UInt16: return in.read<std::uint16_t>(be, what);
    case PlyType::Int32: return in.read<std::int32_t>(be, what);
    case PlyType::UInt32: return in.read<std::uint32_t>(be, what);
    case PlyType::Float32: return in.read<float>(be, what);
    case PlyType::Float64: return in.read<double>(be, what);
  }
  return 0.0;
}

}  // namespace

geometry::TriangleMesh parse_ply(std::string_view bytes, const std::string& name) {
  if (bytes.substr(0, 3) != "ply" || (bytes.size() > 3 && bytes[3] != '\n' && bytes[3] != '\r'))
    throw IoError(name, "missing the 'ply' magic line", {.line = 1, .byte_offset = std::nullopt});
  const std::size_t header_end_tag = bytes.find("end_header");
  if (header_end_tag == std::string_view::npos) throw IoError(name, "no 'end_header' line (truncated header?)");
  std::size_t body = bytes.find('\n', header_end_tag);
  body = body == std::string_view::npos ? bytes.size() : body + 1;

  TextCursor hdr(bytes.substr(0, body), name);
  hdr.skip_line();
  Encoding enc = Encoding::Ascii;
  bool have_format = false;
  std::vector<Element> elements;
  while (true) {
    if (hdr.at_end()) hdr.fail("header ends without an 'end_header' line");
    const auto key = hdr.next_on_line();
    if (key == "end_header") break;
    if (key == "format") {
      const auto f = hdr.next_on_line();
      if (f == "ascii") enc = Encoding::Ascii;
      else if (f == "binary_little_endian") enc = Encoding::BinaryLe;
      else if (f == "binary_big_endian") enc = Encoding::BinaryBe;
      else hdr.fail(fmt::format("unknown PLY format '{}'", f.substr(0, 40)));
      if (hdr.next_on_line() != "1.0") hdr.fail("PLY version must be 1.0");
      have_format = true;
    } else if (key == "element") {
      Element e;
      e.name = std::string(hdr.next_on_line());
      const auto c = hdr.next_on_line();
      if (e.name.empty() || !to_int(c, e.count) || e.count < 0) hdr.fail("element needs a name and a count >= 0");
      e.line = hdr.line();
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) hdr.fail("property before any element");
      Property p;
      auto t = hdr.next_on_line();
      if (t == "list") {
        p.is_list = true;
        if (!ply_type(hdr.next_on_line(), p.count_type)) hdr.fail("unknown list count type");
        t = hdr.next_on_line();
      }
      if (!ply_type(t, p.type)) hdr.fail(fmt::format("unknown property type '{}'", t.substr(0, 40)));
      p.name = std::string(hdr.next_on_line());
      if (p.name.empty()) hdr.fail("property without a name");
      elements.back().properties.push_back(std::move(p));
    } else if (key != "comment" && key != "obj_info" && !key.empty()) {
      hdr.fail(fmt::format("unknown header keyword '{}'", key.substr(0, 40)));
    }
    hdr.skip_line();
  }
  if (!have_format) throw IoError(name, "PLY header has no 'format' line");

  geometry::TriangleMesh mesh;
  std::int64_t vertex_count = -1;
  for (const auto& e : elements)
    if (e.name == "vertex") vertex_count = e.count;
  if (vertex_count < 0) throw IoError(name, "PLY header declares no 'vertex' element");
  // Guard the allocations below against absurd counts: each vertex needs at least 3 bytes.
  if (static_cast<std::uint64_t>(vertex_count) > bytes.size())
    throw IoError(name, fmt::format("header declares {} vertices, more than the file can hold", vertex_count));

  std::vector<std::int64_t> vertex_lines, tri_lines;
  const bool be = enc == Encoding::BinaryBe;
  TextCursor text(bytes.substr(body), name);
  std::int64_t header_lines = hdr.line();
  ByteCursor bin(bytes, name, body);
  std::vector<double> list;
  for (const auto& e : elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1};
    int face_list = -1;
    for (std::size_t p = 0; p < e.properties.size(); ++p) {
      const auto& prop = e.properties[p];
      if (is_vertex && !prop.is_list && prop.name.size() == 1 && prop.name[0] >= 'x' && prop.name[0] <= 'z')
        xyz[prop.name[0] - 'x'] = static_cast<int>(p);
      if (is_face && prop.is_list && (prop.name == "vertex_indices" || prop.name == "vertex_index"))
        face_list = static_cast<int>(p);
    }
    if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
      throw IoError(name, "vertex element lacks x, y or z", {.line = e.line, .byte_offset = std::nullopt});
    if (is_face && face_list < 0)
      throw IoError(name, "face element has no vertex_indices list", {.line = e.line, .byte_offset = std::nullopt});
    // Every instance of an element with properties takes at least one byte: larger counts
    // cannot be satisfied (and would spin); property-less elements hold nothing to read.
    if (!e.properties.empty() && static_cast<std::uint64_t>(e.count) > bytes.size())
      throw IoError(name, fmt::format("element '{}' declares {} entries, more than the file can hold", e.name, e.count),
                    {.line = e.line, .byte_offset = std::nullopt});
    if (e.properties.empty()) continue;
    if (is_vertex) mesh.vertices.reserve(static_cast<std::size_t>(e.count));
    for (std::int64_t i = 0; i < e.count; ++i) {
      Vec3 p = Vec3::Zero();
      if (enc == Encoding::Ascii && text.at_end())
        throw IoError(name, fmt::format("file ends inside element '{}' {} of {} (truncated?)", e.name, i, e.count),
                      {.line = header_lines + text.line(), .byte_offset = std::nullopt});
      const std::size_t at = bin.offset();
      const std::int64_t line = header_lines + text.line();
      for (std::size_t q = 0; q < e.properties.size(); ++q) {
        const auto& prop = e.properties[q];
        if (prop.is_list) {
          double n;
          if (enc == Encoding::Ascii) n = static_cast<double>(text.read_int("list length"));
          else n = read_binary(bin, prop.count_type, be, "list length");
          if (n < 0 || n > 1e6 || n != std::floor(n))
            throw IoError(name, fmt::format("bad list length {} in element '{}' {}", n, e.name, i),
                          enc == Encoding::Ascii ? FileLocation{.line = line, .byte_offset = std::nullopt}
                                                 : FileLocation{.line = std::nullopt, .byte_offset = static_cast<std::int64_t>(at)});
          list.clear();
          for (int k = 0; k < static_cast<int>(n); ++k)
            list.push_back(enc == Encoding::Ascii ? text.read_double("list entry") : read_binary(bin, prop.type, be, "list entry"));
          if (is_face && static_cast<int>(q) == face_list) {
            if (list.size() < 3)
              invalid(name, fmt::format("face {} has {} corners, expected at least 3", i, list.size()),
                      enc == Encoding::Ascii ? FileLocation{.line = line, .byte_offset = std::nullopt}
                                             : FileLocation{.line = std::nullopt, .byte_offset = static_cast<std::int64_t>(at)});
            for (double v : list)
              if (v < 0 || v >= static_cast<double>(vertex_count) || v != std::floor(v))
                invalid(name, fmt::format("face {} refers to vertex {}, but there are {} vertices", i, v, vertex_count),
                        enc == Encoding::Ascii ? FileLocation{.line = line, .byte_offset = std::nullopt}
                                               : FileLocation{.line = std::nullopt, .byte_offset = static_cast<std::int64_t>(at)});
            for (std::size_t c = 1; c + 1 < list.size(); ++c) {
              mesh.triangles.push_back({static_cast<std::int32_t>(list[0]), static_cast<std::int32_t>(list[c]),
                                        static_cast<std::int32_t>(list[c + 1])});
              tri_lines.push_back(enc == Encoding::Ascii ? line : 0);
            }
          }
        } else {
          const double v = enc == Encoding::Ascii ? text.read_double(prop.name) : read_binary(bin, prop.type, be, prop.name);
          if (is_vertex)
            for (int a = 0; a < 3; ++a)
              if (xyz[a] == static_cast<int>(q)) p[a] = v;
        }
      }
      if (is_vertex) {
        if (!p.allFinite())
          invalid(name, fmt::format("vertex {} has a non-finite coordinate", i),
                  enc == Encoding::Ascii ? FileLocation{.line = line, .byte_offset = std::nullopt}
                                         : FileLocation{.line = std::nullopt, .byte_offset = static_cast<std::int64_t>(at)});
        mesh.vertices.push_back(p);
        vertex_lines.push_back(line);
      }
    }
  }
  if (enc == Encoding::Ascii && !text.at_end())
    throw IoError(name, "more data after the last element than the header declares",
                  {.line = header_lines + text.line(), .byte_offset = std::nullopt});
  validate(mesh, name);
  return mesh;
}

void write_ply(std::ostream& out, const geometry::TriangleMesh& mesh, bool ascii, bool big_endian) {
  out << "ply\nformat " << (ascii ? "ascii" : big_endian ? "binary_big_endian" : "binary_little_endian")
      << " 1.0\ncomment written by ido\n";
  out << "element vertex " << mesh.vertices.size() << "\nproperty double x\nproperty double y\nproperty double z\n";
  out << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  if (ascii) {
    for (const auto& p : mesh.vertices) out << fmt::format("{:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
    for (const auto& t : mesh.triangles) out << fmt::format("3 {} {} {}\n", t[0], t[1], t[2]);
    return;
  }
  auto put = [&](const void* src, std::size_t n) {
    char b[8];
    std::memcpy(b, src, n);
    if (big_endian != (std::endian::native == std::endian::big))
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    out.write(b, static_cast<std::streamsize>(n));
  };
  for (const auto& p : mesh.vertices)
    for (int a = 0; a < 3; ++a) put(&p[a], 8);
  for (const auto& t : mesh.triangles) {
    const std::uint8_t three = 3;
    put(&three, 1);
    for (const auto v : t) put(&v, 4);
  }
}

}  // namespace ido::io::detail

// SPDX-License-Identifier: Apache-2.0
// STL, ASCII and binary (format as in 3D Systems' StereoLithography Interface
// Specification, 1989). STL stores a triangle soup; vertices with bit-identical
// coordinates are merged into one indexed vertex.
#include <cmath>
#include <cstring>
#include <unordered_map>

#include <fmt/format.h>

#include "parsers.h"
#include "text_parser.h"

namespace ido::io::detail {
namespace {

struct KeyHash {
  std::size_t operator()(const std::array<double, 3>& k) const noexcept {
    std::size_t h = 1469598103934665603ull;
    for (double d : k) {
      std::uint64_t bits;
      std::memcpy(&bits, &d, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
    return h;
  }
};

/// Merges bit-identical corners into indexed vertices.
class VertexMerger {
 public:
  std::int32_t add(const Vec3& p, geometry::TriangleMesh& mesh) {
    const std::array<double, 3> key{p.x() == 0.0 ? 0.0 : p.x(), p.y() == 0.0 ? 0.0 : p.y(), p.z() == 0.0 ? 0.0 : p.z()};
    const auto [it, inserted] = m_index.try_emplace(key, static_cast<std::int32_t>(mesh.vertices.size()));
    if (inserted) mesh.vertices.push_back(p);
    return it->second;
  }

 private:
  std::unordered_map<std::array<double, 3>, std::int32_t, KeyHash> m_index;
};

geometry::TriangleMesh parse_binary(std::string_view bytes, const std::string& name) {
  ByteCursor in(bytes, name, 80);
  const auto count = in.read<std::uint32_t>(false, "triangle count");
  geometry::TriangleMesh mesh;
  VertexMerger merger;
  mesh.triangles.reserve(count);
  for (std::uint32_t t = 0; t < count; ++t) {
    in.skip(12, "facet normal");
    std::array<std::int32_t, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      const std::size_t at = in.offset();
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = in.read<float>(false, "vertex coordinates");
      if (!p.allFinite())
        invalid(name, fmt::format("triangle {} has a non-finite vertex coordinate", t),
                {.line = std::nullopt, .byte_offset = static_cast<std::int64_t>(at)});
      tri[static_cast<std::size_t>(c)] = merger.add(p, mesh);
    }
    in.skip(2, "attribute byte count");
    mesh.triangles.push_back(tri);
  }
  return mesh;
}

geometry::TriangleMesh parse_ascii(std::string_view bytes, const std::string& name) {
  TextCursor in(bytes, name);
  if (in.expect("'solid'") != "solid") in.fail("ASCII STL must start with 'solid'");
  (void)in.rest_of_line();
  geometry::TriangleMesh mesh;
  VertexMerger merger;
  std::vector<std::int64_t> vertex_lines, triangle_lines;
  auto expect_word = [&](std::string_view word) {
    const auto t = in.expect(fmt::format("'{}'", word));
    if (t != word) in.fail(fmt::format("expected '{}', found '{}'", word, t.substr(0, 40)));
  };
  bool ended = false;
  while (!in.at_end()) {
    const auto t = in.next();
    if (t == "endsolid") {
      ended = true;
      break;
    }
    if (t != "facet") in.fail(fmt::format("expected 'facet' or 'endsolid', found '{}'", t.substr(0, 40)));
    expect_word("normal");
    for (int a = 0; a < 3; ++a) (void)in.read_double("facet normal");
    expect_word("outer");
    expect_word("loop");
    std::vector<std::int32_t> corners;
    const std::int64_t facet_line = in.line();
    while (true) {
      const auto w = in.expect("'vertex' or 'endloop'");
      if (w == "endloop") break;
      if (w != "vertex") in.fail(fmt::format("expected 'vertex' or 'endloop', found '{}'", w.substr(0, 40)));
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = in.read_double("vertex coordinate");
      if (!p.allFinite()) invalid(name, "vertex has a non-finite coordinate", {.line = in.line(), .byte_offset = std::nullopt});
      const auto before = mesh.vertices.size();
      corners.push_back(merger.add(p, mesh));
      if (mesh.vertices.size() != before) vertex_lines.push_back(in.line());
    }
    if (corners.size() < 3) in.fail(fmt::format("facet has {} vertices, expected 3", corners.size()));
    for (std::size_t c = 1; c + 1 < corners.size(); ++c) {  // polygons: fan
      mesh.triangles.push_back({corners[0], corners[c], corners[c + 1]});
      triangle_lines.push_back(facet_line);
    }
    expect_word("endfacet");
  }
  if (!ended) in.fail("file ends before 'endsolid' (truncated?)");
  validate(mesh, name, vertex_lines, triangle_lines);
  return mesh;
}

}  // namespace

geometry::TriangleMesh parse_stl(std::string_view bytes, const std::string& name) {
  if (bytes.empty()) throw IoError(name, "file is empty");
  if (bytes.size() >= 84) {
    std::uint32_t count;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (84 + 50 * std::uint64_t(count) == bytes.size()) return parse_binary(bytes, name);
  }
  std::size_t first = bytes.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && bytes.substr(first, 5) == "solid") return parse_ascii(bytes, name);
  if (bytes.size() < 84)
    throw IoError(name, fmt::format("{} bytes: too short for a binary STL (84-byte header) and no 'solid' "
                                    "keyword of an ASCII STL", bytes.size()));
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  throw IoError(name,
                fmt::format("binary STL header announces {} triangles ({} bytes) but the file has {} bytes", count,
                            84 + 50 * std::uint64_t(count), bytes.size()),
                {.line = std::nullopt, .byte_offset = 80});
}

void write_stl(std::ostream& out, const geometry::TriangleMesh& mesh, bool ascii) {
  auto normal = [&](const Tri& t) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    Vec3 n = (mesh.vertices[static_cast<std::size_t>(t[1])] - a).cross(mesh.vertices[static_cast<std::size_t>(t[2])] - a);
    const double len = n.norm();
    return len > 0.0 ? Vec3(n / len) : Vec3::Zero();
  };
  if (ascii) {
    out << "solid ido\n";
    for (const auto& t : mesh.triangles) {
      const Vec3 n = normal(t);
      out << fmt::format(" facet normal {:.9g} {:.9g} {:.9g}\n  outer loop\n", n.x(), n.y(), n.z());
      for (int c = 0; c < 3; ++c) {
        const Vec3& p = mesh.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(c)])];
        // STL holds single precision: 9 significant digits print a float exactly.
        out << fmt::format("   vertex {:.9g} {:.9g} {:.9g}\n", float(p.x()), float(p.y()), float(p.z()));
      }
      out << "  endloop\n endfacet\n";
    }
    out << "endsolid ido\n";
    return;
  }
  char header[80] = {};
  std::snprintf(header, sizeof header, "ido binary STL");
  out.write(header, 80);
  auto put_u32 = [&](std::uint32_t v) {
    unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                          static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 24)};
    out.write(reinterpret_cast<const char*>(b), 4);
  };
  auto put_f32 = [&](double d) {
    const float f = static_cast<float>(d);
    std::uint32_t bits;
    std::memcpy(&bits, &f, 4);
    put_u32(bits);
  };
  put_u32(static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const Vec3 n = normal(t);
    for (int a = 0; a < 3; ++a) put_f32(n[a]);
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) put_f32(mesh.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(c)])][a]);
    out.write("\0\0", 2);
  }
}

}  // namespace ido::io::detail

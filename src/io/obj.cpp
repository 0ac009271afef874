// SPDX-License-Identifier: Apache-2.0
// Wavefront OBJ (geometry subset): `v x y z [w]` and `f` with `v`, `v/vt`, `v//vn` or
// `v/vt/vn` corners, 1-based or negative (relative) indices; polygons are split into a fan.
// Texture coordinates, normals, groups, materials and lines are ignored.
#include <fmt/format.h>

#include "parsers.h"
#include "text_parser.h"

namespace ido::io::detail {

geometry::TriangleMesh parse_obj(std::string_view bytes, const std::string& name) {
  TextCursor in(bytes, name);
  in.set_comment_char('#');
  geometry::TriangleMesh mesh;
  std::vector<std::int64_t> vertex_lines, tri_lines;
  std::vector<std::int64_t> corners;
  while (!in.at_end()) {
    const auto key = in.next_on_line();
    if (key == "v") {
      Vec3 p;
      for (int a = 0; a < 3; ++a) {
        const auto t = in.next_on_line();
        if (t.empty()) in.fail("vertex has fewer than 3 coordinates");
        if (!to_double(t, p[a])) in.fail(fmt::format("expected a number for a vertex coordinate, found '{}'", t.substr(0, 40)));
      }
      mesh.vertices.push_back(p);
      vertex_lines.push_back(in.line());
    } else if (key == "f") {
      corners.clear();
      for (auto t = in.next_on_line(); !t.empty(); t = in.next_on_line()) {
        const auto vtok = t.substr(0, t.find('/'));
        std::int64_t v = 0;
        if (!to_int(vtok, v) || v == 0) in.fail(fmt::format("bad face corner '{}'", t.substr(0, 40)));
        const auto n = static_cast<std::int64_t>(mesh.vertices.size());
        const std::int64_t index = v > 0 ? v - 1 : n + v;
        if (index < 0 || index >= n)
          invalid(name, fmt::format("face refers to vertex {}, but only {} vertices are defined so far", v, n),
                  {.line = in.line(), .byte_offset = std::nullopt});
        corners.push_back(index);
      }
      if (corners.size() < 3) in.fail(fmt::format("face has {} corners, expected at least 3", corners.size()));
      for (std::size_t c = 1; c + 1 < corners.size(); ++c) {
        mesh.triangles.push_back({static_cast<std::int32_t>(corners[0]), static_cast<std::int32_t>(corners[c]),
                                  static_cast<std::int32_t>(corners[c + 1])});
        tri_lines.push_back(in.line());
      }
    } else if (!key.empty() && key != "vt" && key != "vn" && key != "vp" && key != "g" && key != "o" &&
               key != "s" && key != "l" && key != "p" && key != "usemtl" && key != "mtllib" && key != "cstype" &&
               key != "deg" && key != "curv" && key != "surf" && key != "parm" && key != "end") {
      in.fail(fmt::format("unknown OBJ statement '{}'", key.substr(0, 40)));
    }
    in.skip_line();
  }
  if (mesh.vertices.empty()) throw IoError(name, "no vertices ('v' lines) found");
  validate(mesh, name, vertex_lines, tri_lines);
  return mesh;
}

void write_obj(std::ostream& out, const geometry::TriangleMesh& mesh) {
  out << "# written by ido\n";
  // 17 significant digits: doubles survive the round trip exactly.
  for (const auto& p : mesh.vertices) out << fmt::format("v {:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
  for (const auto& t : mesh.triangles) out << fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
}

}  // namespace ido::io::detail

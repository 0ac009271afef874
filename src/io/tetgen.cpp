// SPDX-License-Identifier: Apache-2.0
// TetGen .node / .ele files (TetGen user manual, section 5.2): '#' comments, a header
// line, then one numbered line per point or tetrahedron; numbering starts at 0 or 1 (the
// first point's number decides, for both files). 10-node tetrahedra keep their corners.
#include <fmt/format.h>

#include "parsers.h"
#include "text_parser.h"

namespace ido::io::detail {

geometry::TetMesh parse_tetgen(std::string_view node_bytes, const std::string& node_name,
                               std::string_view ele_bytes, const std::string& ele_name) {
  geometry::TetMesh mesh;
  std::vector<std::int64_t> vertex_lines, tet_lines;
  TextCursor nodes(node_bytes, node_name);
  nodes.set_comment_char('#');
  const auto np = nodes.read_int("number of points");
  if (np < 0 || static_cast<std::uint64_t>(np) > node_bytes.size()) nodes.fail(fmt::format("point count {} is impossible", np));
  if (nodes.read_int("dimension") != 3) nodes.fail("dimension must be 3");
  const auto nattr = nodes.read_int("number of attributes");
  const auto nmark = nodes.read_int("number of boundary markers");
  if (nattr < 0 || nattr > 1000 || (nmark != 0 && nmark != 1)) nodes.fail("bad attribute or boundary-marker count");
  std::int64_t base = 0;
  mesh.vertices.reserve(static_cast<std::size_t>(np));
  for (std::int64_t i = 0; i < np; ++i) {
    if (nodes.at_end()) nodes.fail(fmt::format("file ends after {} of {} points (truncated?)", i, np));
    const auto idx = nodes.read_int("point number");
    if (i == 0) {
      if (idx != 0 && idx != 1) nodes.fail(fmt::format("first point is numbered {}, expected 0 or 1", idx));
      base = idx;
    } else if (idx != base + i) {
      nodes.fail(fmt::format("point numbered {}, expected {}", idx, base + i));
    }
    Vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = nodes.read_double("coordinate");
    if (!p.allFinite())
      invalid(node_name, fmt::format("point {} has a non-finite coordinate", idx), {.line = nodes.line(), .byte_offset = std::nullopt});
    for (std::int64_t k = 0; k < nattr + nmark; ++k) (void)nodes.read_double("attribute or marker");
    mesh.vertices.push_back(p);
    vertex_lines.push_back(nodes.line());
  }
  if (!nodes.at_end()) nodes.fail("more points than the header declares");

  TextCursor ele(ele_bytes, ele_name);
  ele.set_comment_char('#');
  const auto nt = ele.read_int("number of tetrahedra");
  if (nt < 0 || static_cast<std::uint64_t>(nt) > ele_bytes.size()) ele.fail(fmt::format("tetrahedron count {} is impossible", nt));
  const auto per = ele.read_int("nodes per tetrahedron");
  if (per != 4 && per != 10) ele.fail(fmt::format("{} nodes per tetrahedron; expected 4 or 10", per));
  const auto region = ele.read_int("region attribute flag");
  if (region < 0 || region > 1000) ele.fail("bad attribute count");
  for (std::int64_t i = 0; i < nt; ++i) {
    if (ele.at_end()) ele.fail(fmt::format("file ends after {} of {} tetrahedra (truncated?)", i, nt));
    const auto idx = ele.read_int("tetrahedron number");
    if (idx != base + i) ele.fail(fmt::format("tetrahedron numbered {}, expected {}", idx, base + i));
    Tet t{};
    for (std::int64_t c = 0; c < per; ++c) {
      const auto v = ele.read_int("node number") - base;
      if (v < 0 || v >= np)
        invalid(ele_name, fmt::format("tetrahedron {} refers to point {}, but {} has {} points", idx, v + base,
                                      node_name, np), {.line = ele.line(), .byte_offset = std::nullopt});
      if (c < 4) t[static_cast<std::size_t>(c)] = static_cast<std::int32_t>(v);
    }
    for (std::int64_t k = 0; k < region; ++k) (void)ele.read_double("region attribute");
    mesh.tets.push_back(t);
    tet_lines.push_back(ele.line());
  }
  if (!ele.at_end()) ele.fail("more tetrahedra than the header declares");
  validate(mesh, ele_name, vertex_lines, tet_lines);
  return mesh;
}

void write_tetgen_node(std::ostream& out, const geometry::TetMesh& mesh) {
  out << mesh.vertices.size() << " 3 0 0\n";
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& p = mesh.vertices[i];
    out << fmt::format("{} {:.17g} {:.17g} {:.17g}\n", i + 1, p.x(), p.y(), p.z());
  }
  out << "# written by ido\n";
}

void write_tetgen_ele(std::ostream& out, const geometry::TetMesh& mesh) {
  out << mesh.tets.size() << " 4 0\n";
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    const auto& t = mesh.tets[i];
    out << fmt::format("{} {} {} {} {}\n", i + 1, t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1);
  }
  out << "# written by ido\n";
}

}  // namespace ido::io::detail

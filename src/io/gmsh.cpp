// SPDX-License-Identifier: Apache-2.0
// Gmsh MSH ASCII, versions 2.2 and 4.1 (Gmsh reference manual, "MSH file format").
// Nodes and elements are read; tetrahedra (type 4) make a TetMesh, triangles (type 2) a
// TriangleMesh; every other element type is skipped. Other sections ($Entities,
// $PhysicalNames, $NodeData, ...) are skipped.
#include <unordered_map>

#include <fmt/format.h>

#include "ido/geometry/aabb.h"

#include "parsers.h"
#include "text_parser.h"

namespace ido::io::detail {
namespace {

struct GmshElement {
  int type = 0;
  std::vector<std::int64_t> nodes;  ///< node tags
  std::int64_t line = 0;
};

struct GmshFile {
  std::vector<Vec3> nodes;
  std::vector<std::int64_t> node_lines;
  std::unordered_map<std::int64_t, std::int32_t> index_of_tag;
  std::vector<GmshElement> elements;  ///< only the kept type
};

/// Reads tokens to the end of the line as integers.
void read_line_ints(TextCursor& in, std::vector<std::int64_t>& out) {
  out.clear();
  for (auto t = in.next_on_line(); !t.empty(); t = in.next_on_line()) {
    std::int64_t v;
    if (!to_int(t, v)) in.fail(fmt::format("expected an integer, found '{}'", t.substr(0, 40)));
    out.push_back(v);
  }
}

void add_node(GmshFile& f, TextCursor& in, std::int64_t tag, const Vec3& p) {
  if (!f.index_of_tag.emplace(tag, static_cast<std::int32_t>(f.nodes.size())).second)
    in.fail(fmt::format("node tag {} appears twice", tag));
  if (f.nodes.size() >= 0x7fffffff) in.fail("too many nodes");
  f.nodes.push_back(p);
  f.node_lines.push_back(in.line());
}

Vec3 read_xyz(TextCursor& in) {
  Vec3 p;
  for (int a = 0; a < 3; ++a) p[a] = in.read_double("node coordinate");
  return p;
}

std::int64_t read_count(TextCursor& in, std::string_view what, std::size_t file_size) {
  const std::int64_t n = in.read_int(what);
  if (n < 0 || static_cast<std::uint64_t>(n) > file_size) in.fail(fmt::format("{} {} is impossible for this file", what, n));
  return n;
}

void expect_end(TextCursor& in, std::string_view section) {
  const auto t = in.expect(fmt::format("$End{}", section));
  if (t != fmt::format("$End{}", section))
    in.fail(fmt::format("expected $End{}, found '{}' (counts disagree with the data?)", section, t.substr(0, 40)));
}

GmshFile parse(std::string_view bytes, const std::string& name, int keep_type) {
  TextCursor in(bytes, name);
  GmshFile f;
  int version = 0;
  std::vector<std::int64_t> ints;
  bool saw_nodes = false;
  while (!in.at_end()) {
    const auto section = in.next();
    if (section.empty() || section[0] != '$') in.fail(fmt::format("expected a $Section, found '{}'", section.substr(0, 40)));
    const std::string sec(section.substr(1));
    if (sec == "MeshFormat") {
      const auto v = in.expect("version");
      if (v == "2.2") version = 2;
      else if (v == "4.1") version = 4;
      else in.fail(fmt::format("MSH version {} is not supported (2.2 and 4.1 are)", v.substr(0, 20)));
      if (in.read_int("file type") != 0) in.fail("binary MSH is not supported; save as ASCII");
      (void)in.read_int("data size");
      expect_end(in, "MeshFormat");
    } else if (sec == "Nodes") {
      if (version == 0) in.fail("$Nodes before $MeshFormat");
      saw_nodes = true;
      if (version == 2) {
        const auto n = read_count(in, "node count", bytes.size());
        for (std::int64_t i = 0; i < n; ++i) {
          const auto tag = in.read_int("node tag");
          add_node(f, in, tag, read_xyz(in));
        }
      } else {
        const auto blocks = read_count(in, "entity block count", bytes.size());
        const auto total = read_count(in, "node count", bytes.size());
        (void)in.read_int("min node tag");
        (void)in.read_int("max node tag");
        std::vector<std::int64_t> tags;
        for (std::int64_t b = 0; b < blocks; ++b) {
          const auto dim = in.read_int("entity dimension");
          (void)in.read_int("entity tag");
          const auto parametric = in.read_int("parametric flag");
          const auto n = read_count(in, "nodes in block", bytes.size());
          if (dim < 0 || dim > 3 || (parametric != 0 && parametric != 1)) in.fail("bad node block header");
          tags.resize(static_cast<std::size_t>(n));
          for (auto& t : tags) t = in.read_int("node tag");
          for (std::int64_t i = 0; i < n; ++i) {
            add_node(f, in, tags[static_cast<std::size_t>(i)], read_xyz(in));
            for (std::int64_t u = 0; u < (parametric ? dim : 0); ++u) (void)in.read_double("parametric coordinate");
          }
        }
        if (static_cast<std::int64_t>(f.nodes.size()) != total)
          in.fail(fmt::format("$Nodes header says {} nodes, blocks hold {}", total, f.nodes.size()));
      }
      expect_end(in, "Nodes");
    } else if (sec == "Elements") {
      if (!saw_nodes) in.fail("$Elements before $Nodes");
      auto take = [&](int type, const std::int64_t* nodes, std::size_t count) {
        if (type != keep_type) return;
        GmshElement e;
        e.type = type;
        e.nodes.assign(nodes, nodes + count);
        e.line = in.line();
        f.elements.push_back(std::move(e));
      };
      const std::size_t need = keep_type == 4 ? 4 : 3;
      if (version == 2) {
        const auto n = read_count(in, "element count", bytes.size());
        in.skip_line();
        for (std::int64_t i = 0; i < n; ++i) {
          if (in.at_end()) in.fail(fmt::format("file ends after {} of {} elements", i, n));
          read_line_ints(in, ints);
          if (ints.size() < 3 || ints[2] < 0 || ints.size() < 3 + static_cast<std::size_t>(ints[2]))
            in.fail("element line too short");
          const std::size_t first = 3 + static_cast<std::size_t>(ints[2]);
          const int type = static_cast<int>(ints[1]);
          if (type == keep_type) {
            if (ints.size() - first != need)
              in.fail(fmt::format("element type {} needs {} nodes, line has {}", type, need, ints.size() - first));
            take(type, ints.data() + first, need);
          }
          in.skip_line();
        }
      } else {
        const auto blocks = read_count(in, "entity block count", bytes.size());
        const auto total = read_count(in, "element count", bytes.size());
        (void)in.read_int("min element tag");
        (void)in.read_int("max element tag");
        std::int64_t seen = 0;
        for (std::int64_t b = 0; b < blocks; ++b) {
          (void)in.read_int("entity dimension");
          (void)in.read_int("entity tag");
          const int type = static_cast<int>(in.read_int("element type"));
          const auto n = read_count(in, "elements in block", bytes.size());
          in.skip_line();
          for (std::int64_t i = 0; i < n; ++i) {
            if (in.at_end()) in.fail(fmt::format("file ends inside an element block ({} of {} elements)", i, n));
            read_line_ints(in, ints);
            if (type == keep_type) {
              if (ints.size() != need + 1)
                in.fail(fmt::format("element type {} needs {} nodes, line has {}", type, need,
                                    ints.empty() ? 0 : ints.size() - 1));
              take(type, ints.data() + 1, need);
            }
            in.skip_line();
          }
          seen += n;
        }
        if (seen != total) in.fail(fmt::format("$Elements header says {} elements, blocks hold {}", total, seen));
      }
      expect_end(in, "Elements");
    } else {
      // Unknown or unused section: skip to its end marker.
      const std::string end = "$End" + sec;
      while (true) {
        const auto t = in.next();
        if (t.empty()) in.fail(fmt::format("section ${} is not closed by {}", sec, end));
        if (t == end) break;
      }
    }
  }
  if (version == 0) throw IoError(name, "no $MeshFormat section (not a Gmsh file?)", {.line = 1, .byte_offset = std::nullopt});
  if (!saw_nodes) throw IoError(name, "no $Nodes section");
  return f;
}

std::int32_t node_index(const GmshFile& f, const GmshElement& e, std::int64_t tag, const std::string& name) {
  const auto it = f.index_of_tag.find(tag);
  if (it == f.index_of_tag.end())
    invalid(name, fmt::format("element refers to node tag {}, which $Nodes does not define", tag),
            {.line = e.line, .byte_offset = std::nullopt});
  return it->second;
}

}  // namespace

geometry::TetMesh parse_gmsh_tets(std::string_view bytes, const std::string& name) {
  GmshFile f = parse(bytes, name, 4);
  geometry::TetMesh mesh;
  mesh.vertices = std::move(f.nodes);
  std::vector<std::int64_t> lines;
  for (const auto& e : f.elements) {
    mesh.tets.push_back({node_index(f, e, e.nodes[0], name), node_index(f, e, e.nodes[1], name),
                         node_index(f, e, e.nodes[2], name), node_index(f, e, e.nodes[3], name)});
    lines.push_back(e.line);
  }
  validate(mesh, name, f.node_lines, lines);
  return mesh;
}

geometry::TriangleMesh parse_gmsh_triangles(std::string_view bytes, const std::string& name) {
  GmshFile f = parse(bytes, name, 2);
  // Keep only the nodes the triangles use (a volume mesh file also holds interior nodes),
  // in their file order.
  geometry::TriangleMesh mesh;
  std::vector<std::int32_t> remap(f.nodes.size(), -1);
  std::vector<std::int64_t> lines, vertex_lines;
  std::vector<Tri> raw;
  for (const auto& e : f.elements) {
    Tri t{};
    for (std::size_t c = 0; c < 3; ++c) {
      t[c] = node_index(f, e, e.nodes[c], name);
      remap[static_cast<std::size_t>(t[c])] = 0;
    }
    raw.push_back(t);
    lines.push_back(e.line);
  }
  for (std::size_t i = 0; i < f.nodes.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<std::int32_t>(mesh.vertices.size());
      mesh.vertices.push_back(f.nodes[i]);
      vertex_lines.push_back(f.node_lines[i]);
    }
  for (auto t : raw) {
    for (auto& v : t) v = remap[static_cast<std::size_t>(v)];
    mesh.triangles.push_back(t);
  }
  validate(mesh, name, vertex_lines, lines);
  return mesh;
}

namespace {
template <std::size_t N>
void write_msh(std::ostream& out, const std::vector<Vec3>& vertices, const std::vector<std::array<std::int32_t, N>>& elements,
               bool version2) {
  const int type = N == 4 ? 4 : 2;
  const int dim = N == 4 ? 3 : 2;
  const std::size_t nv = vertices.size(), ne = elements.size();
  if (version2) {
    out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << nv << "\n";
    for (std::size_t i = 0; i < nv; ++i)
      out << fmt::format("{} {:.17g} {:.17g} {:.17g}\n", i + 1, vertices[i].x(), vertices[i].y(), vertices[i].z());
    out << "$EndNodes\n$Elements\n" << ne << "\n";
    for (std::size_t e = 0; e < ne; ++e) {
      out << e + 1 << " " << type << " 2 0 1";
      for (const auto v : elements[e]) out << " " << v + 1;
      out << "\n";
    }
    out << "$EndElements\n";
    return;
  }
  const geometry::Aabb box = nv ? geometry::Aabb::of(vertices) : geometry::Aabb{Vec3::Zero(), Vec3::Zero()};
  const Vec3 &lo = box.min, &hi = box.max;
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n";
  out << (dim == 2 ? "0 0 1 0\n" : "0 0 0 1\n");
  out << fmt::format("1 {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} 0 0\n", lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  out << "$EndEntities\n$Nodes\n";
  out << (nv ? 1 : 0) << " " << nv << " " << (nv ? 1 : 0) << " " << nv << "\n";
  if (nv) {
    out << dim << " 1 0 " << nv << "\n";
    for (std::size_t i = 0; i < nv; ++i) out << i + 1 << "\n";
    for (const auto& p : vertices) out << fmt::format("{:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
  }
  out << "$EndNodes\n$Elements\n";
  out << (ne ? 1 : 0) << " " << ne << " " << (ne ? 1 : 0) << " " << ne << "\n";
  if (ne) {
    out << dim << " 1 " << type << " " << ne << "\n";
    for (std::size_t e = 0; e < ne; ++e) {
      out << e + 1;
      for (const auto v : elements[e]) out << " " << v + 1;
      out << "\n";
    }
  }
  out << "$EndElements\n";
}
}  // namespace

void write_gmsh(std::ostream& out, const geometry::TetMesh& mesh, bool version2) {
  write_msh(out, mesh.vertices, mesh.tets, version2);
}
void write_gmsh_triangles(std::ostream& out, const geometry::TriangleMesh& mesh, bool version2) {
  write_msh(out, mesh.vertices, mesh.triangles, version2);
}

}  // namespace ido::io::detail

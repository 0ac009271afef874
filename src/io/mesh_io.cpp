// SPDX-License-Identifier: Apache-2.0
// Mesh files: dispatch by extension, whole-file reads, atomic writes, and the checks every
// parsed mesh goes through.
#include "ido/io/mesh_io.h"

#include <cmath>

#include <fmt/format.h>

#include "ido/core/atomic_file.h"
#include "parsers.h"
#include "text_parser.h"

namespace ido::io {
namespace fs = std::filesystem;
using namespace detail;

namespace detail {
namespace {
std::optional<std::int64_t> line_of(const std::vector<std::int64_t>& lines, std::size_t i) {
  if (i < lines.size()) return lines[i];
  return std::nullopt;
}

void check_vertices(const std::vector<Vec3>& vertices, const std::string& name,
                    const std::vector<std::int64_t>& vertex_lines) {
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (!vertices[i].allFinite())
      invalid(name, fmt::format("vertex {} has a non-finite coordinate ({}, {}, {})", i, vertices[i].x(),
                                vertices[i].y(), vertices[i].z()),
              {.line = line_of(vertex_lines, i), .byte_offset = std::nullopt});
}

template <std::size_t N>
void check_indices(const std::vector<std::array<std::int32_t, N>>& elements, std::size_t vertex_count,
                   const std::string& name, const char* what,
                   const std::vector<std::int64_t>& element_lines) {
  for (std::size_t e = 0; e < elements.size(); ++e)
    for (const auto v : elements[e])
      if (v < 0 || static_cast<std::size_t>(v) >= vertex_count)
        invalid(name, fmt::format("{} {} refers to vertex {}, but there are {} vertices", what, e, v, vertex_count),
                {.line = line_of(element_lines, e), .byte_offset = std::nullopt});
}

void check_fields(const geometry::FieldMap& fields, std::size_t count, const std::string& name, const char* kind) {
  for (const auto& [field_name, f] : fields)
    if (f.components < 1 || f.values.size() != count * static_cast<std::size_t>(f.components))
      invalid(name, fmt::format("{} field '{}' has {} values, expected {} × {}", kind, field_name,
                                f.values.size(), count, f.components));
}
}  // namespace

void validate(const geometry::TriangleMesh& mesh, const std::string& name,
              const std::vector<std::int64_t>& vertex_lines, const std::vector<std::int64_t>& element_lines) {
  check_vertices(mesh.vertices, name, vertex_lines);
  check_indices(mesh.triangles, mesh.vertices.size(), name, "triangle", element_lines);
  check_fields(mesh.point_fields, mesh.vertices.size(), name, "point");
  check_fields(mesh.cell_fields, mesh.triangles.size(), name, "cell");
}

void validate(const geometry::TetMesh& mesh, const std::string& name,
              const std::vector<std::int64_t>& vertex_lines, const std::vector<std::int64_t>& element_lines) {
  check_vertices(mesh.vertices, name, vertex_lines);
  check_indices(mesh.tets, mesh.vertices.size(), name, "tetrahedron", element_lines);
  check_fields(mesh.point_fields, mesh.vertices.size(), name, "point");
  check_fields(mesh.cell_fields, mesh.tets.size(), name, "cell");
  // Inverted or degenerate tetrahedra are read as they are: a simulation frame may hold them,
  // and geometry::check_tet_mesh (`ido info`) counts them. Users that need positive volumes
  // (sim::World, the drill's hierarchy) check their own input.
}
}  // namespace detail

namespace {
/// Writers check structure only (indices, field sizes): a simulation may legitimately write
/// inverted elements or non-finite positions for inspection.
template <class Mesh, std::size_t N>
void check_for_write(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                     const std::string& name) {
  for (std::size_t e = 0; e < elements.size(); ++e)
    for (const auto v : elements[e])
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.vertices.size())
        throw InvalidInput(fmt::format("{}: element {} refers to vertex {}, but the mesh has {} vertices", name, e,
                                       v, mesh.vertices.size()));
  for (const auto* fields : {&mesh.point_fields, &mesh.cell_fields}) {
    const std::size_t count = fields == &mesh.point_fields ? mesh.vertices.size() : elements.size();
    for (const auto& [field_name, f] : *fields)
      if (f.components < 1 || f.values.size() != count * static_cast<std::size_t>(f.components))
        throw InvalidInput(fmt::format("{}: field '{}' has {} values, expected {} × {}", name, field_name,
                                       f.values.size(), count, f.components));
  }
}

std::string ext_of(const fs::path& path) { return lower_extension(path.filename().string()); }

/// The .node/.ele pair for a TetGen path given by either name.
std::pair<fs::path, fs::path> tetgen_pair(const fs::path& path) {
  fs::path node = path, ele = path;
  node.replace_extension(".node");
  ele.replace_extension(".ele");
  return {node, ele};
}
}  // namespace

bool is_tet_mesh_path(const fs::path& path) {
  const auto e = ext_of(path);
  return e == ".vtu" || e == ".msh" || e == ".node" || e == ".ele";
}

bool is_triangle_mesh_path(const fs::path& path) {
  const auto e = ext_of(path);
  return e == ".stl" || e == ".obj" || e == ".ply" || e == ".vtp";
}

geometry::TriangleMesh read_triangle_mesh(const fs::path& path) {
  const auto e = ext_of(path);
  const std::string name = path.string();
  if (!is_triangle_mesh_path(path) && e != ".msh")
    throw IoError(name, "unknown triangle mesh extension (expected .stl, .obj, .ply, .vtp or .msh)");
  const std::string bytes = read_file_bytes(path);
  if (e == ".stl") return parse_stl(bytes, name);
  if (e == ".obj") return parse_obj(bytes, name);
  if (e == ".ply") return parse_ply(bytes, name);
  if (e == ".vtp") return parse_vtp(bytes, name);
  return parse_gmsh_triangles(bytes, name);
}

void write_triangle_mesh(const fs::path& path, const geometry::TriangleMesh& mesh, const MeshWriteOptions& options) {
  const auto e = ext_of(path);
  check_for_write(mesh, mesh.triangles, path.string());
  if (e == ".stl") return write_file_atomically(path, [&](std::ostream& o) { write_stl(o, mesh, options.ascii); });
  if (e == ".obj") return write_file_atomically(path, [&](std::ostream& o) { write_obj(o, mesh); });
  if (e == ".ply")
    return write_file_atomically(path, [&](std::ostream& o) { write_ply(o, mesh, options.ascii, options.big_endian); });
  if (e == ".vtp") return write_file_atomically(path, [&](std::ostream& o) { write_vtp(o, mesh, options.ascii); });
  if (e == ".msh")
    return write_file_atomically(path, [&](std::ostream& o) { write_gmsh_triangles(o, mesh, options.gmsh_v2); });
  throw IoError(path.string(), "cannot write a triangle mesh with this extension (use .stl, .obj, .ply, .vtp or .msh)");
}

geometry::TetMesh read_tet_mesh(const fs::path& path) {
  const auto e = ext_of(path);
  const std::string name = path.string();
  if (e == ".vtu") return parse_vtu(read_file_bytes(path), name);
  if (e == ".msh") return parse_gmsh_tets(read_file_bytes(path), name);
  if (e == ".node" || e == ".ele") {
    const auto [node, ele] = tetgen_pair(path);
    const std::string node_bytes = read_file_bytes(node);  // node first: errors name it first
    const std::string ele_bytes = read_file_bytes(ele);
    return parse_tetgen(node_bytes, node.string(), ele_bytes, ele.string());
  }
  throw IoError(name, "unknown tetrahedral mesh extension (expected .vtu, .msh, .node or .ele)");
}

void write_tet_mesh(const fs::path& path, const geometry::TetMesh& mesh, const MeshWriteOptions& options) {
  const auto e = ext_of(path);
  check_for_write(mesh, mesh.tets, path.string());
  if (e == ".vtu") return write_file_atomically(path, [&](std::ostream& o) { write_vtu(o, mesh, options.ascii); });
  if (e == ".msh") return write_file_atomically(path, [&](std::ostream& o) { write_gmsh(o, mesh, options.gmsh_v2); });
  if (e == ".node" || e == ".ele") {
    const auto [node, ele] = tetgen_pair(path);
    // Two files: each is atomic; the .ele (which refers to the nodes) is written last.
    write_file_atomically(node, [&](std::ostream& o) { write_tetgen_node(o, mesh); }, false);
    write_file_atomically(ele, [&](std::ostream& o) { write_tetgen_ele(o, mesh); }, false);
    return;
  }
  throw IoError(path.string(), "cannot write a tetrahedral mesh with this extension (use .vtu, .msh, .node or .ele)");
}

}  // namespace ido::io

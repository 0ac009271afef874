// SPDX-License-Identifier: Apache-2.0
// Private to ido::io (and the fuzz targets): every mesh parser works on the bytes of a
// whole file held in memory, so the fuzzers can drive them without touching the disk.
// @p name is the path shown in error messages.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/io/pvd.h"

namespace ido::io::detail {

/// The whole file as bytes. @throws IoError if missing, a folder, unreadable or empty.
std::string read_file_bytes(const std::filesystem::path& path);

geometry::TriangleMesh parse_stl(std::string_view bytes, const std::string& name);
geometry::TriangleMesh parse_obj(std::string_view bytes, const std::string& name);
geometry::TriangleMesh parse_ply(std::string_view bytes, const std::string& name);
geometry::TriangleMesh parse_vtp(std::string_view bytes, const std::string& name);
geometry::TetMesh parse_vtu(std::string_view bytes, const std::string& name);
geometry::TetMesh parse_gmsh_tets(std::string_view bytes, const std::string& name);
geometry::TriangleMesh parse_gmsh_triangles(std::string_view bytes, const std::string& name);
/// TetGen: the .node text and the .ele text (named separately in errors).
geometry::TetMesh parse_tetgen(std::string_view node_bytes, const std::string& node_name,
                               std::string_view ele_bytes, const std::string& ele_name);
std::vector<PvdEntry> parse_pvd(std::string_view bytes, const std::string& name);

void write_stl(std::ostream& out, const geometry::TriangleMesh& mesh, bool ascii);
void write_obj(std::ostream& out, const geometry::TriangleMesh& mesh);
void write_ply(std::ostream& out, const geometry::TriangleMesh& mesh, bool ascii, bool big_endian);
void write_vtp(std::ostream& out, const geometry::TriangleMesh& mesh, bool ascii);
void write_vtu(std::ostream& out, const geometry::TetMesh& mesh, bool ascii);

/// A named field of a streamed mesh: @p components values per entity.
struct StreamedField {
  std::string name;
  int components = 1;
};

/// A tetrahedral mesh handed to the writer piece by piece instead of held: its counts, and
/// generators that call the sink they are given once per value, in file order (so a large mesh
/// can be written from a structure that only walks it, e.g. a drilling hierarchy).
struct StreamedTetMesh {
  std::size_t vertex_count = 0;
  std::size_t tet_count = 0;
  std::vector<StreamedField> point_fields;  ///< written in this order
  std::vector<StreamedField> cell_fields;   ///< written in this order
  /// Calls its argument with every vertex position (mm), in index order.
  std::function<void(const std::function<void(const Vec3&)>&)> vertices;
  /// Calls its argument with every tetrahedron's vertex indices, in order.
  std::function<void(const std::function<void(const Tet&)>&)> tets;
  /// point_values(k, put) / cell_values(k, put): puts every value of field k, entity-major.
  std::function<void(std::size_t, const std::function<void(double)>&)> point_values;
  std::function<void(std::size_t, const std::function<void(double)>&)> cell_values;
};
/// Writes @p mesh as write_vtu(TetMesh) writes the same mesh (byte for byte, fields in the
/// given order). @throws ido::Error if a generator gives another count than declared.
void write_vtu(std::ostream& out, const StreamedTetMesh& mesh, bool ascii);

/// A triangle mesh handed to the writer piece by piece, as StreamedTetMesh.
struct StreamedTriangleMesh {
  std::size_t vertex_count = 0;
  std::size_t triangle_count = 0;
  std::vector<StreamedField> point_fields;  ///< written in this order
  std::vector<StreamedField> cell_fields;   ///< written in this order
  /// Calls its argument with every vertex position (mm), in index order.
  std::function<void(const std::function<void(const Vec3&)>&)> vertices;
  /// Calls its argument with every triangle's vertex indices, in order.
  std::function<void(const std::function<void(const Tri&)>&)> triangles;
  /// point_values(k, put) / cell_values(k, put): puts every value of field k, entity-major.
  std::function<void(std::size_t, const std::function<void(double)>&)> point_values;
  std::function<void(std::size_t, const std::function<void(double)>&)> cell_values;
};
/// Writes @p mesh as write_vtp(TriangleMesh) writes the same mesh (byte for byte, fields in
/// the given order). @throws ido::Error if a generator gives another count than declared.
void write_vtp(std::ostream& out, const StreamedTriangleMesh& mesh, bool ascii);
void write_gmsh(std::ostream& out, const geometry::TetMesh& mesh, bool version2);
void write_gmsh_triangles(std::ostream& out, const geometry::TriangleMesh& mesh, bool version2);
void write_tetgen_node(std::ostream& out, const geometry::TetMesh& mesh);
void write_tetgen_ele(std::ostream& out, const geometry::TetMesh& mesh);

/// Checks a parsed mesh: finite coordinates, indices in range, field sizes. Inverted or
/// degenerate tetrahedra are accepted (geometry::check_tet_mesh reports them). @p element_lines (optional) gives each element's 1-based line
/// for the message. @throws ido::InvalidInput naming @p name, the element and the problem.
void validate(const geometry::TriangleMesh& mesh, const std::string& name,
              const std::vector<std::int64_t>& vertex_lines = {},
              const std::vector<std::int64_t>& element_lines = {});
void validate(const geometry::TetMesh& mesh, const std::string& name,
              const std::vector<std::int64_t>& vertex_lines = {},
              const std::vector<std::int64_t>& element_lines = {});

}  // namespace ido::io::detail

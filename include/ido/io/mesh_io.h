// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>

#include "ido/geometry/tet_mesh.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::io {

/// Mesh file formats ido reads and writes.
enum class MeshFormat { Stl, StlAscii, Obj, Ply, PlyAscii, PlyBigEndian, Vtp, Vtu, Gmsh22, Gmsh41, TetGen };

/// Options for writers whose format has variants.
struct MeshWriteOptions {
  bool ascii = false;        ///< STL / PLY / VTK XML (.vtp, .vtu): ASCII instead of binary
  bool big_endian = false;   ///< binary PLY only
  bool gmsh_v2 = false;      ///< .msh: write version 2.2 instead of 4.1
};

/// Reads a triangle mesh; format by extension: .stl (ASCII or binary), .obj, .ply (ASCII,
/// binary little or big endian), .vtp. Point and cell data are read into fields where the
/// format has them. @throws ido::IoError naming the file, the line or byte offset, and the
/// problem; ido::InvalidInput for content that parses but is invalid (indices out of
/// range, non-finite coordinates).
[[nodiscard]] geometry::TriangleMesh read_triangle_mesh(const std::filesystem::path& path);

/// Writes a triangle mesh (format by extension, as above), atomically.
void write_triangle_mesh(const std::filesystem::path& path, const geometry::TriangleMesh& mesh,
                         const MeshWriteOptions& options = {});

/// Reads a tetrahedral mesh: .vtu (with point and cell data), .msh (Gmsh 2.2 or 4.1,
/// ASCII), .node/.ele (TetGen; either name may be given). Inverted or degenerate tetrahedra
/// are read as they are (a simulation frame may hold them; geometry::check_tet_mesh counts
/// them); non-finite coordinates and indices out of range are rejected with
/// ido::InvalidInput naming the element.
[[nodiscard]] geometry::TetMesh read_tet_mesh(const std::filesystem::path& path);

/// Writes a tetrahedral mesh (.vtu, .msh, .node/.ele), atomically.
void write_tet_mesh(const std::filesystem::path& path, const geometry::TetMesh& mesh,
                    const MeshWriteOptions& options = {});

/// True when the extension names a tetrahedral format (.vtu, .msh, .node, .ele).
[[nodiscard]] bool is_tet_mesh_path(const std::filesystem::path& path);
/// True when the extension names a triangle format (.stl, .obj, .ply, .vtp).
[[nodiscard]] bool is_triangle_mesh_path(const std::filesystem::path& path);

}  // namespace ido::io

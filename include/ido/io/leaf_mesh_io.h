// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <filesystem>

#include "ido/drill/assembled_surface.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/io/mesh_io.h"

namespace ido::io {

/// What write_leaf_mesh() wrote and held.
struct LeafMeshWriteStats {
  std::size_t tets = 0;          ///< tetrahedra written (full leaves)
  std::size_t vertices = 0;      ///< welded vertices written
  std::size_t memory_bytes = 0;  ///< bytes held for the mesh while it was written (approximate)
};

/// Writes the remaining material of @p hierarchy as a tetrahedral mesh file (format by
/// extension, as write_tet_mesh), atomically: the same bytes as
/// write_tet_mesh(path, drill::full_leaf_mesh(hierarchy), options). A .vtu is streamed from
/// the hierarchy (drill::LeafMeshWalk), without the mesh: it holds the numbers of the points
/// on the roots' faces and one root's inner points, and walks the tree once per array; .msh and
/// .node/.ele build the mesh first. @throws ido::IoError as write_tet_mesh.
LeafMeshWriteStats write_leaf_mesh(const std::filesystem::path& path, const drill::TetHierarchy& hierarchy,
                                   const MeshWriteOptions& options = {});

/// Writes the drilled boundary surface @p surface as a triangle mesh file (format by
/// extension, as write_triangle_mesh), atomically: the same bytes as
/// write_triangle_mesh(path, surface.to_mesh(), options). A .vtp is streamed from @p surface
/// (positions computed from its point keys as they are written), without the mesh; .stl, .obj,
/// .ply and .msh build the mesh first. @throws ido::IoError as write_triangle_mesh.
void write_drilled_surface(const std::filesystem::path& path, const drill::AssembledSurface& surface,
                           const MeshWriteOptions& options = {});

}  // namespace ido::io

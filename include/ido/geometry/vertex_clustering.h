// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>

#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Decimates @p mesh by vertex clustering (Rossignac & Borrel 1993): space is cut into cubes
/// of edge @p cell_mm starting at the mesh's bounding-box minimum; the vertices in one cube
/// become one vertex at their mean (inside that cube, so within √3 · cell_mm of each of them);
/// a triangle whose corners fall in three different cubes is kept with its corners' order
/// (so its orientation), one falling in fewer is dropped, as are repeats (the same three
/// cubes in the same cyclic order) and triangles of area below 10⁻⁹ · cell_mm². Vertices no
/// kept triangle uses are removed. The result has at most as many vertices as occupied
/// cubes and no degenerate triangle; it may be non-manifold where the surface is thinner
/// than a cube. Fields are not carried over. Runs in O(n log n) for n vertices.
///
/// It lives in geometry, not in the viewer, because it is plain triangle-mesh processing
/// (the window uses it for a coarse copy to draw while the camera moves, but any consumer of
/// a triangle mesh may want a cheap preview or proxy). Written here rather than taken from a
/// package: the clustering is short, and a library for it (meshoptimizer, VTK, CGAL) would
/// be a new dependency for one call.
/// @throws ido::InvalidInput if cell_mm is not positive and finite, or the grid over the
/// bounding box would have more than 2⁶² cells.
[[nodiscard]] TriangleMesh cluster_vertices(const TriangleMesh& mesh, double cell_mm);

/// cluster_vertices() with the smallest cell size it tries that leaves at most
/// @p max_triangles triangles: the first try is the cell whose count of a surface of the
/// mesh's area would be about the budget (3 · area / cell² triangles), then the cell grows by
/// 20 % a try. @p mesh itself (a copy) when it already has at most @p max_triangles.
/// @throws ido::InvalidInput if max_triangles is 0.
[[nodiscard]] TriangleMesh cluster_vertices_to(const TriangleMesh& mesh, std::size_t max_triangles);

}  // namespace ido::geometry

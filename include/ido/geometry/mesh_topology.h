// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// One undirected edge of a triangle mesh and how the triangles use it.
struct EdgeInfo {
  Edge vertices{};                     ///< the two vertex indices, vertices[0] < vertices[1]
  std::int32_t triangle_count = 0;     ///< number of triangles having this edge
  std::int32_t forward = 0;            ///< of those, how many traverse it vertices[0] → vertices[1]
  std::int32_t backward = 0;           ///< … and how many traverse it vertices[1] → vertices[0]
  std::array<std::int32_t, 2> triangles{-1, -1};  ///< the first two incident triangles (−1: none)
};

/// All unique edges of a mesh with their incidence, and for each triangle the ids of its
/// three edges: triangle_edges[t][k] is the edge (t[k], t[(k+1) % 3]).
struct EdgeMap {
  std::vector<EdgeInfo> edges;                            ///< sorted by (vertices[0], vertices[1])
  std::vector<std::array<std::int32_t, 3>> triangle_edges;  ///< one entry per triangle
};

/// Throws ido::InvalidInput naming the triangle when an index is negative or not below
/// vertex_count, or when a coordinate is not finite.
void validate_mesh(const TriangleMesh& mesh);

/// Builds the edge map of @p mesh in O(T log T). Edges of a triangle with a repeated index
/// (e.g. (3, 3, 5)) are included as they appear; a self-edge (v, v) is listed too.
/// @throws ido::InvalidInput for an index out of range.
[[nodiscard]] EdgeMap build_edge_map(const TriangleMesh& mesh);

/// The unique undirected edges of @p mesh, each as (smaller index, larger index), sorted.
/// @throws ido::InvalidInput for an index out of range.
[[nodiscard]] std::vector<Edge> unique_edges(const TriangleMesh& mesh);

/// For each vertex, the ids of the triangles that use it (ascending; a triangle appears once
/// per vertex even if the index repeats). @throws ido::InvalidInput for an index out of range.
[[nodiscard]] std::vector<std::vector<std::int32_t>> vertex_triangles(const TriangleMesh& mesh);

/// For each triangle, the id of its connected component, where triangles sharing a vertex
/// are connected. Components are numbered 0.. in order of their smallest triangle id.
[[nodiscard]] std::vector<std::int32_t> triangle_components(const TriangleMesh& mesh);

/// Number of connected components of the triangles (triangles sharing a vertex are connected;
/// unused vertices do not count). 0 for a mesh without triangles.
[[nodiscard]] int connected_components(const TriangleMesh& mesh);

/// Merges vertices closer than @p tol_mm (each vertex joins the cluster of any vertex within
/// the distance, transitively), keeps the first vertex of each cluster (and its point field
/// values), drops triangles that lose a corner to the merge (two equal indices) together with
/// their cell field values, and removes vertices no triangle uses. tol_mm = 0 merges exactly
/// equal positions only. @throws ido::InvalidInput if tol_mm is negative or not finite, or
/// for an index out of range.
[[nodiscard]] TriangleMesh weld_vertices(const TriangleMesh& mesh, double tol_mm);

/// Removes, in place, the vertices that no triangle uses, renumbering triangles and
/// compacting point fields. @throws ido::InvalidInput for an index out of range.
void remove_unused_vertices(TriangleMesh& mesh);

/// By-value variant of remove_unused_vertices.
[[nodiscard]] TriangleMesh without_unused_vertices(TriangleMesh mesh);

}  // namespace ido::geometry

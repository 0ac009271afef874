// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Tunables of the self-intersection search.
struct SelfIntersectionOptions {
  /// Run on several threads (oneTBB): one block of triangle indices per worker, then each
  /// block against the earlier ones.
  bool threaded = true;
};

/// Exact test of two triangles of @p mesh (by id): whether they intersect other than
/// through the vertices or edge they legitimately share by index. Triangles sharing no
/// vertex index intersect when they share any point; triangles sharing an edge intersect
/// when they overlap beyond it (coplanar fold); triangles sharing one vertex intersect when
/// they meet anywhere else; two triangles with the same three vertex indices always
/// intersect. Vertices at the same position but with different indices are NOT shared.
/// Preconditions: valid ids and indices (not checked here).
[[nodiscard]] bool mesh_triangles_intersect(const TriangleMesh& mesh, std::int32_t t1,
                                            std::int32_t t2);

/// All pairs (i, j), i < j, of triangles of @p mesh for which mesh_triangles_intersect is
/// true, sorted. Broad phase: a uniform grid (cells about twice the mean triangle size) whose
/// cell lists are filled in one incremental pass, each triangle meeting the earlier ones in
/// the cells of its box (on a spatially sorted copy when consecutive triangles are not
/// neighbours in space; a TriangleBvh when no sensible grid exists, e.g. very uneven
/// triangle sizes). Narrow phase: exact predicates behind a floating-point filter that only
/// answers when its error bound certifies the signs. The result does not depend on
/// threading. O(T) for surfaces with triangles of similar size.
/// @throws ido::InvalidInput for an index out of range or a non-finite coordinate.
[[nodiscard]] std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections(
    const TriangleMesh& mesh, const SelfIntersectionOptions& options = {});

/// The pairs of self_intersections(mesh) in which at least one triangle is flagged in
/// @p changed (one flag per triangle), found without testing two unflagged triangles against
/// each other: for a surface that moved in places since a search that found nothing (the
/// balloon's sleeping vertices), flag the triangles with a moved or re-connected corner and
/// the result equals the whole search. Every triangle is boxed into the grid; only the
/// flagged ones look for neighbours. Sorted, each pair (i, j) with i < j once.
/// @throws ido::InvalidInput as self_intersections, or when @p changed has the wrong size.
[[nodiscard]] std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections_touching(
    const TriangleMesh& mesh, const std::vector<std::uint8_t>& changed, const SelfIntersectionOptions& options = {});

/// True when self_intersections(mesh) would not be empty; the search stops at the first
/// intersecting pair it meets, having boxed only the triangles before it (single-threaded)
/// or within each thread's block of triangles.
[[nodiscard]] bool has_self_intersections(const TriangleMesh& mesh,
                                          const SelfIntersectionOptions& options = {});

}  // namespace ido::geometry

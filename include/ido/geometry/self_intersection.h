// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Tunables of the self-intersection search.
struct SelfIntersectionOptions {
  bool threaded = true;  ///< run the broad and narrow phases on several threads (oneTBB)
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
/// true, sorted. Broad phase: pair traversal of a TriangleBvh over closed triangle boxes;
/// narrow phase: exact predicates. The result does not depend on threading.
/// @throws ido::InvalidInput for an index out of range or a non-finite coordinate.
[[nodiscard]] std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections(
    const TriangleMesh& mesh, const SelfIntersectionOptions& options = {});

/// True when self_intersections(mesh) would not be empty; the search stops soon after the
/// first intersecting pair.
[[nodiscard]] bool has_self_intersections(const TriangleMesh& mesh,
                                          const SelfIntersectionOptions& options = {});

}  // namespace ido::geometry

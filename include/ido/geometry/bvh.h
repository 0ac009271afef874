// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Result of a closest-point query.
struct ClosestPoint {
  double distance_mm = std::numeric_limits<double>::infinity();  ///< distance to the surface
  Vec3 point = Vec3::Zero();   ///< the closest surface point (mm)
  std::int32_t triangle = -1;  ///< its triangle id, −1 when nothing was found
};

/// A bounding-volume hierarchy (axis-aligned boxes; triangles ordered along a Morton curve of
/// their centroids and halved recursively) over the triangles of a
/// mesh. It copies the triangle corners it needs, so it does not borrow the mesh: the mesh
/// may change or die afterwards (the BVH then describes the mesh as it was at
/// construction). Queries are const and may run concurrently from several threads.
class TriangleBvh {
 public:
  /// Builds over every triangle of @p mesh in O(T log T).
  /// @throws ido::InvalidInput for an index out of range or a non-finite coordinate.
  explicit TriangleBvh(const TriangleMesh& mesh, int leaf_size = 4);

  /// Number of triangles.
  [[nodiscard]] std::size_t size() const { return m_triangle_id.size(); }
  /// Box of all triangles (empty box for an empty mesh).
  [[nodiscard]] Aabb bounds() const;

  /// The point of the surface closest to @p p. Triangle −1 and infinite distance for an
  /// empty mesh. Ties are broken by traversal order.
  [[nodiscard]] ClosestPoint closest_point(const Vec3& p) const;
  /// As closest_point(p) but only within @p max_distance_mm; beyond it, triangle −1.
  [[nodiscard]] ClosestPoint closest_point(const Vec3& p, double max_distance_mm) const;

  /// Ids of the triangles whose (closed) bounding boxes overlap @p box, ascending.
  [[nodiscard]] std::vector<std::int32_t> overlapping(const Aabb& box) const;

  /// Calls @p accept(i, j) (i < j, triangle ids) for every pair of distinct triangles whose
  /// closed bounding boxes overlap, and returns the pairs for which it returned true, sorted.
  /// With @p threaded, accept is called concurrently from several threads (it must be
  /// thread-safe); the result does not depend on threading.
  [[nodiscard]] std::vector<std::pair<std::int32_t, std::int32_t>> self_pairs(
      const std::function<bool(std::int32_t, std::int32_t)>& accept, bool threaded = true) const;

  /// True when @p accept(i, j) returns true for some pair of distinct triangles whose closed
  /// boxes overlap; the traversal stops soon after the first such pair (every thread
  /// checks a shared flag). accept must be thread-safe when @p threaded.
  [[nodiscard]] bool any_self_pair(const std::function<bool(std::int32_t, std::int32_t)>& accept,
                                   bool threaded = true) const;

  /// The corners of triangle @p id as copied at construction.
  [[nodiscard]] const std::array<Vec3, 3>& corners(std::int32_t id) const;

 private:
  std::vector<std::pair<std::int32_t, std::int32_t>> traverse_self(
      const std::function<bool(std::int32_t, std::int32_t)>& accept, bool threaded,
      bool first_only) const;
  struct Node {
    Aabb box;
    std::int32_t first = 0;  // leaf: first slot; inner: left child (right = first + 1)
    std::int32_t count = 0;  // leaf: slots; inner: 0
  };
  std::vector<Node> m_nodes;
  std::vector<std::int32_t> m_triangle_id;         // slot → triangle id
  std::vector<std::int32_t> m_slot;                // triangle id → slot
  std::vector<std::array<Vec3, 3>> m_corners;      // by slot
  std::vector<Aabb> m_boxes;                       // by slot
};

}  // namespace ido::geometry

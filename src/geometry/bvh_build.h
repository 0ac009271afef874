// SPDX-License-Identifier: Apache-2.0
// Internal: the bounding-volume hierarchy layout shared by TriangleBvh and WindingNumber.
#pragma once

#include <cstdint>
#include <vector>

#include "ido/geometry/aabb.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry::detail {

/// A node: a leaf holds items order[first, first + count); an inner node (count == 0) has
/// children first and first + 1.
struct BvhNode {
  Aabb box;
  std::int32_t first = 0;
  std::int32_t count = 0;
  [[nodiscard]] bool leaf() const { return count > 0; }
};

struct BvhTree {
  std::vector<BvhNode> nodes;       ///< nodes[0] is the root (absent when there are no items)
  std::vector<std::int32_t> order;  ///< item ids in leaf order
};

/// Build: items sorted along a Morton curve of their centroids, the ordered range halved
/// recursively down to at most @p leaf_size items per leaf, boxes filled bottom-up.
/// O(n log n).
BvhTree build_bvh(const std::vector<Aabb>& boxes, const std::vector<Vec3>& centroids,
                  int leaf_size);

/// build_bvh() over the triangles of @p mesh (item id = triangle index), boxed tightly.
BvhTree build_triangle_bvh(const TriangleMesh& mesh, int leaf_size);

}  // namespace ido::geometry::detail

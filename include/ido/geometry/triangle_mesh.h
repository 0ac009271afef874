// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/field.h"

namespace ido::geometry {

/// An indexed triangle mesh in world coordinates (mm). Triangles are counter-clockwise seen
/// from outside for a closed, outward-oriented surface. Optional named fields hold one
/// entry per vertex (point_fields) or per triangle (cell_fields).
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<Tri> triangles;
  FieldMap point_fields;
  FieldMap cell_fields;

  [[nodiscard]] std::size_t vertex_count() const { return vertices.size(); }
  [[nodiscard]] std::size_t triangle_count() const { return triangles.size(); }
};

}  // namespace ido::geometry

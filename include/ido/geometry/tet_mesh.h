// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/field.h"

namespace ido::geometry {

/// An indexed tetrahedral mesh in world coordinates (mm). A tetrahedron (a, b, c, d) is
/// positively oriented when (b − a) · ((c − a) × (d − a)) > 0, i.e. its signed volume is
/// positive. Optional named fields hold one entry per vertex or per tetrahedron.
struct TetMesh {
  std::vector<Vec3> vertices;
  std::vector<Tet> tets;
  FieldMap point_fields;
  FieldMap cell_fields;

  [[nodiscard]] std::size_t vertex_count() const { return vertices.size(); }
  [[nodiscard]] std::size_t tet_count() const { return tets.size(); }
};

}  // namespace ido::geometry

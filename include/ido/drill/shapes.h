// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string_view>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"

namespace ido::drill {

/// The cube [0, size]³ as 12 tetrahedra: each face split into 2 triangles joined to the
/// centre (the paper's test cube).
[[nodiscard]] geometry::TetMesh make_cube12(double size_mm = 1.0);

/// A box [0, sx] × [0, sy] × [0, sz] (mm) cut into cubic cells of about @p cell_mm, each
/// split into 6 Kuhn tetrahedra (conforming across cells), all positively oriented.
/// @throws ido::InvalidInput for non-positive sizes or more than 10⁷ tetrahedra.
[[nodiscard]] geometry::TetMesh make_block(const Vec3& size_mm, double cell_mm);

/// Parses "cube", "cube12" or "block:SX,SY,SZ[,CELL]" (mm; CELL defaults to the smallest
/// side / 4) and builds that mesh: "cube" is the unit cube [0, 1]³ as one cell of 6 Kuhn
/// tetrahedra (make_block({1, 1, 1}, 1)), "cube12" is make_cube12(1).
/// @throws ido::InvalidInput naming the text.
[[nodiscard]] geometry::TetMesh make_shape(std::string_view spec);

}  // namespace ido::drill

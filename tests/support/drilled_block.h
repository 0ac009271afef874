// SPDX-License-Identifier: Apache-2.0
// A drilled hierarchy shared by the tests of what is left after drilling (the leaf mesh and its
// files).
#pragma once

#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"

namespace ido::test {

/// A 6 × 6 × 4 mm block (2 mm cells) drilled at three levels of refinement: a burr through a
/// corner and one inside, and a whole root erased, so leaves of several depths, erased cells and
/// points on the roots' faces, edges and corners (shared between roots) all occur.
inline drill::TetHierarchy drilled_block() {
  drill::TetHierarchy h(drill::make_block({6, 6, 4}, 2.0));
  drill::Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = 3, .max_node_visits = 0});
  for (const Vec3& c : {Vec3(0.3, 0.4, 4.1), Vec3(3.1, 2.9, 2.2), Vec3(5.0, 5.5, 1.0)})
    e.erode(h, c, 1.1, 1.0, 1e-3);
  h.erase(drill::NodeRef{7, 0, 0});
  return h;
}

}  // namespace ido::test

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ido/core/math.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/drill/tool.h"

namespace ido::drill {

/// Local contact model from one collision query: the material near the tool is modelled
/// as a half-space with outward normal @p normal, penetrated by @p depth_mm when the burr
/// centre is at @p position_mm. The haptic thread extrapolates it between queries:
/// depth(x) = depth_mm − normal · (x − position_mm).
struct ContactModel {
  bool in_contact = false;
  Vec3 normal = Vec3::Zero();       ///< unit vector from the material toward the tool
  double depth_mm = 0.0;            ///< penetration estimate (mm)
  Vec3 position_mm = Vec3::Zero();  ///< burr centre at the query (mm)
  int burr_samples_inside = 0;
  int shaft_samples_inside = 0;
};

/// Tests every tool sample against the material (spatial hash → root → TreeTable descent
/// → leaf; a sample is inside when its leaf is full). For the burr, the samples inside form
/// a cap; on a flat face the fraction f of evenly spread samples in the cap equals the cap
/// area over the sphere area, d / (2r), so depth = 2 r f; the direction is the sum of the
/// inside samples' inward normals (centre − sample). Shaft rings add their inward radial
/// directions and a depth 2 r_s f_ring for their most covered ring. A fully buried burr
/// (no direction) pushes back along the shaft axis. Allocates nothing, never throws.
[[nodiscard]] ContactModel collide(const TetHierarchy& hierarchy, const Tool& tool, const ToolPose& pose) noexcept;

}  // namespace ido::drill

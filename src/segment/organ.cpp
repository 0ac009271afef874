// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/organ.h"

#include <cmath>

#include "ido/core/error.h"

namespace ido::segment {

Organ parse_organ(std::string_view name) {
  for (Organ o : {Organ::Generic, Organ::Artery, Organ::Vein, Organ::Vertebra})
    if (name == organ_name(o)) return o;
  throw InvalidInput("organ '" + std::string(name) + "': expected generic, artery, vein or vertebra");
}

const char* organ_name(Organ organ) noexcept {
  switch (organ) {
    case Organ::Artery: return "artery";
    case Organ::Vein: return "vein";
    case Organ::Vertebra: return "vertebra";
    case Organ::Generic: break;
  }
  return "generic";
}

BalloonOptions organ_options(Organ organ, BalloonOptions o) {
  switch (organ) {
    case Organ::Artery:
    case Organ::Vein:
      // The lumen: the wall half-way to soft tissue, not to lung or fat beyond a thin wall, and
      // the final snap kept to the vessel the inflation filled (docs/segmentation.md).
      o.outside_level = 40.0;
      // At 2–3 mm voxels the cortex is a voxel or less: the half-way level fits the reference
      // better than the three-plateau wall, which puts it about a voxel outward there; at 1 mm
      // the plateau fit finds the cortex's outer edge (measured: docs/segmentation.md).
      o.plateau_wall_max_voxel_mm = 1.5;
      o.edge_reach_voxels = 2.0;
      // A heart chamber's inscribed radius is about twice a great vessel's (a left ventricle
      // 21–29 mm, the descending aorta 10–14 mm), the aortic root at most about 1.5 times: an
      // artery's chambers start at 1.6 times the seed's radius. A vein's (the IVC's right
      // atrium, the liver around it) at 2.
      o.leak.chamber_factor = organ == Organ::Vein ? 2.0 : 1.6;
      break;
    case Organ::Vertebra:
      o.accept_brighter = true;
      // The band reaches at most half-way from the marrow down to soft tissue (CT, HU).
      o.outside_level = 40.0;
      // At 2–3 mm voxels the cortex is a voxel or less: the half-way level fits the reference
      // better than the three-plateau wall, which puts it about a voxel outward there; at 1 mm
      // the plateau fit finds the cortex's outer edge (measured: docs/segmentation.md).
      o.plateau_wall_max_voxel_mm = 1.5;
      o.leak.separate_neighbours = true;
      break;
    case Organ::Generic: break;
  }
  return o;
}

BalloonOptions balloon_options(const BalloonChoices& c, const std::function<std::string(std::string_view)>& option_name) {
  const auto name = [&](std::string_view field) { return option_name ? option_name(field) : std::string(field); };
  if (c.reference && !std::isfinite(*c.reference)) throw InvalidInput(name("reference") + " must be finite");
  if (c.tolerance && !(*c.tolerance > 0 && std::isfinite(*c.tolerance)))
    throw InvalidInput(name("tolerance") + " must be positive and finite");
  if (!(c.edge_reach_voxels >= 0) || !std::isfinite(c.edge_reach_voxels))
    throw InvalidInput(name("edge_reach_voxels") + " must be 0 (no limit) or a positive number of voxels");
  if (c.outside_level && !std::isfinite(*c.outside_level)) throw InvalidInput(name("outside_level") + " must be finite");
  if (c.max_iterations < 1) throw InvalidInput(name("max_iterations") + " must be at least 1");
  if (c.max_radius_mm && !(*c.max_radius_mm > 0)) throw InvalidInput(name("max_radius_mm") + " must be positive");
  if (c.roi_mm && (!c.roi_mm->min.allFinite() || !c.roi_mm->max.allFinite() ||
                   (c.roi_mm->min.array() >= c.roi_mm->max.array()).any()))
    throw InvalidInput(name("roi") + ": expected x0,y0,z0,x1,y1,z1 in mm with each minimum below its maximum");
  BalloonOptions bo = organ_options(c.organ);
  bo.reference = c.reference;
  bo.tolerance = c.tolerance;
  bo.accept_brighter = bo.accept_brighter || c.bone;
  if (c.white_noise) bo.estimate.residual_ball_factor = 5.0;
  if (c.edge_reach_voxels > 0) bo.edge_reach_voxels = c.edge_reach_voxels;
  if (c.outside_level) bo.outside_level = c.outside_level;
  bo.max_iterations = c.max_iterations;
  bo.roi_mm = c.roi_mm;
  bo.leak.enabled = c.leak_control;
  bo.leak.stop_points_mm = c.stop_points_mm;
  if (c.max_radius_mm) bo.leak.max_radius_mm = *c.max_radius_mm;
  return bo;
}

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/organ.h"

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
      if (organ == Organ::Vein) o.leak.chamber_factor = 2.0;
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

}  // namespace ido::segment

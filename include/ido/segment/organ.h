// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <string>
#include <string_view>

#include "ido/segment/balloon.h"

namespace ido::segment {

/// What the seed is placed in, when the defaults are not enough: each choice sets a few
/// documented BalloonOptions (docs/segmentation.md, "Organ choices"). Generic keeps them all.
enum class Organ {
  Generic,   ///< the defaults: the paper's symmetric band, leak control against chambers
  Artery,    ///< contrast-filled CT vessel: the lumen's wall (outside level 40 HU), edge reach 2 voxels
  Vein,      ///< as Artery, with a chamber at twice the vein's radius (a vein inside parenchyma of a close grey level)
  Vertebra,  ///< bone (brighter also belongs) separated from the vertebrae above and below
};

/// The organ named @p name ("generic", "artery", "vein", "vertebra").
/// @throws ido::InvalidInput naming the choices on any other name.
[[nodiscard]] Organ parse_organ(std::string_view name);
[[nodiscard]] const char* organ_name(Organ organ) noexcept;

/// The balloon options for @p organ: @p base with the organ's settings applied.
[[nodiscard]] BalloonOptions organ_options(Organ organ, BalloonOptions base = {});

}  // namespace ido::segment

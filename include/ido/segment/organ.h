// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ido/segment/balloon.h"

namespace ido::segment {

/// What the seed is placed in, when the defaults are not enough: each choice sets a few
/// documented BalloonOptions (docs/segmentation.md, "Organ choices"). Generic keeps them all.
enum class Organ {
  Generic,   ///< the defaults: the paper's symmetric band, leak control against chambers
  Artery,    ///< contrast-filled CT vessel: the lumen's wall (outside level 40 HU), edge reach 2 voxels, chambers from 1.6× the seed's radius
  Vein,      ///< as Artery, with a chamber at twice the vein's radius (a vein inside parenchyma of a close grey level)
  Vertebra,  ///< bone (brighter also belongs) separated from the vertebrae above and below
};

/// The organ named @p name ("generic", "artery", "vein", "vertebra").
/// @throws ido::InvalidInput naming the choices on any other name.
[[nodiscard]] Organ parse_organ(std::string_view name);
[[nodiscard]] const char* organ_name(Organ organ) noexcept;

/// The balloon options for @p organ: @p base with the organ's settings applied.
[[nodiscard]] BalloonOptions organ_options(Organ organ, BalloonOptions base = {});

/// What a user says about one segmentation: the `ido segment` flags, `ido pipeline`'s vessel and
/// bone, Python's ido.segment / ido.Balloon keywords and the workbench's panel all fill this,
/// and balloon_options() turns it into BalloonOptions, so the same choices give the same run.
struct BalloonChoices {
  Organ organ = Organ::Generic;
  std::optional<double> reference, tolerance;  ///< unset: estimated at the seeds
  bool bone = false;         ///< brighter also belongs (on top of the organ's own setting)
  bool white_noise = false;  ///< the residual noise estimate (IntensityEstimateOptions::residual_ball_factor 5)
  double edge_reach_voxels = 0.0;  ///< 0: the organ's own (BalloonOptions::edge_reach_voxels)
  std::optional<double> outside_level;  ///< unset: the organ's own
  int max_iterations = BalloonOptions{}.max_iterations;
  std::optional<geometry::Aabb> roi_mm;
  bool leak_control = true;             ///< LeakControlOptions::enabled
  std::vector<Vec3> stop_points_mm;     ///< LeakControlOptions::stop_points_mm
  std::optional<double> max_radius_mm;  ///< LeakControlOptions::max_radius_mm
};

/// The options @p choices ask for: organ_options(choices.organ) with the rest applied.
/// @p option_name spells a field's name as the caller's user knows it (the CLI's flag, Python's
/// keyword); by default the field's own name ("reference", "edge_reach_voxels", ...).
/// @throws ido::InvalidInput naming the option: a non-finite reference or outside level, a
/// tolerance not positive and finite, a negative or non-finite edge reach, max_iterations < 1,
/// a max radius not positive, or an empty or non-finite region of interest.
[[nodiscard]] BalloonOptions balloon_options(const BalloonChoices& choices,
                                             const std::function<std::string(std::string_view)>& option_name = {});

/// How a segmentation was asked for, as its report records it (io::segment_report).
struct SegmentRequest {
  std::string input;               ///< the CT's file name as given
  std::vector<Vec3> seeds_mm;      ///< world positions (mm)
  Organ organ = Organ::Generic;
  BalloonOptions options;          ///< the options the balloon ran with
};

}  // namespace ido::segment

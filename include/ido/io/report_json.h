// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <filesystem>

#include <nlohmann/json.hpp>

#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "ido/segment/balloon.h"
#include "ido/segment/metrics.h"
#include "ido/segment/organ.h"
#include "ido/sim/diagnostics.h"

namespace ido::io {

/// JSON whose objects keep the order their keys were written in (reports read top-down).
using Json = nlohmann::ordered_json;

// One JSON form per report: the CLI's reports, `ido pipeline`'s report and the Python
// module's dicts are all made by these, so one figure has one key everywhere. The keys are
// documented once, in docs/reports.md. A number that is not finite (a Hausdorff distance to
// an empty surface, a chamber radius that does not apply) is written as null.

/// A non-finite @p v as null, otherwise the number.
[[nodiscard]] Json finite_or_null(double v);

/// Closed / manifold / oriented checks, counts, area, volume and bounds of a triangle mesh.
[[nodiscard]] Json to_json(const geometry::MeshCheckReport& report);
/// Orientation, volume, quality and boundary of a tetrahedral mesh.
[[nodiscard]] Json to_json(const geometry::TetMeshReport& report);
/// Dice, surface distances, volumes and components of a mask against its truth.
[[nodiscard]] Json to_json(const segment::SegmentationScores& scores);
/// What a balloon run did: its intensity model, steps, time per phase, surface figures,
/// stop reason and leak control.
[[nodiscard]] Json to_json(const segment::BalloonReport& report);
/// A segmentation's report: the request (input, seeds, organ, edge reach, outside level, region
/// of interest `roi_mm` [[min], [max]], null when not set), to_json of the balloon's report (with
/// the leak control's stop points and radius bound) and the output names ("surface", "mask":
/// null when empty). The document `ido segment --report` writes (which adds its calcification and
/// snapshot keys) and the workbench saves.
[[nodiscard]] Json segment_report(const segment::SegmentRequest& request, const segment::BalloonResult& result,
                                  const std::filesystem::path& surface, const std::filesystem::path& mask);
/// Kinetic, gravitational and elastic energy (total and per model), mJ.
[[nodiscard]] Json to_json(const sim::EnergyReport& report);

}  // namespace ido::io

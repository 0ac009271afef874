// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <nlohmann/json.hpp>

#include "ido/drill/simulator.h"
#include "ido/drill/tet_hierarchy.h"

namespace ido::cli {

/// The JSON figures of a finished drilling session (shared by `ido drill` and
/// `ido pipeline`): removed and remaining volume (mm³), node count, bytes per node, update,
/// haptic-period and force-computation percentiles (ms), missed 1 ms deadlines, force trace.
/// @p volume_before_mm3 is the hierarchy's material volume before the session.
nlohmann::json drill_session_json(const drill::TetHierarchy& hierarchy, const drill::Simulator& sim,
                                  const drill::SimulatorOptions& options, double volume_before_mm3);

}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
#pragma once
// energy.png of `ido simulate` and `ido pipeline --deform`.

#include <filesystem>

#include "ido/io/scene.h"

namespace ido::cli {

/// Plots the energies of a scene run over time: kinetic and elastic as they are, gravitational
/// and total as changes since the first sample (their absolute level depends on where the
/// height origin lies and would flatten the other curves). Written by temp file and rename.
void write_energy_plot(const std::filesystem::path& path, const io::SceneRunResult& result);

}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ido::io {

/// One frame of a ParaView time series.
struct PvdEntry {
  double time_s = 0.0;   ///< simulation time of the frame
  std::string file;      ///< frame file, relative to the .pvd's folder (.vtu or .vtp)
};

/// Writes a ParaView collection (.pvd) indexing @p entries, atomically.
void write_pvd(const std::filesystem::path& path, const std::vector<PvdEntry>& entries);

/// Reads a .pvd index. @throws ido::IoError on malformed content.
[[nodiscard]] std::vector<PvdEntry> read_pvd(const std::filesystem::path& path);

}  // namespace ido::io

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace ido {

/// Writes a file so that it appears whole or not at all: @p write_body fills a temporary
/// file in the target's folder, which is flushed, closed and renamed over @p path. If
/// @p write_body throws or the stream fails, the temporary is removed, any old file at
/// @p path stays untouched, and ido::IoError (naming @p path) is thrown.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write_body,
                           bool binary = true);

/// Same, for writers that need a file name (e.g. ITK): @p write_to receives the temporary
/// path, which keeps @p path's extension (e.g. ".tmp-1234-out.nii.gz").
void write_path_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path&)>& write_to);

}  // namespace ido

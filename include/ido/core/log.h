// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>

#include <spdlog/logger.h>

namespace ido {

/// The logger every ido module writes to. By default it has no sink, so the library prints
/// nothing; an application installs one with set_logger (the `ido` tool logs to stderr).
[[nodiscard]] spdlog::logger& logger();

/// Replaces the library's logger (shared with the caller, who usually keeps a handle to
/// change its level). Passing nullptr restores the silent default.
void set_logger(std::shared_ptr<spdlog::logger> logger);

}  // namespace ido

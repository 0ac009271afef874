// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace ido::cli {

/// Options every subcommand can read (set by the top-level flags).
struct GlobalOptions {
  bool verbose = false;
  bool quiet = false;
};

/// One `ido` subcommand. `setup` adds the subcommand to the app and binds its callback;
/// the callback does the work and throws ido::InvalidInput / ido::IoError for bad input
/// (exit 2) or anything else for internal failures (exit 1). `order` sorts --help.
struct Command {
  std::string name;
  int order = 100;
  std::function<void(CLI::App& app, const GlobalOptions& global)> setup;
};

/// Adds a command to the tool's registry; used by each cmd_*.cpp at static-init time.
bool register_command(Command command);
/// All registered commands, sorted by order.
std::vector<Command>& registered_commands();

}  // namespace ido::cli

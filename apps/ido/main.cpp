// SPDX-License-Identifier: Apache-2.0
// The `ido` command-line tool. Subcommands live in cmd_*.cpp and register themselves; this
// file only parses global flags, installs the logger and maps errors to exit codes:
// 0 success, 2 bad input or arguments, 1 internal failure.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "command.h"
#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "ido/core/log.h"
#include "ido/core/memory.h"
#include "ido/io/memory_budget.h"

namespace ido::cli {

bool register_command(Command command) {
  registered_commands().push_back(std::move(command));
  return true;
}

std::vector<Command>& registered_commands() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace ido::cli

int main(int argc, char** argv) {
  using namespace ido::cli;
  // Volumes and repair grids of tens of MB are allocated and freed again and again: reuse
  // freed memory and map fresh memory in huge pages (ido/core/memory.h). On this project's
  // 2-core VM it took 90 % of the page faults and 0.1–0.3 s out of each `ido segment` run.
  ido::use_huge_page_heap();
  // Ctrl-C, SIGTERM or SIGHUP during a write removes the temporary files (ido/core/atomic_file.h)
  // and the process ends by the signal, so an interrupted run leaves no output behind.
  ido::install_signal_cleanup();
  CLI::App app{"ido — toolkit for computer-assisted surgery (balloon segmentation, "
               "deformable simulation, bone drilling)"};
  app.require_subcommand(1);
  // -v / -q may also follow the subcommand: its unknown options fall through to this app.
  app.fallthrough();
  app.set_version_flag("--version", "ido 0.1.0");
  GlobalOptions global;
  app.add_flag("-v,--verbose", global.verbose, "Log details to stderr");
  app.add_flag("-q,--quiet", global.quiet, "Only errors on stderr, no progress bar");
  std::string memory_limit;
  app.add_option("--memory-limit", memory_limit,
                 "Largest buffer a file may declare, e.g. 8G or 512M (default: 3/4 of physical memory)");

  auto& commands = registered_commands();
  std::stable_sort(commands.begin(), commands.end(),
                   [](const Command& a, const Command& b) { return a.order < b.order; });
  for (const auto& c : commands) c.setup(app, global);

  auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  auto logger = std::make_shared<spdlog::logger>("ido", sink);
  logger->set_pattern("%^[%l]%$ %v");
  logger->set_level(spdlog::level::warn);
  ido::set_logger(logger);
  app.parse_complete_callback([&] {
    if (!memory_limit.empty())
      ido::io::set_memory_limit_bytes(ido::io::parse_memory_size(memory_limit, "--memory-limit"));
    logger->set_level(global.quiet     ? spdlog::level::err
                      : global.verbose ? spdlog::level::debug
                                       : spdlog::level::info);
  });

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "ido: error: %s\n", e.what());
    return 2;
  } catch (const ido::InvalidInput& e) {
    std::fprintf(stderr, "ido: error: %s\n", e.what());
    return 2;
  } catch (const ido::IoError& e) {
    std::fprintf(stderr, "ido: error: %s\n", e.what());
    return 2;
  } catch (const ido::Cancelled& e) {
    std::fprintf(stderr, "ido: cancelled\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ido: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}

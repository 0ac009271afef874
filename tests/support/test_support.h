// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/math.h"

namespace ido::test {

/// The project's source folder.
std::filesystem::path source_dir();
/// tests/data inside the source tree (small fixtures committed with the project).
std::filesystem::path fixtures_dir();
/// ../shared/data beside the checkout (or $IDO_SHARED_DATA), if present.
std::optional<std::filesystem::path> shared_data_dir();
/// A fresh empty folder for one test's output, removed at the next run.
std::filesystem::path scratch_dir(const std::string& name);
/// Path of the built `ido` executable.
std::filesystem::path tool_path();

/// Result of running a command: exit code and captured stdout / stderr.
struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
/// Runs `ido ARGS` (arguments already shell-quoted as needed) and captures its output.
CommandResult run_tool(const std::string& args);

/// Rotation by @p ax about x, then @p ay about y, then @p az about z (radians).
inline Mat3 rotation(double ax, double ay, double az) {
  return (Eigen::AngleAxisd(az, Vec3::UnitZ()) * Eigen::AngleAxisd(ay, Vec3::UnitY()) *
          Eigen::AngleAxisd(ax, Vec3::UnitX()))
      .toRotationMatrix();
}

/// |a − b| ≤ tol, with a readable failure message.
inline ::testing::AssertionResult near(double a, double b, double tol) {
  if (std::abs(a - b) <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << a << " vs " << b << " differ by " << std::abs(a - b)
                                       << " > " << tol;
}
/// |a − b| ≤ rel · max(|a|, |b|).
inline ::testing::AssertionResult rel_near(double a, double b, double rel) {
  const double scale = std::max(std::abs(a), std::abs(b));
  if (std::abs(a - b) <= rel * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << a << " vs " << b << " relative difference "
                                       << std::abs(a - b) / scale << " > " << rel;
}

}  // namespace ido::test

/// Skips the current test when ../shared/data is absent.
#define IDO_REQUIRE_SHARED_DATA()                                           \
  do {                                                                      \
    if (!::ido::test::shared_data_dir()) GTEST_SKIP() << "no ../shared/data"; \
  } while (0)

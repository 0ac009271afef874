// SPDX-License-Identifier: Apache-2.0
// Helpers shared by the io tests: reading a file back with VTK's own Python readers.
#pragma once

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace ido::test {

/// Runs tests/io/vtk_check.py KIND FILE with /usr/bin/python3 and parses its JSON, or
/// returns nullopt when python3 with vtk is unavailable.
inline std::optional<nlohmann::json> vtk_read(const std::string& kind, const std::filesystem::path& file) {
  static const bool have_vtk = std::system("/usr/bin/python3 -c 'import vtkmodules.vtkIOXML' >/dev/null 2>&1") == 0;
  if (!have_vtk) return std::nullopt;
  const std::string cmd = "/usr/bin/python3 '" + (std::filesystem::path(IDO_SOURCE_DIR) / "tests/io/vtk_check.py").string() +
                          "' " + kind + " '" + file.string() + "' 2>/dev/null";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return std::nullopt;
  std::string text;
  char buf[65536];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) text.append(buf, n);
  ::pclose(pipe);
  return nlohmann::json::parse(text);
}

}  // namespace ido::test

/// Skips the test when VTK's Python readers are missing.
#define IDO_VTK_READ(var, kind, file)                                   \
  auto var##_opt = ::ido::test::vtk_read(kind, file);                   \
  if (!var##_opt) GTEST_SKIP() << "python3-vtk9 not available";         \
  const nlohmann::json& var = *var##_opt

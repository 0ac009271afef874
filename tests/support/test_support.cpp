// SPDX-License-Identifier: Apache-2.0
#include "support/test_support.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace ido::test {
namespace fs = std::filesystem;

fs::path source_dir() { return IDO_SOURCE_DIR; }
fs::path fixtures_dir() { return source_dir() / "tests" / "data"; }

std::optional<fs::path> shared_data_dir() {
  if (const char* env = std::getenv("IDO_SHARED_DATA"); env && fs::is_directory(env)) return fs::path(env);
  const fs::path p = source_dir().parent_path() / "shared" / "data";
  if (fs::is_directory(p)) return p;
  return std::nullopt;
}

fs::path scratch_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("ido-test-" + std::to_string(::getpid())) / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

fs::path tool_path() { return IDO_TOOL_PATH; }

CommandResult run_tool(const std::string& args) {
  static int counter = 0;
  const fs::path dir = scratch_dir("run-tool-" + std::to_string(counter++));
  const fs::path out = dir / "out.txt", err = dir / "err.txt";
  const std::string cmd = tool_path().string() + " " + args + " >" + out.string() + " 2>" + err.string() + " </dev/null";
  const int status = std::system(cmd.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace ido::test

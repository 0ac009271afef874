// SPDX-License-Identifier: Apache-2.0
// Ctrl-C or SIGTERM while `ido` writes (issue 30): the real tool is started on a write big
// enough to be caught half-way (a noisy phantom, gzip-compressed), the signal is sent as soon
// as a temporary file has bytes in it, and then the tool must have ended by that signal and
// left nothing in its output folder: no temporary, no partial output.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_support.h"

namespace ido::cli {
namespace {
namespace fs = std::filesystem;

std::vector<std::string> names(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) out.push_back(e.path().filename().string());
  return out;
}

/// True once a temporary file in @p dir (or in a staging folder in it) holds bytes: a write
/// is under way.
bool writing(const fs::path& dir) {
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    const auto name = it->path().filename().string();
    std::error_code size_ec;
    if (name.rfind(".tmp-", 0) == 0 && it->is_regular_file(size_ec) && fs::file_size(it->path(), size_ec) > 0 &&
        !size_ec)
      return true;
  }
  return false;
}

struct Interrupted {
  bool caught_writing = false;  ///< the signal was sent while a temporary file was being written
  int status = 0;               ///< wait status of the tool
};

/// Starts `ido ARGS` (stdout and stderr to /dev/null), sends @p sig once a temporary file in
/// @p out_dir has bytes, and waits for the tool.
Interrupted interrupt_while_writing(const std::vector<std::string>& args, const fs::path& out_dir, int sig) {
  std::vector<std::string> argv_text{test::tool_path().string()};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    // The signals' default actions, whatever the test runner set.
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) _exit(126);
    execv(argv[0], argv.data());
    _exit(127);
  }
  Interrupted r;
  // Poll every half millisecond for at most two minutes (a sanitizer build is slow).
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  while (std::chrono::steady_clock::now() < give_up) {
    if (writing(out_dir)) {
      r.caught_writing = true;
      break;
    }
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {  // ended before any write was seen
      r.status = status;
      return r;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  kill(pid, sig);
  waitpid(pid, &r.status, 0);
  return r;
}

TEST(CliInterrupt, SignalDuringAWriteLeavesNothingAndEndsByTheSignal) {
  for (const int sig : {SIGTERM, SIGINT}) {
    SCOPED_TRACE(sig == SIGTERM ? "SIGTERM" : "SIGINT");
    const auto dir = test::scratch_dir(std::string("cli-interrupt-") + (sig == SIGTERM ? "term" : "int"));
    // 160 x 160 x 160 float voxels of noise, about 16 MB to compress, then the labels.
    const auto r = interrupt_while_writing({"-q", "phantom", "sphere", "--spacing", "0.3,0.3,0.3", "--noise", "20",
                                            "-o", (dir / "ct.nii.gz").string(), "--labels",
                                            (dir / "labels.nii.gz").string()},
                                           dir, sig);
    ASSERT_TRUE(r.caught_writing) << "the tool ended before a write could be interrupted";
    ASSERT_TRUE(WIFSIGNALED(r.status)) << "exit status " << (WIFEXITED(r.status) ? WEXITSTATUS(r.status) : -1);
    EXPECT_EQ(WTERMSIG(r.status), sig);
    EXPECT_EQ(names(dir), std::vector<std::string>{});
  }
}

}  // namespace
}  // namespace ido::cli

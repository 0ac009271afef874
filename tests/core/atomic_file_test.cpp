// SPDX-License-Identifier: Apache-2.0
#include "ido/core/atomic_file.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido {
namespace fs = std::filesystem;
namespace {
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}
}  // namespace

TEST(AtomicFile, WritesWholeFile) {
  const auto dir = test::scratch_dir("atomic-ok");
  write_file_atomically(dir / "a.txt", [](std::ostream& o) { o << "hello"; });
  EXPECT_EQ(slurp(dir / "a.txt"), "hello");
  EXPECT_EQ(entries(dir), 1u);  // no temporary left behind
}

TEST(AtomicFile, FailedWriteKeepsOldFileAndLeavesNoTemporary) {
  const auto dir = test::scratch_dir("atomic-fail");
  write_file_atomically(dir / "a.txt", [](std::ostream& o) { o << "old"; });
  EXPECT_THROW(write_file_atomically(dir / "a.txt",
                                     [](std::ostream& o) {
                                       o << "partial";
                                       throw IoError("a.txt", "simulated failure");
                                     }),
               IoError);
  EXPECT_EQ(slurp(dir / "a.txt"), "old");
  EXPECT_EQ(entries(dir), 1u);
}

TEST(AtomicFile, MissingFolderIsNamed) {
  const auto dir = test::scratch_dir("atomic-missing");
  try {
    write_file_atomically(dir / "nope" / "a.txt", [](std::ostream& o) { o << "x"; });
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

TEST(AtomicFile, FolderAsTargetIsRejected) {
  const auto dir = test::scratch_dir("atomic-folder");
  fs::create_directory(dir / "sub");
  EXPECT_THROW(write_file_atomically(dir / "sub", [](std::ostream& o) { o << "x"; }), IoError);
  EXPECT_TRUE(fs::is_directory(dir / "sub"));
}

TEST(AtomicFile, PathWriterKeepsExtension) {
  const auto dir = test::scratch_dir("atomic-path");
  std::string seen;
  write_path_atomically(dir / "m.nii.gz", [&](const fs::path& tmp) {
    seen = tmp.filename().string();
    std::ofstream(tmp) << "x";
  });
  EXPECT_TRUE(seen.ends_with("m.nii.gz"));
  EXPECT_TRUE(fs::exists(dir / "m.nii.gz"));
  EXPECT_EQ(entries(dir), 1u);
}

}  // namespace ido

// ---- FileBatch and the signal cleanup ------------------------------------------------------

namespace ido {
namespace {
namespace fs = std::filesystem;

std::vector<std::string> names(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// Any number of outputs: they are staged in one hidden folder per target folder, which is
// what the signal cleanup's table holds (one entry however many files).
TEST(FileBatch, CommitPutsEveryStagedFileInPlace) {
  const auto dir = test::scratch_dir("batch-commit");
  const int registered = registered_temporary_file_count();
  FileBatch batch;
  const auto a = batch.stage(dir / "a.vtu");
  const auto b = batch.stage(dir / "b.json");
  EXPECT_EQ(batch.staged(dir / "a.vtu"), a);
  EXPECT_EQ(batch.stage(dir / "a.vtu"), a);
  EXPECT_TRUE(batch.staged(dir / "c.txt").empty());
  EXPECT_EQ(a.filename(), "a.vtu");  // writers that go by the extension still work
  EXPECT_EQ(a.parent_path(), b.parent_path());
  EXPECT_EQ(registered_temporary_file_count(), registered + 1);
  std::ofstream(a) << "a";
  std::ofstream(b) << "b";
  ASSERT_EQ(names(dir).size(), 1u);
  EXPECT_EQ(names(dir)[0].rfind(".tmp-", 0), 0u);
  EXPECT_FALSE(fs::exists(dir / "a.vtu"));
  batch.commit();
  EXPECT_EQ(names(dir), (std::vector<std::string>{"a.vtu", "b.json"}));
  EXPECT_EQ(slurp(dir / "b.json"), "b");
  EXPECT_EQ(registered_temporary_file_count(), registered);
}

TEST(FileBatch, UncommittedBatchLeavesNothing) {
  const auto dir = test::scratch_dir("batch-drop");
  const int registered = registered_temporary_file_count();
  {
    FileBatch batch;
    std::ofstream(batch.stage(dir / "a.vtu")) << "a";
    std::ofstream(batch.stage(dir / "b.json")) << "b";
  }
  EXPECT_TRUE(names(dir).empty());
  EXPECT_EQ(registered_temporary_file_count(), registered);
  FileBatch batch;
  EXPECT_THROW((void)batch.stage(dir / "missing" / "a.vtu"), IoError);
}

/// Runs @p body in a child process and returns its wait status.
template <class Body>
int in_child(Body body) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    body();
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

// SIGTERM, SIGINT and SIGHUP remove the registered temporaries (only those) and end the
// process by the signal, as its default action would.
TEST(SignalCleanup, FatalSignalRemovesRegisteredTemporariesAndEndsByIt) {
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) {
    SCOPED_TRACE(sig);
    const auto dir = test::scratch_dir("signal-cleanup-" + std::to_string(sig));
    std::ofstream(dir / "keep.txt") << "not registered";
    const int status = in_child([&] {
      install_signal_cleanup();
      // More outputs than the table has entries, all staged in one folder.
      FileBatch batch;
      for (int f = 0; f < 2 * kMaxTemporaryFiles; ++f)
        std::ofstream(batch.stage(dir / ("frame_" + std::to_string(f) + ".vtu"))) << "frame";
      const auto tmp = dir / ".tmp-writing";
      const int handle = register_temporary_file(tmp);
      std::ofstream(tmp) << "partial";
      if (handle < 0 || names(dir).size() != 3) _exit(3);
      ::raise(sig);
      _exit(4);  // not reached: the signal ends the process
    });
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(names(dir), std::vector<std::string>{"keep.txt"});
  }
}

// A signal ignored when the handler is installed (nohup) stays ignored.
TEST(SignalCleanup, IgnoredSignalStaysIgnored) {
  const auto dir = test::scratch_dir("signal-ignored");
  const int status = in_child([&] {
    std::signal(SIGHUP, SIG_IGN);
    install_signal_cleanup();
    const int handle = register_temporary_file(dir / "t");
    std::ofstream(dir / "t") << "x";
    ::raise(SIGHUP);
    unregister_temporary_file(handle);
  });
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(names(dir), std::vector<std::string>{"t"});
}

// A full table or an over-long path is not guarded but does not fail; handles are reused.
TEST(SignalCleanup, RegistryIsBoundedAndReusesSlots) {
  const int before = registered_temporary_file_count();
  std::vector<int> handles;
  for (int i = 0; i < kMaxTemporaryFiles + 5; ++i) handles.push_back(register_temporary_file("t" + std::to_string(i)));
  EXPECT_EQ(registered_temporary_file_count(), kMaxTemporaryFiles);
  EXPECT_EQ(std::count(handles.begin(), handles.end(), -1), before + 5);
  for (const int h : handles) unregister_temporary_file(h);
  EXPECT_EQ(registered_temporary_file_count(), before);
  EXPECT_EQ(register_temporary_file(std::string(5000, 'x')), -1);
  const int h = register_temporary_file("again");
  EXPECT_GE(h, 0);
  unregister_temporary_file(h);
}

}  // namespace
}  // namespace ido

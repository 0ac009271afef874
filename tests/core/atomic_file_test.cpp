// SPDX-License-Identifier: Apache-2.0
#include "ido/core/atomic_file.h"

#include <fstream>
#include <sstream>

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

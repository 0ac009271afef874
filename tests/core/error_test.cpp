// SPDX-License-Identifier: Apache-2.0
#include "ido/core/error.h"

#include <gtest/gtest.h>

namespace ido {

TEST(Error, IoErrorNamesPathAndLine) {
  const IoError e("mesh.ply", "expected 3 indices", {.line = 12, .byte_offset = {}});
  EXPECT_STREQ(e.what(), "mesh.ply:12: expected 3 indices");
  EXPECT_EQ(e.path(), "mesh.ply");
  EXPECT_EQ(*e.location().line, 12);
}

TEST(Error, IoErrorNamesByteOffset) {
  const IoError e("a.stl", "truncated", {.line = {}, .byte_offset = 84});
  EXPECT_STREQ(e.what(), "a.stl: byte 84: truncated");
}

TEST(Error, HierarchyCatchesAsError) {
  try {
    throw InvalidInput("x");
  } catch (const Error& e) {
    SUCCEED();
    return;
  }
  FAIL();
}

}  // namespace ido

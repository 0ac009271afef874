// SPDX-License-Identifier: Apache-2.0
// The checks of a segmentation's output names, made before any work.
#include "ido/view/segment_output.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(SegmentOutput, OutputNamesAreCheckedBeforeAnyWork) {
  EXPECT_THROW(view::check_segment_outputs({"s.txt", "", ""}), InvalidInput);
  EXPECT_THROW(view::check_segment_outputs({"", "m.stl", ""}), InvalidInput);
  EXPECT_NO_THROW(view::check_segment_outputs({"s.ply", "m.nii.gz", "r.json"}));
}

}  // namespace
}  // namespace ido

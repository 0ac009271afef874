// SPDX-License-Identifier: Apache-2.0
// `ido compare --truth-below`: a level-set truth (inside where the value is below a level).
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/image/volume.h"
#include "ido/io/volume_io.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(CompareCli, LevelSetTruthIsInsideBelowTheLevel) {
  const auto dir = test::scratch_dir("compare_level_set");
  // Signed distance to a sphere of radius 6 (negative inside) and the same sphere as a mask.
  image::Volume<float> phi({24, 24, 24}, Vec3(0.8, 0.8, 0.8));
  auto ball = phi.like<std::uint8_t>(0);
  const Vec3 c(9.2, 9.2, 9.2);
  std::size_t inside = 0, shell = 0;
  for (std::int64_t k = 0; k < 24; ++k)
    for (std::int64_t j = 0; j < 24; ++j)
      for (std::int64_t i = 0; i < 24; ++i) {
        // Classified on the stored float, as the tool reads it.
        const auto d = static_cast<float>((phi.index_to_world(Vec3(double(i), double(j), double(k))) - c).norm() - 6.0);
        phi(i, j, k) = d;
        ball(i, j, k) = d < 0.0f;
        inside += d < 0.0f;
        shell += d >= 0.0f && d < 1.0f;
      }
  ASSERT_GT(inside, 1000U);
  ASSERT_GT(shell, 300U);
  io::write_volume(dir / "phi.nii.gz", phi);
  io::write_volume(dir / "ball.nii.gz", ball);
  const std::string base = "compare --mask " + (dir / "ball.nii.gz").string() + " --truth " + (dir / "phi.nii.gz").string();
  auto r = test::run_tool(base + " --truth-below 0 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["dice"], 1.0);
  EXPECT_EQ(j["voxels_truth"], inside);
  // Level 1: the truth grows by the one-unit shell, which the mask misses.
  r = test::run_tool(base + " --truth-below 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["voxels_truth"], inside + shell);
  EXPECT_NEAR(j["dice"].get<double>(), 2.0 * double(inside) / double(2 * inside + shell), 1e-12);
  // Without the option every non-zero voxel of the distance map counts as inside.
  r = test::run_tool(base + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(nlohmann::json::parse(r.out)["dice"].get<double>(), 0.5);
  r = test::run_tool(base + " --truth-below nan");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--truth-below"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace ido

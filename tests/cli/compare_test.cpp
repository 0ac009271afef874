// SPDX-License-Identifier: Apache-2.0
// `ido compare --truth-below`: a level-set truth (inside where the value is below a level).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"
#include "ido/io/mesh_io.h"
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

// An open surface has no inside: --mesh refuses it with one line naming the file (it used to
// score Dice 0 and HD inf with exit 0), and a closed one is scored.
TEST(CompareCli, MeshMustBeClosed) {
  const auto dir = test::scratch_dir("compare_open_mesh");
  image::Volume<std::uint8_t> truth({12, 12, 12}, Vec3(1, 1, 1));
  for (std::int64_t k = 3; k < 9; ++k)
    for (std::int64_t j = 3; j < 9; ++j)
      for (std::int64_t i = 3; i < 9; ++i) truth(i, j, k) = 1;
  io::write_volume(dir / "truth.nii.gz", truth);
  // The cube [2.5, 8.5]^3 (the truth's voxels exactly), outward-oriented; without its top face
  // (two triangles) it is open along that face's four edges.
  geometry::TriangleMesh cube;
  for (int c = 0; c < 8; ++c) cube.vertices.push_back(Vec3(c & 1 ? 8.5 : 2.5, c & 2 ? 8.5 : 2.5, c & 4 ? 8.5 : 2.5));
  cube.triangles = {{0, 2, 1}, {1, 2, 3}, {0, 1, 4}, {1, 5, 4}, {0, 4, 2}, {2, 4, 6},
                    {1, 3, 5}, {3, 7, 5}, {2, 6, 3}, {3, 6, 7}, {4, 5, 6}, {5, 7, 6}};
  io::write_triangle_mesh(dir / "closed.ply", cube);
  cube.triangles.resize(10);
  io::write_triangle_mesh(dir / "open.ply", cube);
  auto r = test::run_tool("compare --mesh " + (dir / "closed.ply").string() + " --truth " + (dir / "truth.nii.gz").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["dice"], 1.0);
  r = test::run_tool("compare --mesh " + (dir / "open.ply").string() + " --truth " + (dir / "truth.nii.gz").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("open.ply: the surface is not closed (4 boundary edges)"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

}  // namespace
}  // namespace ido

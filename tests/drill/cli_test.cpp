// SPDX-License-Identifier: Apache-2.0
// `ido tetmesh` and `ido drill` end to end.
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/drill/tet_hierarchy.h"
#include "ido/io/mesh_io.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

TEST(DrillCli, TetmeshThenDrillWritesConsistentOutputs) {
  const auto dir = test::scratch_dir("drill_cli");
  const auto block = (dir / "block.vtu").string();
  auto r = test::run_tool("tetmesh --shape block:16,16,8,2 -o " + block);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto mesh = io::read_tet_mesh(block);
  EXPECT_EQ(mesh.tets.size(), 8U * 8U * 4U * 6U);
  {
    std::ofstream f(dir / "path.csv");
    f << "t,x,y,z\n0,8,8,11\n0.25,8,8,7\n0.5,11,9,7\n0.6,11,9,11\n";
  }
  r = test::run_tool("drill " + block + " --tool sphere:radius=1.5 --path " + (dir / "path.csv").string() + " -o " +
                     (dir / "out.vtu").string() + " --surface " + (dir / "out.stl").string() + " --report " +
                     (dir / "r.json").string() + " --max-depth 4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "r.json");
  const auto rep = nlohmann::json::parse(in);
  const double removed = rep["removed_volume_mm3"], remaining = rep["remaining_volume_mm3"];
  EXPECT_TRUE(test::rel_near(removed + remaining, 16.0 * 16 * 8, 1e-9));
  EXPECT_GT(removed, 4.0 / 3.0 * kPi * 1.5 * 1.5 * 1.5 * 0.5);  // at least the plunge's lower half-ball
  EXPECT_LE(rep["bytes_per_node"].get<double>(), 4.0);
  EXPECT_GT(rep["haptic_ticks"].get<int>(), 0);
  // The drilled mesh holds exactly the remaining volume, with depth and density fields.
  const auto out = io::read_tet_mesh(dir / "out.vtu");
  double v = 0.0;
  for (const auto& t : out.tets)
    v += signed_volume(out.vertices[static_cast<std::size_t>(t[0])], out.vertices[static_cast<std::size_t>(t[1])],
                       out.vertices[static_cast<std::size_t>(t[2])], out.vertices[static_cast<std::size_t>(t[3])]);
  EXPECT_TRUE(test::rel_near(v, remaining, 1e-9));
  ASSERT_TRUE(out.cell_fields.count("depth"));
  ASSERT_TRUE(out.cell_fields.count("density"));
  EXPECT_EQ(out.cell_fields.at("depth").count(), out.tets.size());
  EXPECT_GT(io::read_triangle_mesh(dir / "out.stl").triangles.size(), 12U);
}

TEST(DrillCli, BadInputIsExitTwoWithAMessage) {
  const auto dir = test::scratch_dir("drill_cli_bad");
  auto r = test::run_tool("tetmesh --shape block:1,x,1 -o " + (dir / "a.vtu").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("block:1,x,1"), std::string::npos);
  r = test::run_tool("tetmesh --shape cube -o " + (dir / "a.stl").string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(test::run_tool("tetmesh --shape cube12 -o " + (dir / "c.vtu").string()).exit_code, 0);
  r = test::run_tool("drill " + (dir / "c.vtu").string() + " --tool sphere:radius=1 --path " + (dir / "none.csv").string() +
                     " -o " + (dir / "o.vtu").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("none.csv"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "o.vtu"));
  r = test::run_tool("drill " + (dir / "c.vtu").string() + " --tool sphere:radius=-1 --path x.csv -o " + (dir / "o.vtu").string());
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace ido::drill

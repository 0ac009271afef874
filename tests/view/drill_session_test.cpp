// SPDX-License-Identifier: Apache-2.0
// The drilling session the Drill workspace runs: moved from code like a mouse drag it drills,
// records its path (readable by ScriptedTrajectory::load_csv) and hands over a final surface
// enclosing what is left; a replayed path CSV moves the tool along it and ends with it.
#include "ido/view/drill_session.h"

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/shapes.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

TEST(DrillSession, WindowMovedBurrDrillsRecordsItsPathAndHandsOverTheSurface) {
  const geometry::TetMesh block = drill::make_shape("block:16,16,8");
  view::DrillSession session(block, view::drill_cli_options(2.0), 20.0);
  EXPECT_FALSE(session.started());
  EXPECT_TRUE(test::rel_near(session.initial_volume_mm3(), 16.0 * 16 * 8, 1e-9));
  // Down from 2 mm above the top to 3 mm into it, as a mouse drag would, then stop.
  session.start(Vec3(8, 8, 10));
  for (int i = 0; i <= 50; ++i) {
    session.move_tool(Vec3(8, 8, 10 - 0.1 * i));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    (void)session.figures();  // read while the haptic thread writes
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const view::DrillFigures live = session.figures();
  EXPECT_GT(live.ticks, 100u);
  EXPECT_TRUE(live.contact) << "the burr is pressed into the block";
  EXPECT_GT(live.force_n.z(), 0.0) << "the block pushes the burr back up";
  session.stop();
  for (auto t0 = std::chrono::steady_clock::now();
       !session.ended() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(session.ended());
  const double removed = session.stats().removed_volume_mm3;
  EXPECT_GT(removed, 10.0);
  // The final surface handed over encloses what is left.
  std::shared_ptr<const view::DrillSnapshot> last;
  for (int i = 0; i < 100 && !(last && last->final); ++i) last = session.latest_surface();
  ASSERT_TRUE(last && last->final);
  EXPECT_TRUE(test::rel_near(last->volume_mm3, session.initial_volume_mm3() - removed, 1e-6));
  // The path: every tick, times strictly increasing, readable by `ido drill --path`.
  const fs::path csv = test::scratch_dir("drill-session") / "path.csv";
  session.write_path_csv(csv);
  const auto replay = drill::ScriptedTrajectory::load_csv(csv);
  EXPECT_GE(replay.times().size(), live.ticks);
  EXPECT_TRUE(test::near(replay.poses().front().position_mm.z(), 10.0, 0.5));  // the first tick may come after a move
  EXPECT_TRUE(test::near(replay.poses().back().position_mm.z(), 5.0, 1e-9));
}

TEST(DrillSession, ReplayedPathMovesTheToolAndEndsWithThePath) {
  const geometry::TetMesh block = drill::make_shape("block:16,16,8");
  const fs::path dir = test::scratch_dir("drill-replay");
  std::ofstream(dir / "path.csv") << "t,x,y,z\n0,8,8,11\n0.4,8,8,6\n0.6,8,8,6\n";
  const drill::SimulatorOptions options = view::drill_cli_options(2.0);
  auto device = view::load_path_device(dir / "path.csv", options);
  const double duration = device->duration();
  EXPECT_DOUBLE_EQ(duration, 0.6);
  view::DrillSession session(block, options, duration + 1.0, std::move(device));
  ASSERT_NE(session.source(), nullptr);
  session.start(Vec3(0, 0, 50));  // the path, not this, places the tool
  session.move_tool(Vec3(0, 0, 50));  // ignored: the path moves the tool
  for (auto t0 = std::chrono::steady_clock::now();
       !session.ended() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(session.ended()) << "the session ends when the path does";
  EXPECT_GT(session.stats().removed_volume_mm3, 5.0) << "2 mm deep into the block";
  EXPECT_TRUE(test::near((session.tool_pose().position_mm - Vec3(8, 8, 6)).norm(), 0.0, 1e-9));
  session.write_path_csv(dir / "recorded.csv");
  const auto recorded = drill::ScriptedTrajectory::load_csv(dir / "recorded.csv");
  for (std::size_t i = 0; i < recorded.times().size(); i += 50)  // every tick on the path at its time
    EXPECT_TRUE(test::near(recorded.poses()[i].position_mm.z(),
                           std::max(6.0, 11.0 - 5.0 * std::min(recorded.times()[i], 0.4) / 0.4), 1e-9))
        << recorded.times()[i];
  EXPECT_THROW((void)view::load_path_device(dir / "missing.csv", options), IoError);
}

}  // namespace
}  // namespace ido

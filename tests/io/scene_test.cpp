// SPDX-License-Identifier: Apache-2.0
// io::run_scene as parse → world → sim::run with a writer observer: the files hold exactly the
// frames the run hands over in memory, extra observers watch the same run, the report can be
// rebuilt without reading it back, and a diverging run leaves no file behind.
#include "ido/io/scene.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "support/clamped_cube_scene.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

/// Counts the frames an observer sees.
struct FrameCounter final : sim::RunObserver {
  int frames = 0;
  void on_frame(const sim::World&, std::int64_t, std::int64_t) override { ++frames; }
};

// The frame files hold the meshes the listener got in memory (positions and stress to the
// last bit: VTU stores float64), an extra observer sees every frame, and scene_report() gives
// the report.json the run wrote.
TEST(SceneRun, FilesHoldTheFramesHandedOverInMemory) {
  auto scene = io::parse_scene(test::clamped_cube_scene("implicit_euler", 0.01, 20, 5).dump(), "cube.json", ".");
  const auto out = test::scratch_dir("scene_run_frames");
  std::vector<geometry::TetMesh> frames;
  FrameCounter counter;
  std::vector<sim::RunObserver*> observers{&counter};
  const auto result = io::run_scene(scene, out, nullptr, nullptr, observers,
                                    [&](std::int64_t index, const geometry::TetMesh& mesh) {
                                      EXPECT_EQ(index, std::int64_t(frames.size()));
                                      frames.push_back(mesh);
                                    });
  ASSERT_EQ(result.frames, 5);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(counter.frames, 5);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.vtu", f);
    const auto file = io::read_tet_mesh(out / name);
    ASSERT_EQ(file.vertices.size(), frames[f].vertices.size());
    for (std::size_t i = 0; i < file.vertices.size(); ++i)
      EXPECT_EQ((file.vertices[i] - frames[f].vertices[i]).cwiseAbs().maxCoeff(), 0.0) << name << " vertex " << i;
    for (const char* field : {"von_mises_pa", "green_strain"})
      EXPECT_EQ(file.cell_fields.at(field).values, frames[f].cell_fields.at(field).values) << name << " " << field;
  }
  // The last frame is the end state: it has sagged (z down) under gravity.
  double sag = 0.0;
  for (std::size_t i = 0; i < frames.back().vertices.size(); ++i)
    sag = std::min(sag, frames.back().vertices[i].z() - frames.front().vertices[i].z());
  EXPECT_LT(sag, -1e-3);
  std::ifstream in(out / "report.json");
  const auto written = nlohmann::json::parse(in);
  EXPECT_EQ(written, io::scene_report(scene, result));
}

// The divergence floor is the energy that strains the body by 0.1 %: ½ E ε² V.
TEST(SceneRun, RunOptionsCarryTheSceneAndTheFloor) {
  const auto scene = io::parse_scene(test::clamped_cube_scene("explicit_euler", 0.001, 40, 10).dump(), "cube.json", ".");
  const auto o = io::run_options(scene);
  EXPECT_EQ(o.steps, 40);
  EXPECT_EQ(o.frame_every, 10);
  EXPECT_TRUE(test::rel_near(o.dt_s, 0.001, 1e-15));
  EXPECT_EQ(o.label, "cube.json");
  EXPECT_TRUE(test::rel_near(o.energy_floor_mj, 0.5 * (1e4 * 1e-6) * 1e-6 * 1000.0, 1e-12));
}

// Explicit Euler far beyond its stable step: run_scene throws sim::Diverged before anything of
// the bad state is written, and leaves no file: not frame 0, not the .pvd index; a folder it
// made is removed, a folder that was there is left empty.
TEST(SceneRun, DivergingRunLeavesNoFile) {
  for (const bool folder_existed : {false, true}) {
    SCOPED_TRACE(folder_existed);
    auto scene = io::parse_scene(test::clamped_cube_scene("explicit_euler", 0.01, 4000, 1).dump(), "cube.json", ".");
    const auto dir = test::scratch_dir(folder_existed ? "scene_diverging_existing" : "scene_diverging_new");
    const auto out = dir / "out";
    if (folder_existed) fs::create_directories(out);
    FrameCounter counter;
    std::vector<sim::RunObserver*> observers{&counter};
    int written = 0;
    try {
      (void)io::run_scene(scene, out, nullptr, nullptr, observers,
                          [&](std::int64_t, const geometry::TetMesh&) { ++written; });
      FAIL() << "no divergence";
    } catch (const sim::Diverged& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cube.json: simulation diverged at step ", 0), 0u) << e.what();
      // Frames before the divergence were handed over (and staged), never committed.
      EXPECT_EQ(written, int(e.step()));
      EXPECT_EQ(counter.frames, int(e.step()));
    }
    EXPECT_EQ(fs::exists(out), folder_existed);
    if (folder_existed) {
      EXPECT_TRUE(fs::is_empty(out));
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), folder_existed ? 1 : 0);
  }
}

}  // namespace
}  // namespace ido

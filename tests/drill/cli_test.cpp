// SPDX-License-Identifier: Apache-2.0
// `ido tetmesh` and `ido drill` end to end.

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/io/mesh_io.h"
#include "support/png_read.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

// `ido drill BLOCK --tool sphere:radius=1.5 --path DIR/path.csv -o DIR/OUT EXTRA`.
test::CommandResult drill_burr_1_5(const std::string& block, const std::filesystem::path& dir, const std::string& out,
                                   const std::string& extra = "") {
  return test::run_tool("drill " + block + " --tool sphere:radius=1.5 --path " + (dir / "path.csv").string() + " -o " +
                        (dir / out).string() + extra);
}

// Writes the block `tetmesh --shape SHAPE` into dir/block.vtu and the path CSV rows into
// dir/path.csv; returns the block's path.
std::string block_and_path(const std::filesystem::path& dir, const std::string& shape, const std::string& path_rows) {
  const auto block = (dir / "block.vtu").string();
  const auto r = test::run_tool("tetmesh --shape " + shape + " -o " + block);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::ofstream(dir / "path.csv") << "t,x,y,z\n" << path_rows;
  return block;
}

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
  r = drill_burr_1_5(block, dir, "out.vtu",
                     " --surface " + (dir / "out.stl").string() + " --report " + (dir / "r.json").string() + " --max-depth 4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "r.json");
  const auto rep = nlohmann::json::parse(in);
  const double removed = rep["removed_volume_mm3"], remaining = rep["remaining_volume_mm3"];
  EXPECT_TRUE(test::rel_near(removed + remaining, 16.0 * 16 * 8, 1e-9));
  EXPECT_GT(removed, 4.0 / 3.0 * kPi * 1.5 * 1.5 * 1.5 * 0.5);  // at least the plunge's lower half-ball
  EXPECT_LE(rep["bytes_per_node"].get<double>(), 4.0);
  EXPECT_GT(rep["haptic_ticks"].get<int>(), 0);
  EXPECT_TRUE(rep["haptic_realtime"].is_boolean());
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

// The v_list rebuild on two workers (and serially) still gives a closed surface enclosing
// exactly the remaining volume, and the report says how many workers ran.
TEST(DrillCli, SurfaceThreadsGiveTheSameClosedSurface) {
  const auto dir = test::scratch_dir("drill_cli_surface_threads");
  const auto block = block_and_path(dir, "block:16,16,8,2", "0,8,8,11\n0.25,8,8,7\n0.5,11,9,7\n0.6,11,9,11\n");
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    const auto r = drill_burr_1_5(block, dir, "out.vtu",
                                  " --surface " + (dir / "out.ply").string() + " --report " + (dir / "r.json").string() +
                                      " --max-depth 4 --surface-threads " + std::to_string(threads));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(dir / "r.json");
    const auto rep = nlohmann::json::parse(in);
    EXPECT_EQ(rep["surface_threads"].get<int>(), threads);
    const double remaining = rep["remaining_volume_mm3"];
    EXPECT_GT(rep["removed_volume_mm3"].get<double>(), 1.0);
    const auto s = io::read_triangle_mesh(dir / "out.ply");
    const auto check = geometry::check_mesh(s);
    EXPECT_EQ(check.boundary_edges, 0U);
    EXPECT_TRUE(test::rel_near(check.signed_volume_mm3, remaining, 1e-9)) << check.signed_volume_mm3 << " vs " << remaining;
  }
}

// With neither --max-depth nor --min-size the leaves go down to a quarter of the burr radius:
// block cells of 2 mm (6 tetrahedra each, longest edge 2·√3 ≈ 3.46 mm) and r = 1.5 mm need
// level 4 (0.217 mm ≤ 0.375 mm < 0.433 mm at level 3), and the cut reaches it.
TEST(DrillCli, DefaultFinestLevelFollowsTheBurrRadius) {
  const auto dir = test::scratch_dir("drill_cli_default_depth");
  const auto block = block_and_path(dir, "block:8,8,4,2", "0,4,4,6\n0.3,4,4,3\n");
  const auto r = drill_burr_1_5(block, dir, "out.vtu");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto out = io::read_tet_mesh(dir / "out.vtu");
  const auto& depth = out.cell_fields.at("depth").values;
  ASSERT_FALSE(depth.empty());
  EXPECT_EQ(*std::max_element(depth.begin(), depth.end()), 4.0);
}

std::size_t differing_pixels(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 3 < a.size() && i + 3 < b.size(); i += 4)
    n += (a[i] != b[i] || a[i + 1] != b[i + 1] || a[i + 2] != b[i + 2]) ? 1 : 0;
  return n;
}

TEST(DrillCli, SnapshotsShowTheSurfaceAsItIsDrilled) {
  const auto dir = test::scratch_dir("drill_cli_snapshots");
  const auto block = (dir / "block.vtu").string();
  ASSERT_EQ(test::run_tool("tetmesh --shape block:12,12,6,2 -o " + block).exit_code, 0);
  {
    // Top face at z = 6, burr r = 1.5: in the air until t ≈ 0.29 s (centre above z = 7.5),
    // then down to z = 4.5 and sideways until 0.8 s.
    std::ofstream f(dir / "path.csv");
    f << "t,x,y,z\n0,6,6,10\n0.25,6,6,8\n0.5,6,6,4.5\n0.8,9,7,4.5\n";
  }
  const auto shots = dir / "pictures";
  std::filesystem::create_directories(shots);
  { std::ofstream(shots / "snapshot_0099.png") << "stale"; }  // an earlier run's picture goes
  { std::ofstream(shots / "notes.txt") << "kept"; }
  const auto r = drill_burr_1_5(block, dir, "out.vtu",
                                " --report " + (dir / "r.json").string() + " --max-depth 3 --snapshots " + shots.string() +
                                    " --snapshot-every 0.1 --snapshot-size 160x120");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "r.json");
  const auto rep = nlohmann::json::parse(in);
  // Pictures at t = 0, 0.1, …, 0.8 s: duration / period + 1.
  ASSERT_EQ(rep["snapshots"].size(), 9U);
  EXPECT_FALSE(std::filesystem::exists(shots / "snapshot_0099.png"));
  EXPECT_TRUE(std::filesystem::exists(shots / "notes.txt"));
  std::vector<std::vector<std::uint8_t>> pictures;
  for (std::size_t k = 0; k < 9; ++k) {
    const std::filesystem::path p = rep["snapshots"][k].get<std::string>();
    char name[32];
    std::snprintf(name, sizeof name, "snapshot_%04zu.png", k);
    EXPECT_EQ(p.filename().string(), name);
    std::ifstream f(p, std::ios::binary);
    char magic[8] = {};
    f.read(magic, 8);
    ASSERT_EQ(std::string(magic, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
    test::Png png = test::read_png(p);
    ASSERT_EQ(png.w, 160);
    ASSERT_EQ(png.h, 120);
    pictures.push_back(std::move(png.rgba));
  }
  // Before the burr touches (t = 0, 0.1, 0.2 s) nothing changes: identical pictures.
  EXPECT_EQ(differing_pixels(pictures[0], pictures[1]), 0U);
  EXPECT_EQ(differing_pixels(pictures[1], pictures[2]), 0U);
  // While it cuts (plunge, then sideways) every picture differs from the one before, and the
  // drilled block differs from the intact one in a region of visible size.
  for (std::size_t k = 4; k < 9; ++k) EXPECT_GT(differing_pixels(pictures[k - 1], pictures[k]), 0U) << "picture " << k;
  EXPECT_GT(differing_pixels(pictures[0], pictures[8]), 100U);
  const double removed = rep["removed_volume_mm3"];
  EXPECT_GT(removed, 0.5 * 4.0 / 3.0 * kPi * 1.5 * 1.5 * 1.5);
  // Bad snapshot arguments: exit 2 naming the option.
  auto bad = drill_burr_1_5(block, dir, "o2.vtu", " --snapshots " + shots.string() + " --snapshot-every 0");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--snapshot-every"), std::string::npos);
  bad = drill_burr_1_5(block, dir, "o2.vtu", " --snapshots " + (dir / "path.csv").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("not a folder"), std::string::npos);
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
  {
    std::ofstream f(dir / "path.csv");
    f << "t,x,y,z\n0,0.5,0.5,2\n0.1,0.5,0.5,1.5\n";
  }
  for (const char* priority : {"-1", "100"}) {
    r = test::run_tool("drill " + (dir / "c.vtu").string() + " --tool sphere:radius=0.3 --path " + (dir / "path.csv").string() +
                       " -o " + (dir / "o.vtu").string() + " --haptic-priority " + priority);
    EXPECT_EQ(r.exit_code, 2) << priority;
    EXPECT_NE(r.err.find("--haptic-priority"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "o.vtu"));
  }
  r = test::run_tool("drill " + (dir / "c.vtu").string() + " --tool sphere:radius=0.3 --path " + (dir / "path.csv").string() +
                     " -o " + (dir / "o.vtu").string() + " --surface-threads -2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--surface-threads"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.vtu"));
}

// A bad path CSV, option or output: exit 2, one line on stderr naming @p what, and none of
// the run's outputs (in @p dir: out.vtu, s.vtp, r.json) left behind.
void expect_refused(const test::CommandResult& r, const std::filesystem::path& dir, const std::string& what) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const char* f : {"out.vtu", "s.vtp", "r.json"}) EXPECT_FALSE(std::filesystem::exists(dir / f)) << f;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().rfind(".tmp-", 0), std::string::npos) << e.path();
}

TEST(DrillCli, PathCsvIsCheckedLineByLine) {
  const auto dir = test::scratch_dir("drill_cli_path_csv");
  const auto block = block_and_path(dir, "block:8,8,4,2", "0,4,4,6\n");
  const std::string outputs = " --surface " + (dir / "s.vtp").string() + " --report " + (dir / "r.json").string();
  // A first line with numbers and a name is data with a bad field, not a header.
  std::ofstream(dir / "path.csv") << "0,10,10,abc\n1,10,10,5\n";
  expect_refused(drill_burr_1_5(block, dir, "out.vtu", outputs), dir, "path.csv:1");
  std::ofstream(dir / "path.csv") << "t,x,y,z\n0,4,4,6\n0.2,4,4,x\n";
  expect_refused(drill_burr_1_5(block, dir, "out.vtu", outputs), dir, "path.csv:3");
  // A last time of 1e30 s would be played in real time for ever: refused, naming the line.
  std::ofstream(dir / "path.csv") << "t,x,y,z\n0,4,4,6\n1e30,4,4,3\n";
  const auto r = drill_burr_1_5(block, dir, "out.vtu", outputs);
  expect_refused(r, dir, "path.csv:3");
  EXPECT_NE(r.err.find("3600"), std::string::npos) << r.err;
  // A header of names only is still taken.
  std::ofstream(dir / "path.csv") << "time,x,y,z\n0,4,4,6\n0.1,4,4,5\n";
  EXPECT_EQ(drill_burr_1_5(block, dir, "out.vtu", " --max-depth 2").exit_code, 0);
}

TEST(DrillCli, MinSizeBeyondTheHierarchyIsRefused) {
  const auto dir = test::scratch_dir("drill_cli_min_size");
  const auto block = block_and_path(dir, "block:8,8,4,2", "0,4,4,6\n0.1,4,4,5\n");
  const auto r = drill_burr_1_5(block, dir, "out.vtu", " --min-size 1e-6 --report " + (dir / "r.json").string());
  // Cells of 2 mm: tetrahedra 3.46 mm across need depth 22 for 1e-6 mm; 10 are allowed,
  // so at least 3.46 / 1024 = 0.00338 mm.
  expect_refused(r, dir, "--min-size");
  EXPECT_NE(r.err.find("depth 22"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0.00338"), std::string::npos) << r.err;
}

TEST(DrillCli, OutputsAreCheckedBeforeTheWorkAndWrittenAllOrNone) {
  const auto dir = test::scratch_dir("drill_cli_outputs");
  const auto block = block_and_path(dir, "block:8,8,4,2", "0,4,4,6\n0.1,4,4,5\n");
  // An output that cannot be written is named before anything else is read: with the mesh
  // missing too, the error is about the output, and no other output appears.
  const auto missing = (dir / "missing.vtu").string();
  auto r = test::run_tool("drill " + missing + " --tool sphere:radius=1.5 --path " + (dir / "path.csv").string() + " -o " +
                          (dir / "out.vtu").string() + " --surface /proc/x.vtp --report " + (dir / "r.json").string());
  expect_refused(r, dir, "/proc/x.vtp");
  r = test::run_tool("drill " + missing + " --tool sphere:radius=1.5 --path " + (dir / "path.csv").string() +
                     " -o /proc/x.vtu --surface " + (dir / "s.vtp").string() + " --report " + (dir / "r.json").string());
  expect_refused(r, dir, "/proc/x.vtu");
  r = drill_burr_1_5(block, dir, "out.vtu", " --surface " + (dir / "nowhere" / "s.vtp").string());
  expect_refused(r, dir, "nowhere");
}

// `/usr/bin/python3 tests/drill/vtk_surface_check.py FILE` (VTK's vtkFeatureEdges and
// vtkMassProperties), or nullopt without python3-vtk9.
std::optional<nlohmann::json> vtk_surface_check(const std::filesystem::path& file) {
  static const bool have_vtk = std::system("/usr/bin/python3 -c 'import vtkmodules.vtkIOXML' >/dev/null 2>&1") == 0;
  if (!have_vtk) return std::nullopt;
  const std::string cmd = "/usr/bin/python3 '" + (test::source_dir() / "tests/drill/vtk_surface_check.py").string() + "' '" +
                          file.string() + "' 2>/dev/null";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  std::string text;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) text.append(buf, n);
  ::pclose(pipe);
  return nlohmann::json::parse(text);
}

// Grooves that leave and re-enter the block (random paths) and a hole through a 2 mm plate:
// VTK finds the drilled surfaces closed and edge-manifold, enclosing the remaining volume;
// the session ends at the path's end with the backlog done, prints one summary line, and the
// report's memory breakdown lies within the process's peak.
TEST(DrillCli, DrilledSurfacesAreClosedManifoldsForVtk) {
  const auto dir = test::scratch_dir("drill_cli_manifold");
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    const bool plate = seed == 4;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::string rows;
    if (plate) {
      rows = "0,5,5,4\n0.2,5,5,-2\n0.3,5,5,4\n0.4,7,6,4\n0.6,7,6,-2\n";
    } else {
      for (int k = 0; k < 5; ++k)
        rows += fmt::format("{},{:.3f},{:.3f},{:.3f}\n", 0.1 * k, 12 * u(rng), 10 * u(rng),
                            k % 2 == 0 ? 6.0 + 1.0 * u(rng) : 6.0 - 1.5 * u(rng));
    }
    const auto block = block_and_path(dir, plate ? "block:10,10,2,1" : "block:12,10,6,2", rows);
    const auto r = drill_burr_1_5(block, dir, "out.vtu",
                                  " --surface " + (dir / "s.vtp").string() + " --report " + (dir / "r.json").string() +
                                      " --max-depth 4 --force-threshold 0");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // One summary line.
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_EQ(r.out.rfind("drilled ", 0), 0U) << r.out;
    std::ifstream in(dir / "r.json");
    const auto rep = nlohmann::json::parse(in);
    EXPECT_TRUE(rep["session_end"]["path_finished"].get<bool>());
    EXPECT_EQ(rep["session_end"]["backlog_left_positions"].get<int>(), 0);
    const auto& mem = rep["memory"];
    const std::size_t parts = mem["nodes_bytes"].get<std::size_t>() + mem["v_lists_bytes"].get<std::size_t>() +
                              mem["hash_bytes"].get<std::size_t>() + mem["buffers_bytes"].get<std::size_t>();
    for (const char* key : {"nodes_bytes", "v_lists_bytes", "hash_bytes", "buffers_bytes", "surface_mesh_bytes", "leaf_mesh_bytes"})
      EXPECT_GT(mem[key].get<std::size_t>(), 0U) << key;
    // The breakdown is taken at the session's end, so it lies within the session's peak, and
    // that within the whole process's.
    EXPECT_LE(parts, mem["session_peak_rss_bytes"].get<std::size_t>());
    EXPECT_LE(mem["session_peak_rss_bytes"].get<std::size_t>(), mem["peak_rss_bytes"].get<std::size_t>());
    EXPECT_LE(parts + mem["other_bytes"].get<std::size_t>(), mem["peak_rss_bytes"].get<std::size_t>());
    const double remaining = rep["remaining_volume_mm3"];
    const auto own = geometry::check_mesh(io::read_triangle_mesh(dir / "s.vtp"));
    EXPECT_TRUE(own.closed);
    EXPECT_EQ(own.non_manifold_edges, 0U);
    EXPECT_EQ(own.non_manifold_vertices, 0U);
    EXPECT_TRUE(test::rel_near(own.signed_volume_mm3, remaining, 1e-9));
    const auto vtk = vtk_surface_check(dir / "s.vtp");
    if (!vtk) GTEST_SKIP() << "python3-vtk9 not available";
    EXPECT_EQ((*vtk)["boundary_edges"].get<int>(), 0);
    EXPECT_EQ((*vtk)["non_manifold_edges"].get<int>(), 0);
    EXPECT_TRUE(test::rel_near((*vtk)["volume"].get<double>(), remaining, 1e-6));
  }
  // -q: no summary line.
  const auto q = drill_burr_1_5((dir / "block.vtu").string(), dir, "out.vtu", " --max-depth 2 -q");
  ASSERT_EQ(q.exit_code, 0) << q.err;
  EXPECT_TRUE(q.out.empty()) << q.out;
}

}  // namespace
}  // namespace ido::drill

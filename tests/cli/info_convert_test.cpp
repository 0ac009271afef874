// SPDX-License-Identifier: Apache-2.0
// `ido info` and `ido convert`, run as the built tool.
#include <fstream>

#include <nlohmann/json.hpp>

#include "../io/catalogue.h"
#include "../io/dicom_writer.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "support/test_support.h"

namespace ido::cli {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

geometry::TetMesh unit_tet() {
  geometry::TetMesh m;
  m.vertices = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
  m.tets = {{0, 1, 2, 3}};
  return m;
}

// The whole catalogue through the CLI: exit 2 and one stderr line naming the file.
TEST(CliInfo, BadInputCatalogueExitsTwoWithOneLine) {
  const auto dir = test::fixtures_dir() / "bad";
  for (const auto& bad : test::bad_catalogue()) {
    SCOPED_TRACE(bad.file);
    const auto r = test::run_tool("info " + q(dir / bad.file));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find((dir / bad.file).string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(bad.fragment), std::string::npos) << r.err;
    // In ido's words: no ITK object pointers, teem chains or library prefixes.
    for (const char* internal : {"0x", "ITK ERROR", "[nrrd]", "nifti_", "json.exception", "internal error"})
      EXPECT_EQ(r.err.find(internal), std::string::npos) << internal << " in: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

TEST(CliInfo, MixedDicomFolderExitsTwo) {
  const auto dir = test::scratch_dir("cli-mixed-dicom");
  test::write_tiny_dicom_series(dir, "1.2.826.0.1.3680043.2.1125.9.1", "a", 2);
  test::write_tiny_dicom_series(dir, "1.2.826.0.1.3680043.2.1125.9.2", "b", 2);
  const auto r = test::run_tool("info " + q(dir));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("2 DICOM series"), std::string::npos) << r.err;
}

TEST(CliInfo, TetMeshJsonHasCountsBoundsAndChecks) {
  const auto dir = test::scratch_dir("cli-info-tet");
  io::write_tet_mesh(dir / "t.vtu", unit_tet());
  const auto r = test::run_tool("info --json " + q(dir / "t.vtu"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = json::parse(r.out);
  EXPECT_EQ(j["kind"], "tet_mesh");
  EXPECT_EQ(j["vertices"], 4);
  EXPECT_EQ(j["tets"], 1);
  EXPECT_EQ(j["bounds_max_mm"], json::array({2.0, 2.0, 2.0}));
  EXPECT_TRUE(test::near(j["checks"]["volume_mm3"].get<double>(), 8.0 / 6.0, 1e-12));
  EXPECT_EQ(j["checks"]["inverted"], 0);
  EXPECT_EQ(j["checks"]["boundary_faces"], 4);
  EXPECT_EQ(j["checks"]["boundary_closed"], true);
}

TEST(CliInfo, VolumeJsonHasGridAndStatistics) {
  const auto dir = test::scratch_dir("cli-info-vol");
  image::Volume<std::int16_t> v(Index3{10, 10, 1}, Vec3(0.5, 0.5, 3.0), Vec3(1, 2, 3));
  for (std::size_t n = 0; n < 100; ++n) v.data()[n] = static_cast<std::int16_t>(n);  // 0..99
  io::write_volume(dir / "v.nii.gz", v);
  const auto r = test::run_tool("info --json " + q(dir / "v.nii.gz"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = json::parse(r.out);
  EXPECT_EQ(j["size"], json::array({10, 10, 1}));
  EXPECT_EQ(j["spacing_mm"], json::array({0.5, 0.5, 3.0}));
  EXPECT_EQ(j["pixel_type"], "short");
  EXPECT_EQ(j["min"], 0.0);
  EXPECT_EQ(j["max"], 99.0);
  EXPECT_TRUE(test::near(j["mean"].get<double>(), 49.5, 1e-12));
  // ido::percentile on 0..99 (numpy.percentile's values): p50 = 49.5, p95 = 94.05.
  EXPECT_TRUE(test::near(j["percentiles"]["p50"].get<double>(), 49.5, 1e-12));
  EXPECT_TRUE(test::near(j["percentiles"]["p95"].get<double>(), 94.05, 1e-9));
  // The text form names the same things.
  const auto t = test::run_tool("info " + q(dir / "v.nii.gz"));
  EXPECT_EQ(t.exit_code, 0);
  EXPECT_NE(t.out.find("spacing_mm: 0.5 × 0.5 × 3"), std::string::npos) << t.out;
}

TEST(CliConvert, MeshFormatsRoundTrip) {
  const auto dir = test::scratch_dir("cli-convert-mesh");
  io::write_tet_mesh(dir / "t.vtu", unit_tet());
  ASSERT_EQ(test::run_tool("convert " + q(dir / "t.vtu") + " " + q(dir / "t.msh")).exit_code, 0);
  ASSERT_EQ(test::run_tool("convert --gmsh2 " + q(dir / "t.msh") + " " + q(dir / "t2.node")).exit_code, 0);
  const auto back = io::read_tet_mesh(dir / "t2.ele");
  EXPECT_EQ(back.tets, unit_tet().tets);
  EXPECT_EQ(back.vertices, unit_tet().vertices);
  // A tetrahedral mesh cannot become an STL: exit 2 naming the output.
  const auto r = test::run_tool("convert " + q(dir / "t.vtu") + " " + q(dir / "t.stl"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("t.stl"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "t.stl"));
}

// A Gmsh file may hold a surface: info and convert see it as a triangle mesh, not as a
// tetrahedral mesh without tetrahedra.
TEST(CliConvert, TriangleGmshFileIsASurface) {
  const auto dir = test::scratch_dir("cli-convert-trimsh");
  geometry::TriangleMesh tetra_surface;
  tetra_surface.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra_surface.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  io::write_triangle_mesh(dir / "s.stl", tetra_surface);
  ASSERT_EQ(test::run_tool("convert " + q(dir / "s.stl") + " " + q(dir / "s.msh")).exit_code, 0);
  const auto info = test::run_tool("info --json " + q(dir / "s.msh"));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto j = json::parse(info.out);
  EXPECT_EQ(j["kind"], "triangle_mesh") << info.out;
  EXPECT_EQ(j["triangles"], 4) << info.out;
  const auto back = test::run_tool("convert " + q(dir / "s.msh") + " " + q(dir / "s2.ply"));
  ASSERT_EQ(back.exit_code, 0) << back.err;
  // STL welds its corners in order of appearance: compare with what the STL reads as.
  const auto from_stl = io::read_triangle_mesh(dir / "s.stl");
  const auto through_msh = io::read_triangle_mesh(dir / "s2.ply");
  EXPECT_EQ(through_msh.triangles, from_stl.triangles);
  EXPECT_EQ(through_msh.vertices, from_stl.vertices);
}

// The global -q / -v flags work after the subcommand too.
TEST(CliInfo, GlobalFlagsAfterTheSubcommand) {
  const auto dir = test::scratch_dir("cli-info-flags");
  io::write_tet_mesh(dir / "t.vtu", unit_tet());
  EXPECT_EQ(test::run_tool("info " + q(dir / "t.vtu") + " -q").exit_code, 0);
  EXPECT_EQ(test::run_tool("info --verbose " + q(dir / "t.vtu")).exit_code, 0);
  const auto bad = test::run_tool("info " + q(dir / "t.vtu") + " --no-such-flag");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--no-such-flag"), std::string::npos) << bad.err;
}

TEST(CliConvert, VolumeKeepsGridValuesAndType) {
  const auto dir = test::scratch_dir("cli-convert-vol");
  image::Volume<std::uint8_t> v(Index3{4, 3, 2}, Vec3(0.5, 0.75, 2.0), Vec3(-1, 2, 5));
  for (std::size_t n = 0; n < v.voxel_count(); ++n) v.data()[n] = static_cast<std::uint8_t>(n * 7);
  io::write_volume(dir / "m.mha", v);
  ASSERT_EQ(test::run_tool("convert " + q(dir / "m.mha") + " " + q(dir / "m.nrrd")).exit_code, 0);
  io::VolumeFileInfo info;
  const auto back = io::read_volume(dir / "m.nrrd", &info);
  EXPECT_EQ(info.pixel_type, "unsigned_char");
  ASSERT_TRUE(back.same_grid(v));
  for (std::size_t n = 0; n < v.voxel_count(); ++n) EXPECT_EQ(back.data()[n], float(v.data()[n]));
}

TEST(CliData, AbdomenSeriesInfoAndConversion) {
  IDO_REQUIRE_SHARED_DATA();
  const auto series = *test::shared_data_dir() / "abdomen-dicom/series";
  const auto r = test::run_tool("info --json " + q(series));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = json::parse(r.out);
  EXPECT_EQ(j["size"], json::array({512, 512, 20}));
  EXPECT_TRUE(test::near(j["spacing_mm"][0].get<double>(), 0.977, 5e-4));
  EXPECT_TRUE(test::near(j["spacing_mm"][1].get<double>(), 0.977, 5e-4));
  EXPECT_TRUE(test::near(j["spacing_mm"][2].get<double>(), 2.0, 1e-6));
  EXPECT_EQ(j["format"], "DICOM");
  const auto dir = test::scratch_dir("cli-convert-dicom");
  const auto c = test::run_tool("convert " + q(series) + " " + q(dir / "ct.nii.gz"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  io::VolumeFileInfo info;
  const auto ct = io::read_volume(dir / "ct.nii.gz", &info);
  EXPECT_EQ(info.pixel_type, "short");  // HU stay integers: int16, not float
  EXPECT_TRUE(ct.same_grid(io::read_volume(series), 1e-4));
}

}  // namespace
}  // namespace ido::cli

namespace ido::cli {
namespace {

// `ido info` lists in reading order — what the file is, its size and geometry, then the
// statistics (p5 before p25) — in text and JSON alike.
TEST(CliInfo, ListsInReadingOrder) {
  const auto dir = test::scratch_dir("cli-info-order");
  image::Volume<std::int16_t> v(Index3{10, 10, 2}, Vec3(0.5, 0.5, 3.0), Vec3(1, 2, 3));
  for (std::size_t n = 0; n < v.data().size(); ++n) v.data()[n] = static_cast<std::int16_t>(n);
  io::write_volume(dir / "v.nii.gz", v);
  const std::vector<std::string> order = {"file", "kind", "format", "size", "spacing_mm", "origin_mm", "voxels",
                                          "min", "max", "mean", "percentiles", "p1", "p5", "p25", "p50", "p99"};
  const auto text = test::run_tool("info " + q(dir / "v.nii.gz"));
  ASSERT_EQ(text.exit_code, 0) << text.err;
  const auto json_out = test::run_tool("info --json " + q(dir / "v.nii.gz"));
  ASSERT_EQ(json_out.exit_code, 0) << json_out.err;
  for (const auto* out : {&text.out, &json_out.out}) {
    std::size_t last = 0;
    for (const auto& key : order) {
      // Text lines start with "key:" (indented under percentiles), JSON with "\"key\":".
      const std::string needle = out == &text.out ? key + ":" : "\"" + key + "\":";
      const auto at = out->find(needle, last);
      ASSERT_NE(at, std::string::npos) << key << " missing or out of order in:\n" << *out;
      last = at;
    }
  }
}

// A tetrahedral mesh with an inverted (or flat) tetrahedron is read, and the check reports
// it: simulation frames can hold such elements and must read back.
TEST(CliInfo, InvertedAndDegenerateTetrahedraAreReadAndCounted) {
  const auto bad = test::fixtures_dir() / "bad";
  for (const auto& [file, key] : {std::pair{"inverted.vtu", "inverted"}, std::pair{"inverted.ele", "inverted"},
                                  std::pair{"degenerate.vtu", "degenerate"}}) {
    SCOPED_TRACE(file);
    const auto r = test::run_tool("info --json " + q(bad / file));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = json::parse(r.out);
    EXPECT_EQ(j["checks"][key], 1) << r.out;
  }
  // A frame with an inverted tetrahedron converts and reads back unchanged.
  const auto dir = test::scratch_dir("cli-info-inverted");
  geometry::TetMesh m = unit_tet();
  std::swap(m.tets[0][1], m.tets[0][2]);
  io::write_tet_mesh(dir / "frame.vtu", m);
  ASSERT_EQ(test::run_tool("convert " + q(dir / "frame.vtu") + " " + q(dir / "frame.msh")).exit_code, 0);
  const auto back = io::read_tet_mesh(dir / "frame.msh");
  EXPECT_EQ(back.tets, m.tets);
  const auto r = test::run_tool("info --json " + q(dir / "frame.msh"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["checks"]["inverted"], 1) << r.out;
}

}  // namespace
}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
// file_kind (by extension, a folder being DICOM, a Gmsh file read to tell tetrahedra from
// triangles) and volume_statistics (range, mean, population σ, ido's one percentile).
#include "ido/io/file_info.h"

#include <cmath>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/core/statistics.h"
#include "ido/io/mesh_io.h"
#include "support/test_support.h"

namespace ido::io {
namespace {

namespace fs = std::filesystem;

TEST(FileKind, ExtensionsNameTheKind) {
  // Only the name matters for these: the files need not exist.
  const fs::path dir = test::scratch_dir("file_kind_names");
  for (const char* name : {"ct.nii", "ct.nii.gz", "ct.nrrd", "ct.nhdr", "ct.mha", "ct.mhd"})
    EXPECT_EQ(file_kind(dir / name), FileKind::Volume) << name;
  for (const char* name : {"s.stl", "s.obj", "s.ply", "s.vtp", "S.STL", "s.Obj"})
    EXPECT_EQ(file_kind(dir / name), FileKind::TriangleMesh) << name;
  for (const char* name : {"m.vtu", "m.node", "m.ele", "M.VTU"}) EXPECT_EQ(file_kind(dir / name), FileKind::TetMesh) << name;
}

TEST(FileKind, FoldersAreDicomUnlessNamedLikeAMesh) {
  const fs::path dir = test::scratch_dir("file_kind_folders");
  fs::create_directories(dir / "series");
  fs::create_directories(dir / "surface.stl");
  fs::create_directories(dir / "mesh.vtu");
  EXPECT_EQ(file_kind(dir / "series"), FileKind::Volume);
  EXPECT_EQ(file_kind(dir / "surface.stl"), FileKind::TriangleMesh);
  EXPECT_EQ(file_kind(dir / "mesh.vtu"), FileKind::TetMesh);
}

TEST(FileKind, GmshFilesAreReadToTellTetrahedraFromTriangles) {
  const fs::path dir = test::scratch_dir("file_kind_msh");
  geometry::TetMesh tets;
  tets.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  tets.tets = {{0, 1, 2, 3}};
  geometry::TriangleMesh tris;
  tris.vertices = tets.vertices;
  tris.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const bool v2 : {false, true}) {
    const std::string suffix = v2 ? "_v2.msh" : "_v4.msh";
    write_tet_mesh(dir / ("volume" + suffix), tets, {.gmsh_v2 = v2});
    write_triangle_mesh(dir / ("surface" + suffix), tris, {.gmsh_v2 = v2});
    EXPECT_EQ(file_kind(dir / ("volume" + suffix)), FileKind::TetMesh) << suffix;
    EXPECT_EQ(file_kind(dir / ("surface" + suffix)), FileKind::TriangleMesh) << suffix;
  }
  // A .msh that is not Gmsh: the parser's error, naming the file.
  std::ofstream(dir / "junk.msh") << "hello\n";
  try {
    (void)file_kind(dir / "junk.msh");
    FAIL() << "junk.msh accepted";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), (dir / "junk.msh").string());
  }
}

TEST(FileKind, UnknownOrMissingFilesAreIoErrorsNamingThePath) {
  const fs::path dir = test::scratch_dir("file_kind_unknown");
  std::ofstream(dir / "notes.txt") << "text\n";
  try {
    (void)file_kind(dir / "notes.txt");
    FAIL() << "notes.txt accepted";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), (dir / "notes.txt").string());
    EXPECT_NE(e.problem().find("unknown file type"), std::string::npos) << e.what();
  }
  try {
    (void)file_kind(dir / "absent.xyz");
    FAIL() << "absent.xyz accepted";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), (dir / "absent.xyz").string());
    EXPECT_NE(e.problem().find("no such file"), std::string::npos) << e.what();
  }
}

TEST(VolumeStatistics, UniformRampHasItsAnalyticMoments) {
  // Voxel values 1 … 120 in a 4 × 5 × 6 grid: mean (n + 1)/2, population variance (n² − 1)/12.
  image::Volume<float> v({4, 5, 6}, Vec3(0.5, 1, 2));
  const std::size_t n = v.voxel_count();
  for (std::size_t i = 0; i < n; ++i) v.data()[i] = float(i + 1);
  const VolumeStatistics s = volume_statistics(v);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 120.0);
  EXPECT_TRUE(test::near(s.mean, 60.5, 1e-12));
  EXPECT_TRUE(test::near(s.stddev, std::sqrt((120.0 * 120.0 - 1.0) / 12.0), 1e-9));
  // The seven percentiles, in order, each ido::percentile's (linear between order
  // statistics at rank q (n − 1)): 1 + q · 119 for this ramp.
  ASSERT_EQ(s.percentiles.size(), 7U);
  const double ps[] = {1, 5, 25, 50, 75, 95, 99};
  std::vector<double> values(v.data().begin(), v.data().end());
  for (std::size_t k = 0; k < 7; ++k) {
    EXPECT_EQ(s.percentiles[k].first, ps[k]);
    EXPECT_TRUE(test::near(s.percentiles[k].second, 1.0 + ps[k] / 100.0 * 119.0, 1e-9)) << ps[k];
    EXPECT_TRUE(test::near(s.percentiles[k].second, percentile(values, ps[k] / 100.0), 1e-9)) << ps[k];
  }
}

TEST(VolumeStatistics, ConstantVolumeAndEmptyVolume) {
  const image::Volume<float> flat({3, 3, 3}, Vec3(1, 1, 1), Vec3::Zero(), Mat3::Identity(), -1000.0f);
  const VolumeStatistics s = volume_statistics(flat);
  EXPECT_EQ(s.min, -1000.0);
  EXPECT_EQ(s.max, -1000.0);
  EXPECT_EQ(s.mean, -1000.0);
  EXPECT_EQ(s.stddev, 0.0);
  for (const auto& [p, value] : s.percentiles) EXPECT_EQ(value, -1000.0) << p;
  try {
    (void)volume_statistics(image::Volume<float>{});
    FAIL() << "empty volume accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ido::io

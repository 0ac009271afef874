// SPDX-License-Identifier: Apache-2.0
// `ido render` end to end: the built tool reads files and writes a PNG.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/geometry/primitives.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "support/png_read.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(RenderCli, SurfaceToPng) {
  const auto dir = test::scratch_dir("render_cli_surface");
  io::write_triangle_mesh(dir / "sphere.stl", geometry::icosphere(Vec3(1, 2, 3), 5.0, 3));
  const auto r = test::run_tool("render " + (dir / "sphere.stl").string() + " -o " +
                                (dir / "pic.png").string() + " --size 120x90 --camera 10,20 --ortho");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const test::Png png = test::read_png(dir / "pic.png");
  ASSERT_EQ(png.w, 120);
  ASSERT_EQ(png.h, 90);
  int covered = 0;
  for (std::size_t i = 0; i < png.rgba.size(); i += 4)
    covered += (png.rgba[i] != 255 || png.rgba[i + 1] != 255 || png.rgba[i + 2] != 255);
  // the fitted camera frames the sphere's bounding box (half-diagonal √3·5 mm, 5 % margin)
  // in 90 px: the disc has radius 5 / (1.05·√3·5) · 45 px ≈ 24.7 px, about 1920 pixels
  const double expected = kPi * std::pow(45.0 / (1.05 * std::sqrt(3.0)), 2);
  EXPECT_TRUE(test::rel_near(covered, expected, 0.05));
}

TEST(RenderCli, SliceWithOverlay) {
  const auto dir = test::scratch_dir("render_cli_slice");
  image::Volume<float> ct({32, 24, 10}, Vec3::Constant(1.0));
  image::Volume<float> mask = ct.like<float>(0);
  for (std::int64_t k = 0; k < 10; ++k)
    for (std::int64_t j = 0; j < 24; ++j)
      for (std::int64_t i = 0; i < 32; ++i) {
        const bool in = (i - 16) * (i - 16) + (j - 12) * (j - 12) < 49;
        mask(i, j, k) = in ? 1.f : 0.f;
        ct(i, j, k) = in ? 200.f : -50.f;
      }
  io::write_volume(dir / "ct.nii.gz", ct);
  io::write_volume(dir / "mask.nii.gz", mask);
  const auto r = test::run_tool("render " + (dir / "ct.nii.gz").string() + " -o " +
                                (dir / "slice.png").string() + " --slice k:5 --size 32x24 --overlay " +
                                (dir / "mask.nii.gz").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const test::Png png = test::read_png(dir / "slice.png");
  ASSERT_EQ(png.w, 32);
  int contour = 0;
  for (std::size_t i = 0; i < png.rgba.size(); i += 4) {
    const bool red = png.rgba[i] > 200 && png.rgba[i + 1] < 100 && png.rgba[i + 2] < 100;
    contour += red;
  }
  EXPECT_GT(contour, 20);   // the ring of a radius-7 disc
  EXPECT_LT(contour, 80);
}

TEST(RenderCli, BadInputExitsWithTwo) {
  const auto dir = test::scratch_dir("render_cli_bad");
  auto r = test::run_tool("render " + (dir / "missing.stl").string() + " -o " + (dir / "x.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.stl"), std::string::npos) << r.err;
  io::write_triangle_mesh(dir / "s.stl", geometry::icosphere(Vec3::Zero(), 1.0, 1));
  r = test::run_tool("render " + (dir / "s.stl").string() + " -o " + (dir / "x.png").string() +
                     " --size 0x10");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--size"), std::string::npos) << r.err;
  r = test::run_tool("render " + (dir / "s.stl").string() + " -o " + (dir / "x.png").string() +
                     " --camera 10");
  EXPECT_EQ(r.exit_code, 2);
  r = test::run_tool("render " + (dir / "notes.txt").string() + " -o " + (dir / "x.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

// A simulation frame may hold inverted tetrahedra, and `ido render` draws it (issue 30).
// Swapping two vertices of a tetrahedron inverts it without moving anything, so the picture
// covers exactly the pixels of the upright mesh's; a tetrahedron whose apex went through its
// base (as in a diverging frame) is drawn too.
TEST(RenderCli, InvertedTetrahedraAreDrawn) {
  const auto dir = test::scratch_dir("render_cli_inverted");
  geometry::TetMesh upright;
  upright.vertices = {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), Vec3(0, 0, 10), Vec3(10, 10, 10)};
  upright.tets = {{0, 1, 2, 3}, {1, 2, 4, 3}};
  geometry::TetMesh inverted = upright;
  std::swap(inverted.tets[0][1], inverted.tets[0][2]);
  geometry::TetMesh through = upright;
  through.vertices[3] = Vec3(2, 2, -6);  // the first tetrahedron's apex below its base
  auto covered = [&](const geometry::TetMesh& mesh, const std::string& name) {
    io::write_tet_mesh(dir / (name + ".vtu"), mesh);
    const auto r = test::run_tool("render " + (dir / (name + ".vtu")).string() + " -o " +
                                  (dir / (name + ".png")).string() + " --size 120x90 --camera 30,20");
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    std::vector<bool> mask;
    if (r.exit_code != 0) return mask;
    const test::Png png = test::read_png(dir / (name + ".png"));
    for (int y = 0; y < png.h; ++y)
      for (int x = 0; x < png.w; ++x) mask.push_back(!png.background(x, y));
    return mask;
  };
  const auto a = covered(upright, "upright"), b = covered(inverted, "inverted"), c = covered(through, "through");
  ASSERT_EQ(a.size(), 120u * 90u);
  EXPECT_GT(std::count(a.begin(), a.end(), true), 1000);
  EXPECT_EQ(a, b);
  EXPECT_GT(std::count(c.begin(), c.end(), true), 1000);
}

}  // namespace
}  // namespace ido

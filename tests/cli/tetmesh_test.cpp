// SPDX-License-Identifier: Apache-2.0
// `ido tetmesh`, run as the built tool: a sphere given as a mask, a closed surface and a
// signed distance field is meshed with the analytic volume, positive tetrahedra, stuffing's
// dihedral bounds and a closed boundary; bad input exits 2 and writes nothing.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <nlohmann/json.hpp>

#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/primitives.h"
#include "ido/geometry/tet_quality.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "ido/meshing/tetrahedralize.h"
#include "support/test_support.h"

namespace ido::cli {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

constexpr double kRadius = 10.0;  // mm
const double kSphereVolume = 4.0 / 3.0 * std::numbers::pi * kRadius * kRadius * kRadius;

// A 0.4 mm grid around a sphere of radius kRadius centred at (1, -2, 3); value(p) gives the
// voxel value from the signed distance to the sphere.
template <typename F>
image::Volume<float> sphere_volume(F value) {
  const double s = 0.4;
  const auto n = std::int64_t(std::ceil(2 * (kRadius + 2.0) / s));
  const Vec3 centre(1, -2, 3);
  image::Volume<float> v({n, n, n}, Vec3::Constant(s), centre - Vec3::Constant(kRadius + 2.0));
  for (std::int64_t k = 0; k < n; ++k)
    for (std::int64_t j = 0; j < n; ++j)
      for (std::int64_t i = 0; i < n; ++i) {
        const Vec3 p = v.index_to_world(Vec3(double(i), double(j), double(k)));
        v(i, j, k) = float(value((p - centre).norm() - kRadius));
      }
  return v;
}

// Properties every stuffed mesh has: positive tetrahedra, stuffing's proven dihedral bounds,
// a closed 2-manifold boundary of genus 0, and a report matching the mesh.
void expect_good_sphere_mesh(const fs::path& mesh_path, const fs::path& report_path,
                             double volume_tolerance) {
  const auto mesh = io::read_tet_mesh(mesh_path);  // reads inverted tetrahedra too: counted below
  const auto q = geometry::check_tet_mesh(mesh);
  EXPECT_EQ(q.inverted, 0u);
  EXPECT_EQ(q.degenerate, 0u);
  EXPECT_GE(q.min_dihedral_deg, meshing::kStuffingMinDihedralDeg - 0.2);
  EXPECT_LE(q.max_dihedral_deg, meshing::kStuffingMaxDihedralDeg);
  EXPECT_TRUE(test::rel_near(q.volume_mm3, kSphereVolume, volume_tolerance));
  const auto checks = geometry::check_mesh(geometry::tet_boundary(mesh));
  EXPECT_TRUE(checks.closed && checks.edge_manifold && checks.vertex_manifold && checks.oriented);
  EXPECT_EQ(checks.genus, std::optional<int>(0));

  std::ifstream in(report_path);
  ASSERT_TRUE(in) << report_path;
  const auto j = json::parse(in);
  EXPECT_EQ(j["tets"].get<std::size_t>(), mesh.tets.size());
  EXPECT_EQ(j["vertices"].get<std::size_t>(), mesh.vertices.size());
  EXPECT_TRUE(test::rel_near(j["volume_mm3"].get<double>(), q.volume_mm3, 1e-9));
  EXPECT_TRUE(test::near(j["min_dihedral_deg"].get<double>(), q.min_dihedral_deg, 1e-9));
  EXPECT_TRUE(test::near(j["max_dihedral_deg"].get<double>(), q.max_dihedral_deg, 1e-9));
}

TEST(CliTetmesh, SphereMaskMeshesToTheAnalyticVolume) {
  const auto dir = test::scratch_dir("cli-tetmesh-mask");
  // 0/1 mask stored as uint8: auto-detected as a mask.
  const auto v = sphere_volume([](double d) { return d < 0 ? 1.0 : 0.0; });
  auto mask = v.like<std::uint8_t>();
  for (std::size_t i = 0; i < v.data().size(); ++i) mask.data()[i] = std::uint8_t(v.data()[i]);
  io::write_volume(dir / "mask.nii.gz", mask);
  const auto r = test::run_tool("tetmesh " + q(dir / "mask.nii.gz") + " -o " + q(dir / "m.vtu") +
                                " --edge 0.8 --report " + q(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tetrahedra"), std::string::npos) << r.out;
  expect_good_sphere_mesh(dir / "m.vtu", dir / "r.json", 0.01);
}

TEST(CliTetmesh, LabelMapMeshesOneLabel) {
  const auto dir = test::scratch_dir("cli-tetmesh-label");
  // label 3 inside the sphere, label 7 in a shell around it, 0 elsewhere
  const auto v = sphere_volume([](double d) { return d < 0 ? 3.0 : (d < 1.5 ? 7.0 : 0.0); });
  io::write_volume(dir / "labels.nrrd", v);
  const auto r = test::run_tool("tetmesh " + q(dir / "labels.nrrd") + " --label 3 -o " +
                                q(dir / "m.msh") + " --edge 0.8 --report " + q(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_good_sphere_mesh(dir / "m.msh", dir / "r.json", 0.01);
}

TEST(CliTetmesh, SphereSurfaceMeshesToTheAnalyticVolume) {
  const auto dir = test::scratch_dir("cli-tetmesh-surface");
  io::write_triangle_mesh(dir / "s.stl", geometry::icosphere(Vec3(1, -2, 3), kRadius, 5));
  const auto r = test::run_tool("tetmesh " + q(dir / "s.stl") + " -o " + q(dir / "m.node") +
                                " --edge 0.8 --report " + q(dir / "r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_good_sphere_mesh(dir / "m.node", dir / "r.json", 0.01);
}

TEST(CliTetmesh, DistanceFieldAndGradedLattice) {
  const auto dir = test::scratch_dir("cli-tetmesh-field");
  io::write_volume(dir / "sdf.mha", sphere_volume([](double d) { return d; }));
  const auto uniform = test::run_tool("tetmesh " + q(dir / "sdf.mha") + " -o " +
                                      q(dir / "u.vtu") + " --edge 0.8 --report " + q(dir / "u.json"));
  ASSERT_EQ(uniform.exit_code, 0) << uniform.err;
  expect_good_sphere_mesh(dir / "u.vtu", dir / "u.json", 0.01);
  const auto graded = test::run_tool("tetmesh --field " + q(dir / "sdf.mha") + " --graded -o " +
                                     q(dir / "g.vtu") + " --edge 0.8 --report " + q(dir / "g.json"));
  ASSERT_EQ(graded.exit_code, 0) << graded.err;
  const auto g = io::read_tet_mesh(dir / "g.vtu");
  const auto gq = geometry::check_tet_mesh(g);
  EXPECT_EQ(gq.inverted, 0u);
  EXPECT_GE(gq.min_dihedral_deg, meshing::kGradedStuffingMinDihedralDeg - 0.2);
  EXPECT_LE(gq.max_dihedral_deg, meshing::kGradedStuffingMaxDihedralDeg);
  EXPECT_TRUE(test::rel_near(gq.volume_mm3, kSphereVolume, 0.01));
  EXPECT_TRUE(geometry::check_mesh(geometry::tet_boundary(g)).closed);
  EXPECT_LT(g.tets.size(), io::read_tet_mesh(dir / "u.vtu").tets.size());
}

TEST(CliTetmesh, ShapesStayAvailable) {
  const auto dir = test::scratch_dir("cli-tetmesh-shape");
  const auto r = test::run_tool("tetmesh --shape block:4,5,6,1 -o " + q(dir / "b.vtu"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto q_ = geometry::check_tet_mesh(io::read_tet_mesh(dir / "b.vtu"));
  EXPECT_TRUE(test::rel_near(q_.volume_mm3, 120.0, 1e-9));
}

TEST(CliTetmesh, BadInputExitsTwoAndWritesNothing) {
  const auto dir = test::scratch_dir("cli-tetmesh-bad");
  io::write_triangle_mesh(dir / "s.stl", geometry::icosphere(Vec3::Zero(), 5.0, 2));
  auto open = geometry::icosphere(Vec3::Zero(), 5.0, 2);
  open.triangles.pop_back();
  io::write_triangle_mesh(dir / "open.stl", open);
  image::Volume<std::uint8_t> empty({8, 8, 8}, Vec3::Constant(1.0));
  io::write_volume(dir / "empty.nii.gz", empty);
  image::Volume<std::int16_t> ct({8, 8, 8}, Vec3::Constant(1.0));
  for (std::size_t i = 0; i < ct.data().size(); ++i) ct.data()[i] = std::int16_t(i % 2 ? -1000 : 300);
  io::write_volume(dir / "ct.nii.gz", ct);
  std::ofstream(dir / "notes.txt") << "not a mesh\n";

  struct Case {
    std::string args;
    std::string fragment;  // expected in the error message
  };
  const fs::path out = dir / "out.vtu";
  const std::vector<Case> cases = {
      {q(dir / "notes.txt") + " -o " + q(out), "notes.txt"},
      {q(dir / "open.stl") + " -o " + q(out), "not closed"},
      {q(dir / "empty.nii.gz") + " -o " + q(out), "empty"},
      {q(dir / "ct.nii.gz") + " -o " + q(out), "--input-kind"},
      {q(dir / "s.stl") + " -o " + q(out) + " --edge 0", "--edge"},
      {q(dir / "s.stl") + " -o " + q(out) + " --edge -1", "--edge"},
      {q(dir / "s.stl") + " --shape cube -o " + q(out), "not both"},
      {"-o " + q(out), "INPUT"},
      {q(dir / "s.stl") + " -o " + q(dir / "out.stl"), "out.stl"},
      {q(dir / "s.stl") + " --input-kind field -o " + q(out), "s.stl"},
      {q(dir / "s.stl") + " --label 2 -o " + q(out), "--label"},
      {q(dir / "missing.nii.gz") + " -o " + q(out), "missing.nii.gz"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.args);
    const auto r = test::run_tool("tetmesh " + c.args + " --report " + q(dir / "r.json"));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(c.fragment), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(dir / "out.stl"));
    EXPECT_FALSE(fs::exists(dir / "r.json"));
  }
}

}  // namespace
}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
#include "ido/io/mesh_io.h"

#include <fstream>

#include "ido/core/error.h"
#include "ido/io/pvd.h"
#include "io_test_util.h"
#include "support/test_support.h"

namespace ido::io {
namespace {
namespace fs = std::filesystem;
using geometry::TetMesh;
using geometry::TriangleMesh;

/// A closed octahedron, outward oriented, with coordinates exact in float (so binary STL
/// round trips are exact too), plus a vector point field and a scalar cell field.
TriangleMesh octahedron() {
  TriangleMesh m;
  m.vertices = {{1.5, 0, 0}, {-1.5, 0, 0}, {0, 2.25, 0}, {0, -2.25, 0}, {0, 0, 3.125}, {0, 0, -3.125}};
  for (auto& v : m.vertices) v += Vec3(10.0, -20.5, 0.75);
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  geometry::Field disp{3, {}};
  for (std::size_t i = 0; i < 6; ++i) disp.values.insert(disp.values.end(), {0.1 * double(i), -1.0 / 3.0, 1e-7 * double(i)});
  m.point_fields["displacement_mm"] = disp;
  geometry::Field id{1, {}};
  for (std::size_t i = 0; i < 8; ++i) id.values.push_back(double(i) * 1.5);
  m.cell_fields["label"] = id;
  return m;
}

/// A unit cube cut into 5 positively oriented tetrahedra, with fields.
TetMesh cube_tets() {
  TetMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  for (auto& v : m.vertices) v = v * 2.5 + Vec3(-1.0, 0.5, 7.25);
  m.tets = {{0, 1, 2, 4}, {1, 3, 2, 7}, {1, 2, 4, 7}, {1, 5, 7, 4}, {2, 4, 7, 6}};
  // Fix orientation so every tetrahedron has positive volume.
  for (auto& t : m.tets) {
    const Vec3 a = m.vertices[std::size_t(t[0])];
    if ((m.vertices[std::size_t(t[1])] - a).dot((m.vertices[std::size_t(t[2])] - a).cross(m.vertices[std::size_t(t[3])] - a)) < 0)
      std::swap(t[2], t[3]);
  }
  geometry::Field temp{1, {}};
  for (std::size_t i = 0; i < 8; ++i) temp.values.push_back(37.0 + 0.01 * double(i));
  m.point_fields["temperature_c"] = temp;
  geometry::Field stress{6, {}};
  for (std::size_t i = 0; i < 5 * 6; ++i) stress.values.push_back(std::sqrt(double(i)) * 1e3);
  m.cell_fields["stress_pa"] = stress;
  return m;
}

void expect_same_geometry(const TriangleMesh& a, const TriangleMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles, b.triangles);
  for (std::size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]) << i;
}

void expect_same_fields(const geometry::FieldMap& a, const geometry::FieldMap& b) {
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, f] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_EQ(f.components, b.at(name).components) << name;
    EXPECT_EQ(f.values, b.at(name).values) << name;
  }
}

/// Corner positions triangle by triangle: independent of vertex numbering.
std::vector<Vec3> corners(const TriangleMesh& m) {
  std::vector<Vec3> out;
  for (const auto& t : m.triangles)
    for (auto v : t) out.push_back(m.vertices[std::size_t(v)]);
  return out;
}

TEST(MeshIo, TriangleRoundTripsExact) {
  const auto dir = test::scratch_dir("mesh-rt-tri");
  const auto m = octahedron();
  struct Case { const char* file; MeshWriteOptions opt; bool fields; };
  const Case cases[] = {{"a.obj", {}, false},           {"a.ply", {}, false},
                        {"b.ply", {.big_endian = true}, false}, {"c.ply", {.ascii = true}, false},
                        {"a.vtp", {}, true},            {"b.vtp", {.ascii = true}, true},
                        {"a.msh", {}, false},           {"b.msh", {.gmsh_v2 = true}, false}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    write_triangle_mesh(dir / c.file, m, c.opt);
    const auto back = read_triangle_mesh(dir / c.file);
    expect_same_geometry(m, back);
    if (c.fields) {
      expect_same_fields(m.point_fields, back.point_fields);
      expect_same_fields(m.cell_fields, back.cell_fields);
    }
  }
}

TEST(MeshIo, StlRoundTripsAndMergesCorners) {
  const auto dir = test::scratch_dir("mesh-rt-stl");
  const auto m = octahedron();
  for (bool ascii : {false, true}) {
    write_triangle_mesh(dir / "m.stl", m, {.ascii = ascii});
    const auto back = read_triangle_mesh(dir / "m.stl");
    EXPECT_EQ(back.vertices.size(), 6u);  // shared corners merged again
    EXPECT_EQ(corners(back), corners(m));
  }
  // Binary STL size is exactly 84 + 50 per triangle.
  write_triangle_mesh(dir / "m.stl", m);
  EXPECT_EQ(fs::file_size(dir / "m.stl"), 84u + 50u * 8u);
}

TEST(MeshIo, TetRoundTripsExact) {
  const auto dir = test::scratch_dir("mesh-rt-tet");
  const auto m = cube_tets();
  struct Case { const char* file; MeshWriteOptions opt; bool fields; };
  const Case cases[] = {{"a.vtu", {}, true}, {"b.vtu", {.ascii = true}, true}, {"a.msh", {}, false},
                        {"b.msh", {.gmsh_v2 = true}, false}, {"a.node", {}, false}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    write_tet_mesh(dir / c.file, m, c.opt);
    const auto back = read_tet_mesh(dir / c.file);
    ASSERT_EQ(back.tets, m.tets);
    ASSERT_EQ(back.vertices.size(), m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) EXPECT_EQ(back.vertices[i], m.vertices[i]);
    if (c.fields) {
      expect_same_fields(m.point_fields, back.point_fields);
      expect_same_fields(m.cell_fields, back.cell_fields);
    }
  }
  // TetGen: either name reads the pair.
  EXPECT_EQ(read_tet_mesh(dir / "a.ele").tets, m.tets);
}

// ---- against VTK's own readers ---------------------------------------------------------

void expect_vtk_mesh(const nlohmann::json& j, const std::vector<Vec3>& vertices,
                     const std::vector<std::vector<int>>& cells, double tol) {
  ASSERT_EQ(j["points"].get<std::size_t>(), vertices.size());
  ASSERT_EQ(j["cells"].get<std::size_t>(), cells.size());
  const auto coords = j["coords"].get<std::vector<double>>();
  for (std::size_t i = 0; i < vertices.size(); ++i)
    for (int a = 0; a < 3; ++a) EXPECT_TRUE(test::near(coords[3 * i + std::size_t(a)], vertices[i][a], tol));
  EXPECT_EQ(j["connectivity"].get<std::vector<std::vector<int>>>(), cells);
}

template <class Elements>
std::vector<std::vector<int>> as_cells(const Elements& e) {
  std::vector<std::vector<int>> out;
  for (const auto& c : e) out.emplace_back(c.begin(), c.end());
  return out;
}

void expect_vtk_fields(const nlohmann::json& data, const geometry::FieldMap& fields) {
  for (const auto& [name, f] : fields) {
    ASSERT_TRUE(data.contains(name)) << name;
    EXPECT_EQ(data[name]["components"].get<int>(), f.components);
    EXPECT_EQ(data[name]["values"].get<std::vector<double>>(), f.values) << name;
  }
}

TEST(MeshIoVtk, VtkReadsOurVtuAndVtp) {
  const auto dir = test::scratch_dir("mesh-vtk-xml");
  const auto t = cube_tets();
  const auto s = octahedron();
  for (bool ascii : {false, true}) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    write_tet_mesh(dir / "t.vtu", t, {.ascii = ascii});
    IDO_VTK_READ(ju, "vtu", dir / "t.vtu");
    expect_vtk_mesh(ju, t.vertices, as_cells(t.tets), 0.0);
    EXPECT_EQ(ju["cell_types"].get<std::vector<int>>(), std::vector<int>(5, 10));
    expect_vtk_fields(ju["point_data"], t.point_fields);
    expect_vtk_fields(ju["cell_data"], t.cell_fields);
    write_triangle_mesh(dir / "s.vtp", s, {.ascii = ascii});
    IDO_VTK_READ(jp, "vtp", dir / "s.vtp");
    expect_vtk_mesh(jp, s.vertices, as_cells(s.triangles), 0.0);
    expect_vtk_fields(jp["point_data"], s.point_fields);
    expect_vtk_fields(jp["cell_data"], s.cell_fields);
  }
}

TEST(MeshIoVtk, VtkReadsOurPlyObjStl) {
  const auto dir = test::scratch_dir("mesh-vtk-tri");
  const auto s = octahedron();
  for (auto [file, opt] : {std::pair{"a.ply", MeshWriteOptions{}}, {"b.ply", MeshWriteOptions{.big_endian = true}},
                           {"c.ply", MeshWriteOptions{.ascii = true}}}) {
    SCOPED_TRACE(file);
    write_triangle_mesh(dir / file, s, opt);
    IDO_VTK_READ(j, "ply", dir / file);
    expect_vtk_mesh(j, s.vertices, as_cells(s.triangles), 1e-6);  // vtkPLYReader keeps float
  }
  write_triangle_mesh(dir / "a.obj", s);
  IDO_VTK_READ(jo, "obj", dir / "a.obj");
  expect_vtk_mesh(jo, s.vertices, as_cells(s.triangles), 1e-6);
  for (bool ascii : {false, true}) {
    write_triangle_mesh(dir / "a.stl", s, {.ascii = ascii});
    IDO_VTK_READ(js, "stl", dir / "a.stl");
    // vtkSTLReader merges points too, in first-appearance order: the same as ours.
    const auto back = read_triangle_mesh(dir / "a.stl");
    expect_vtk_mesh(js, back.vertices, as_cells(back.triangles), 0.0);
    EXPECT_EQ(corners(back), corners(s));
  }
}

// Gmsh itself (python3-gmsh; Debian 12's VTK 9.1 has no vtkGmshReader) reads our .msh files,
// both format versions, and sees our tetrahedra.
TEST(MeshIoVtk, GmshReadsOurGmsh) {
  const auto dir = test::scratch_dir("mesh-gmsh-msh");
  const auto t = cube_tets();
  write_tet_mesh(dir / "v4.msh", t);
  write_tet_mesh(dir / "v2.msh", t, {.gmsh_v2 = true});
  for (const char* name : {"v4.msh", "v2.msh"}) {
    SCOPED_TRACE(name);
    IDO_VTK_READ(jm, "msh", dir / name);
    if (jm.contains("skipped")) GTEST_SKIP() << jm["skipped"].get<std::string>();
    expect_vtk_mesh(jm, t.vertices, as_cells(t.tets), 0.0);
  }
}

// ---- reading what VTK writes -----------------------------------------------------------

bool vtk_write(const std::string& kind, const std::string& mode, const fs::path& file) {
  const std::string cmd = "/usr/bin/python3 '" + (test::source_dir() / "tests/io/vtk_check.py").string() + "' write " +
                          kind + " " + mode + " '" + file.string() + "' >/dev/null 2>&1";
  return std::system(cmd.c_str()) == 0;
}

TEST(MeshIoVtk, ReadsWhatVtkWrites) {
  if (!test::vtk_read("vtp", "/nonexistent")) GTEST_SKIP() << "python3-vtk9 not available";
  const auto dir = test::scratch_dir("mesh-from-vtk");
  const std::vector<Vec3> pts = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  std::vector<double> disp, stress_tet, stress_tri;
  for (int i = 0; i < 5; ++i) disp.insert(disp.end(), {0.5 * i, -0.25 * i, 0.125 * i});
  for (const char* mode : {"ascii", "binary", "appended", "binary-zlib", "appended-zlib", "base64-zlib"}) {
    SCOPED_TRACE(mode);
    ASSERT_TRUE(vtk_write("vtu", mode, dir / (std::string(mode) + ".vtu")));
    const auto t = read_tet_mesh(dir / (std::string(mode) + ".vtu"));
    EXPECT_EQ(t.vertices, pts);
    EXPECT_EQ(t.tets, (std::vector<Tet>{{0, 1, 2, 3}, {1, 4, 2, 3}}));
    EXPECT_EQ(t.point_fields.at("displacement_mm").values, disp);
    EXPECT_EQ(t.cell_fields.at("stress_pa").values, (std::vector<double>{10.0, 12.5}));
    ASSERT_TRUE(vtk_write("vtp", mode, dir / (std::string(mode) + ".vtp")));
    const auto p = read_triangle_mesh(dir / (std::string(mode) + ".vtp"));
    EXPECT_EQ(p.vertices, pts);
    EXPECT_EQ(p.triangles, (std::vector<Tri>{{0, 2, 1}, {0, 1, 3}, {1, 2, 4}}));
    EXPECT_EQ(p.cell_fields.at("stress_pa").values, (std::vector<double>{10.0, 12.5, 15.0}));
  }
  for (const char* mode : {"ascii", "binary"}) {
    SCOPED_TRACE(mode);
    ASSERT_TRUE(vtk_write("ply", mode, dir / (std::string(mode) + ".ply")));
    const auto p = read_triangle_mesh(dir / (std::string(mode) + ".ply"));
    EXPECT_EQ(p.vertices, pts);
    EXPECT_EQ(p.triangles, (std::vector<Tri>{{0, 2, 1}, {0, 1, 3}, {1, 2, 4}}));
    ASSERT_TRUE(vtk_write("stl", mode, dir / (std::string(mode) + ".stl")));
    const auto s = read_triangle_mesh(dir / (std::string(mode) + ".stl"));
    EXPECT_EQ(s.triangles.size(), 3u);
    EXPECT_EQ(s.vertices.size(), 5u);
  }
}

// A damaged zlib-compressed file (as ParaView saves) gives an IoError naming the file and the
// array, never garbage values or a crash.
TEST(MeshIoVtk, DamagedCompressedVtuIsAnIoError) {
  if (!test::vtk_read("vtp", "/nonexistent")) GTEST_SKIP() << "python3-vtk9 not available";
  const auto dir = test::scratch_dir("mesh-zlib-bad");
  const auto good = dir / "good.vtu";
  ASSERT_TRUE(vtk_write("vtu", "appended-zlib", good));
  std::string bytes;
  {
    std::ifstream in(good, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto data = bytes.find('_', bytes.find("<AppendedData")) + 1;
  auto expect_error = [&](const std::string& content, const std::string& name, const std::string& problem) {
    const auto path = dir / name;
    std::ofstream(path, std::ios::binary) << content;
    try {
      (void)read_tet_mesh(path);
      ADD_FAILURE() << name << " was read without error";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    }
  };
  // Flip bits inside the first compressed block (after its 4-value UInt64 header, at least).
  std::string corrupt = bytes;
  for (std::size_t i = data + 40; i < data + 56; ++i) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5A);
  expect_error(corrupt, "corrupt.vtu", "compressed");
  // Cut the last array's compressed blocks short, keeping the closing tags.
  const auto close = bytes.rfind("</AppendedData>");
  const auto end = bytes.find_last_not_of(" \n\r\t", close - 1) + 1;
  expect_error(bytes.substr(0, end - 6) + bytes.substr(end), "truncated.vtu", "truncated");
  // An unknown compressor is named.
  std::string lz4 = bytes;
  lz4.replace(lz4.find("vtkZLibDataCompressor"), 21, "vtkLZ4DataCompressor");
  expect_error(lz4, "lz4.vtu", "vtkLZ4DataCompressor");
}

TEST(MeshIo, PvdRoundTrip) {
  const auto dir = test::scratch_dir("mesh-pvd");
  const std::vector<PvdEntry> entries = {{0.0, "frame_0000.vtu"}, {0.01, "frame_0001.vtu"}, {1.0 / 3.0, "a&b.vtu"}};
  write_pvd(dir / "series.pvd", entries);
  const auto back = read_pvd(dir / "series.pvd");
  ASSERT_EQ(back.size(), entries.size());
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].time_s, entries[i].time_s);
    EXPECT_EQ(back[i].file, entries[i].file);
  }
}

TEST(MeshIo, WritesAreAtomic) {
  const auto dir = test::scratch_dir("mesh-atomic");
  const auto m = octahedron();
  write_triangle_mesh(dir / "m.vtp", m);
  const auto size = fs::file_size(dir / "m.vtp");
  auto bad = m;
  bad.triangles.push_back({0, 1, 99});
  EXPECT_THROW(write_triangle_mesh(dir / "m.vtp", bad), InvalidInput);
  EXPECT_EQ(fs::file_size(dir / "m.vtp"), size);
  EXPECT_THROW(write_triangle_mesh(dir / "nowhere" / "m.vtp", m), IoError);
  EXPECT_THROW(write_triangle_mesh(dir / "m.xyz", m), IoError);
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
}

TEST(MeshIo, PathKinds) {
  EXPECT_TRUE(is_tet_mesh_path("a/b.VTU"));
  EXPECT_TRUE(is_tet_mesh_path("x.ele"));
  EXPECT_FALSE(is_tet_mesh_path("x.stl"));
  EXPECT_TRUE(is_triangle_mesh_path("x.Ply"));
  EXPECT_FALSE(is_triangle_mesh_path("x.nii.gz"));
}

}  // namespace
}  // namespace ido::io

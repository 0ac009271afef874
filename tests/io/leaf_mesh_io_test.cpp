// SPDX-License-Identifier: Apache-2.0
#include "ido/io/leaf_mesh_io.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>

#include "ido/drill/assembled_surface.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/erosion.h"
#include "ido/drill/leaf_mesh.h"
#include "ido/drill/shapes.h"
#include "ido/io/mesh_io.h"
#include "support/test_support.h"

namespace ido {
namespace {

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A block drilled at three levels of refinement: a burr through a corner and one inside,
// and a whole root erased, so leaves of several depths, erased cells and points on the
// roots' faces, edges and corners (shared between roots) all occur.
drill::TetHierarchy drilled_block() {
  drill::TetHierarchy h(drill::make_block({6, 6, 4}, 2.0));
  drill::Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = 3, .max_node_visits = 0});
  for (const Vec3& c : {Vec3(0.3, 0.4, 4.1), Vec3(3.1, 2.9, 2.2), Vec3(5.0, 5.5, 1.0)})
    e.erode(h, c, 1.1, 1.0, 1e-3);
  h.erase(drill::NodeRef{7, 0, 0});
  return h;
}

// The streamed .vtu is the held mesh's file byte for byte (binary and ASCII), and its
// tetrahedra are positively oriented and fill exactly the remaining material.
TEST(LeafMeshIo, StreamedVtuEqualsTheHeldMeshFile) {
  const auto h = drilled_block();
  ASSERT_LT(h.material_volume(), h.total_volume() - h.root_volume(7) + 1e-9);
  const auto dir = test::scratch_dir("leaf-mesh-io");
  const auto held = drill::full_leaf_mesh(h);
  std::size_t deep = 0;
  for (const double d : held.cell_fields.at("depth").values) deep += d == 3.0 ? 1U : 0U;
  ASSERT_GT(deep, 0U);
  for (const bool ascii : {false, true}) {
    SCOPED_TRACE(ascii);
    const auto streamed_path = dir / "streamed.vtu", held_path = dir / "held.vtu";
    const auto stats = io::write_leaf_mesh(streamed_path, h, {.ascii = ascii});
    io::write_tet_mesh(held_path, held, {.ascii = ascii});
    EXPECT_EQ(stats.tets, held.tets.size());
    EXPECT_EQ(stats.vertices, held.vertices.size());
    const auto bytes = file_bytes(streamed_path);
    ASSERT_FALSE(bytes.empty());
    EXPECT_TRUE(bytes == file_bytes(held_path));
  }
  // Read back: positively oriented tetrahedra whose volumes sum to the material left.
  const auto back = io::read_tet_mesh(dir / "streamed.vtu");
  double volume = 0.0, smallest = 1e300;
  for (const auto& t : back.tets) {
    const double v = drill::signed_volume(back.vertices[std::size_t(t[0])], back.vertices[std::size_t(t[1])],
                                          back.vertices[std::size_t(t[2])], back.vertices[std::size_t(t[3])]);
    volume += v;
    smallest = std::min(smallest, v);
  }
  EXPECT_GT(smallest, 0.0);
  EXPECT_TRUE(test::rel_near(volume, h.material_volume(), 1e-12));
}

// Other formats build the mesh: the same files as write_tet_mesh of full_leaf_mesh.
TEST(LeafMeshIo, GmshEqualsTheHeldMeshFile) {
  const auto h = drilled_block();
  const auto dir = test::scratch_dir("leaf-mesh-io-msh");
  io::write_leaf_mesh(dir / "streamed.msh", h);
  io::write_tet_mesh(dir / "held.msh", drill::full_leaf_mesh(h));
  EXPECT_TRUE(file_bytes(dir / "streamed.msh") == file_bytes(dir / "held.msh"));
}

// The drilled surface streamed as a .vtp is write_triangle_mesh's file of the same surface
// made into a TriangleMesh, byte for byte (binary and ASCII); other formats build the mesh.
TEST(LeafMeshIo, StreamedSurfaceVtpEqualsTheHeldMeshFile) {
  const auto h = drilled_block();
  const auto dir = test::scratch_dir("leaf-mesh-io-vtp");
  const drill::BoundarySurface surface(h);
  const drill::AssembledSurface assembled(surface.v_lists(), h.vertices());
  const auto held = drill::assemble_surface(surface.v_lists(), h.vertices());
  ASSERT_GT(held.triangles.size(), 100U);
  for (const bool ascii : {false, true}) {
    SCOPED_TRACE(ascii);
    io::write_drilled_surface(dir / "streamed.vtp", assembled, {.ascii = ascii});
    io::write_triangle_mesh(dir / "held.vtp", held, {.ascii = ascii});
    const auto bytes = file_bytes(dir / "streamed.vtp");
    ASSERT_FALSE(bytes.empty());
    EXPECT_TRUE(bytes == file_bytes(dir / "held.vtp"));
  }
  io::write_drilled_surface(dir / "streamed.stl", assembled);
  io::write_triangle_mesh(dir / "held.stl", held);
  EXPECT_TRUE(file_bytes(dir / "streamed.stl") == file_bytes(dir / "held.stl"));
  // Read back: the closed surface encloses the material left.
  const auto back = io::read_triangle_mesh(dir / "streamed.vtp");
  EXPECT_EQ(back.triangles.size(), held.triangles.size());
  double volume = 0.0;
  for (const auto& t : back.triangles)
    volume += back.vertices[std::size_t(t[0])].dot(back.vertices[std::size_t(t[1])].cross(back.vertices[std::size_t(t[2])])) / 6.0;
  EXPECT_TRUE(test::rel_near(volume, h.material_volume(), 1e-9));
}

// Welding: every vertex is used, and no two vertices share a position.
TEST(LeafMeshWalk, VerticesAreWeldedAndUsed) {
  const auto h = drilled_block();
  const drill::LeafMeshWalk walk(h);
  std::vector<std::array<double, 3>> points;
  walk.for_each_vertex([&](const Vec3& p) { points.push_back({p.x(), p.y(), p.z()}); });
  ASSERT_EQ(points.size(), walk.vertex_count());
  std::vector<int> used(points.size(), 0);
  std::size_t tets = 0;
  walk.for_each_tet([&](const Tet& t) {
    ++tets;
    for (const auto v : t) used.at(std::size_t(v)) = 1;
  });
  EXPECT_EQ(tets, walk.tet_count());
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
  std::sort(points.begin(), points.end());
  EXPECT_EQ(std::adjacent_find(points.begin(), points.end()), points.end());
}

}  // namespace
}  // namespace ido

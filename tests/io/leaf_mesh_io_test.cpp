// SPDX-License-Identifier: Apache-2.0
// The leaf mesh streamed to files: .vtu, .msh and the boundary .vtp are the held mesh's files
// byte for byte, and read back they fill (or enclose) exactly the material left.
#include "ido/io/leaf_mesh_io.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>

#include "ido/drill/assembled_surface.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/leaf_mesh.h"
#include "ido/io/mesh_io.h"
#include "support/drilled_block.h"
#include "support/test_support.h"

namespace ido {
namespace {

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The streamed .vtu is the held mesh's file byte for byte (binary and ASCII), and its
// tetrahedra are positively oriented and fill exactly the remaining material.
TEST(LeafMeshIo, StreamedVtuEqualsTheHeldMeshFile) {
  const auto h = test::drilled_block();
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
  const auto h = test::drilled_block();
  const auto dir = test::scratch_dir("leaf-mesh-io-msh");
  io::write_leaf_mesh(dir / "streamed.msh", h);
  io::write_tet_mesh(dir / "held.msh", drill::full_leaf_mesh(h));
  EXPECT_TRUE(file_bytes(dir / "streamed.msh") == file_bytes(dir / "held.msh"));
}

// The drilled surface streamed as a .vtp is write_triangle_mesh's file of the same surface
// made into a TriangleMesh, byte for byte (binary and ASCII); other formats build the mesh.
TEST(LeafMeshIo, StreamedSurfaceVtpEqualsTheHeldMeshFile) {
  const auto h = test::drilled_block();
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

}  // namespace
}  // namespace ido

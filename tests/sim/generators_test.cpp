// SPDX-License-Identifier: Apache-2.0
// The mesh generators: beams and cubes fill their box exactly with positively oriented,
// conforming tetrahedra (6 or 5 per cell), with the documented vertex numbering and placement;
// the voxel sphere holds exactly the cells whose centres are inside; bad sizes are refused.
#include "ido/geometry/tet_quality.h"
#include "ido/sim/generators.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/fem_common.h"
#include "support/test_support.h"

namespace ido {
namespace {

/// Sum of the tetrahedra's signed volumes (mm³); fails the test for one that is not positive.
double total_volume(const geometry::TetMesh& m) {
  double sum = 0.0;
  for (const Tet& t : m.tets) {
    const double v = sim::tet_signed_volume(m.vertices[std::size_t(t[0])], m.vertices[std::size_t(t[1])],
                                            m.vertices[std::size_t(t[2])], m.vertices[std::size_t(t[3])]);
    EXPECT_GT(v, 0.0);
    sum += v;
  }
  return sum;
}

/// The boundary's area (mm²), checking that every face is used by one tetrahedron (the
/// boundary) or two (conforming inside) and that the boundary is closed and manifold.
double boundary_area(const geometry::TetMesh& m) {
  const geometry::TetMeshReport r = geometry::check_tet_mesh(m);
  EXPECT_TRUE(r.boundary_closed);
  EXPECT_TRUE(r.boundary_manifold);
  const geometry::TriangleMesh b = geometry::tet_boundary(m);
  EXPECT_EQ(b.triangles.size(), r.boundary_faces);
  double area = 0.0;
  for (const Tri& t : b.triangles) {
    const Vec3 &p = b.vertices[std::size_t(t[0])], &q = b.vertices[std::size_t(t[1])], &c = b.vertices[std::size_t(t[2])];
    area += 0.5 * (q - p).cross(c - p).norm();
  }
  return area;
}

TEST(Generators, BeamsFillTheirBoxWithConformingPositiveTetrahedra) {
  const Vec3 size(30, 8, 5), origin(-3, 2, 7);
  const Vec3i cells(6, 2, 3);
  for (const sim::HexSplit split : {sim::HexSplit::Six, sim::HexSplit::Five}) {
    const auto m = sim::make_beam(size, cells, origin, split);
    const int per_cell = split == sim::HexSplit::Six ? 6 : 5;
    EXPECT_EQ(m.vertices.size(), std::size_t(7 * 3 * 4));
    EXPECT_EQ(m.tets.size(), std::size_t(per_cell * 6 * 2 * 3));
    EXPECT_TRUE(test::rel_near(total_volume(m), size.prod(), 1e-12));
    EXPECT_TRUE(test::rel_near(boundary_area(m), 2.0 * (size.x() * size.y() + size.y() * size.z() + size.x() * size.z()), 1e-12));
    // Vertex (i, j, k) is i + (cells.x + 1)(j + (cells.y + 1) k), at origin + size·(i, j, k)/cells.
    for (int k = 0; k <= cells.z(); ++k)
      for (int j = 0; j <= cells.y(); ++j)
        for (int i = 0; i <= cells.x(); ++i) {
          const Vec3 expected = origin + Vec3(size.x() * i / cells.x(), size.y() * j / cells.y(), size.z() * k / cells.z());
          EXPECT_TRUE(test::near((m.vertices[std::size_t(i + 7 * (j + 3 * k))] - expected).norm(), 0.0, 1e-12));
        }
  }
}

// make_cube(edge, cells, centre) is the beam of that edge centred there.
TEST(Generators, CubeIsTheBeamCentredAtItsCentre) {
  const Vec3 centre(4, -5, 6);
  const auto cube = sim::make_cube(12.0, 3, centre);
  const auto beam = sim::make_beam(Vec3::Constant(12.0), Vec3i::Constant(3), centre - Vec3::Constant(6.0));
  EXPECT_TRUE(cube.vertices == beam.vertices);
  EXPECT_TRUE(cube.tets == beam.tets);
  Vec3 lo = cube.vertices[0], hi = cube.vertices[0];
  for (const Vec3& v : cube.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  EXPECT_TRUE(test::near((0.5 * (lo + hi) - centre).norm(), 0.0, 1e-12));
  EXPECT_TRUE(test::near((hi - lo - Vec3::Constant(12.0)).norm(), 0.0, 1e-12));
  EXPECT_TRUE(test::rel_near(total_volume(cube), 1728.0, 1e-12));
}

// The voxel sphere: the cells of the (2n)³ grid over the ball's box whose centres are inside,
// 6 tetrahedra each, so its volume is that count times h³; vertices are shared between cells
// (a conforming mesh) and lie within half a cell diagonal of the sphere.
TEST(Generators, VoxelSphereHoldsTheCellsWhoseCentresAreInside) {
  const double radius = 9.0;
  const Vec3 centre(1, 2, 3);
  for (const int n : {1, 3, 6}) {
    const auto m = sim::make_sphere(radius, n, centre);
    const double h = radius / n;
    int inside = 0;
    for (int k = 0; k < 2 * n; ++k)
      for (int j = 0; j < 2 * n; ++j)
        for (int i = 0; i < 2 * n; ++i)
          inside += (h * Vec3(i + 0.5, j + 0.5, k + 0.5) - Vec3::Constant(radius)).norm() <= radius;
    EXPECT_EQ(m.tets.size(), std::size_t(6 * inside)) << n;
    EXPECT_TRUE(test::rel_near(total_volume(m), inside * h * h * h, 1e-12)) << n;
    (void)boundary_area(m);
    for (const Vec3& v : m.vertices) EXPECT_LE((v - centre).norm(), radius + 0.5 * std::sqrt(3.0) * h + 1e-9);
  }
  // Finer grids approach the ball's volume.
  EXPECT_TRUE(test::rel_near(total_volume(sim::make_sphere(radius, 24, centre)), 4.0 / 3.0 * kPi * std::pow(radius, 3), 0.01));
}

TEST(Generators, BadSizesAndCountsAreRefused) {
  EXPECT_THROW((void)sim::make_beam({1, 1, 1}, {1, 0, 1}), InvalidInput);
  EXPECT_THROW((void)sim::make_beam({1, -1, 1}, {1, 1, 1}), InvalidInput);
  EXPECT_THROW((void)sim::make_beam({1, 1, std::nan("")}, {1, 1, 1}), InvalidInput);
  EXPECT_THROW((void)sim::make_cube(0.0, 2), InvalidInput);
  EXPECT_THROW((void)sim::make_cube(1.0, 0), InvalidInput);
  EXPECT_THROW((void)sim::make_sphere(-1.0, 2), InvalidInput);
  EXPECT_THROW((void)sim::make_sphere(1.0, 0), InvalidInput);
}

}  // namespace
}  // namespace ido

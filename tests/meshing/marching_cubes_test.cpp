// SPDX-License-Identifier: Apache-2.0
#include "ido/meshing/marching_cubes.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ido/geometry/mesh_checks.h"
#include "support/test_support.h"

namespace ido::meshing {
using geometry::check_mesh;
using geometry::MeshCheckReport;
using image::Volume;
using test::near;
using test::rel_near;

namespace {

::testing::AssertionResult closed_oriented_manifold(const geometry::TriangleMesh& mesh) {
  const MeshCheckReport r = check_mesh(mesh);
  if (r.closed && r.edge_manifold && r.vertex_manifold && r.oriented && r.degenerate_triangles == 0 &&
      r.vertices == mesh.vertices.size())
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "closed " << r.closed << " edge_manifold " << r.edge_manifold << " vertex_manifold "
         << r.vertex_manifold << " oriented " << r.oriented << " degenerate "
         << r.degenerate_triangles << " referenced " << r.vertices << "/" << mesh.vertices.size();
}

/// Signed distance to a sphere (negative inside), sampled on a grid.
Volume<float> sphere_field(Index3 n, const Vec3& spacing, const Vec3& centre, double radius,
                           const Mat3& dir = Mat3::Identity()) {
  Volume<float> v(n, spacing, Vec3(-3.0, 2.0, 1.0), dir);
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i)
        v(i, j, k) = float((v.index_to_world(Vec3(double(i), double(j), double(k))) - centre).norm() - radius);
  return v;
}

}  // namespace

TEST(MarchingCubesTable, EveryNonTrivialCaseHasTriangles) {
  EXPECT_EQ(marching_cubes_case_triangle_count(0), 0);
  EXPECT_EQ(marching_cubes_case_triangle_count(255), 0);
  for (int c = 1; c < 255; ++c) EXPECT_GE(marching_cubes_case_triangle_count(c), 1) << c;
  // A single inside corner is cut off by one triangle; a face of four inside corners by two.
  EXPECT_EQ(marching_cubes_case_triangle_count(1), 1);
  EXPECT_EQ(marching_cubes_case_triangle_count(0x0F), 2);
  // Two diagonal inside corners on a face stay separated: two triangles.
  EXPECT_EQ(marching_cubes_case_triangle_count(0b1001), 2);
  EXPECT_THROW((void)marching_cubes_case_triangle_count(256), InvalidInput);
}

TEST(MarchingCubes, FuzzRandomFieldsAreClosedOrientedManifolds) {
  std::mt19937_64 rng(12345);
  std::uniform_int_distribution<int> dim(1, 5);
  std::uniform_int_distribution<int> level(-2, 2);
  std::uniform_real_distribution<float> cont(-1.f, 1.f);
  int nonempty = 0;
  for (int trial = 0; trial < 10000; ++trial) {
    Volume<float> f({dim(rng), dim(rng), dim(rng)}, Vec3(1.0, 0.7, 1.3));
    const int mode = trial % 3;  // integer levels (many values exactly at iso), continuous, mixed
    for (float& x : f.data()) {
      if (mode == 0) x = float(level(rng));
      else if (mode == 1) x = cont(rng);
      else x = (rng() & 1) ? float(level(rng)) * 0.5f : cont(rng);
    }
    const auto mesh = marching_cubes(f, {.iso_value = 0.f, .threaded = false});
    if (mesh.triangles.empty()) {
      EXPECT_TRUE(mesh.vertices.empty());
      continue;
    }
    ++nonempty;
    ASSERT_TRUE(closed_oriented_manifold(mesh)) << "trial " << trial;
    ASSERT_GT(geometry::signed_volume(mesh), 0.0) << "trial " << trial;
    ASSERT_EQ(geometry::euler_characteristic(mesh) % 2, 0) << "trial " << trial;
  }
  EXPECT_GT(nonempty, 9000);
}

TEST(MarchingCubes, ThreadedAndSerialOutputsAreIdentical) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  Volume<float> f({40, 33, 27});
  for (float& x : f.data()) x = u(rng);
  const auto a = marching_cubes(f, {.iso_value = 0.1f, .threaded = false});
  const auto b = marching_cubes(f, {.iso_value = 0.1f, .threaded = true});
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles, b.triangles);
  for (std::size_t n = 0; n < a.vertices.size(); ++n) ASSERT_EQ(a.vertices[n], b.vertices[n]);
  EXPECT_TRUE(closed_oriented_manifold(a));
}

TEST(MarchingCubes, SphereDistanceFieldGivesVolumeWithinHalfPercent) {
  const double r = 20.0;
  const Vec3 c(22.3, 25.1, 24.7);
  const auto f = sphere_field({50, 48, 44}, Vec3(1.0, 1.1, 1.25), c + Vec3(-3, 2, 1), r);
  const auto mesh = marching_cubes(f);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  const double exact = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_TRUE(rel_near(geometry::signed_volume(mesh), exact, 0.005));
  EXPECT_EQ(geometry::euler_characteristic(mesh), 2);
  // Every vertex lies near the sphere (linear interpolation error ≪ a voxel).
  for (const Vec3& p : mesh.vertices) ASSERT_TRUE(near((p - c - Vec3(-3, 2, 1)).norm(), r, 0.05));
}

TEST(MarchingCubes, OrientationOutwardForMirroredDirection) {
  Mat3 d = Mat3::Identity();
  d(0, 0) = -1.0;  // determinant −1
  d = Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()).toRotationMatrix() * d;
  const Vec3 centre(-3.0, 2.0, 1.0);  // the grid origin; the sphere sits inside the grid
  Volume<float> probe({30, 30, 30}, Vec3(0.9, 0.9, 0.9), centre, d);
  const Vec3 mid = probe.index_to_world(Vec3(14.5, 14.5, 14.5));
  const auto f = sphere_field({30, 30, 30}, Vec3(0.9, 0.9, 0.9), mid, 9.0, d);
  const auto mesh = marching_cubes(f);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  EXPECT_TRUE(rel_near(geometry::signed_volume(mesh), 4.0 / 3.0 * kPi * 729.0, 0.01));
}

TEST(MarchingCubes, TorusHasEulerCharacteristicZero) {
  const double big = 14.0, small = 5.0;
  Volume<float> f({44, 44, 20}, Vec3(1, 1, 1));
  const Vec3 c(21.5, 21.5, 9.5);
  for (std::int64_t k = 0; k < 20; ++k)
    for (std::int64_t j = 0; j < 44; ++j)
      for (std::int64_t i = 0; i < 44; ++i) {
        const Vec3 p = Vec3(double(i), double(j), double(k)) - c;
        const double q = std::hypot(p.x(), p.y()) - big;
        f(i, j, k) = float(std::hypot(q, p.z()) - small);
      }
  const auto mesh = marching_cubes(f);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  EXPECT_EQ(geometry::euler_characteristic(mesh), 0);
  EXPECT_TRUE(rel_near(geometry::signed_volume(mesh), 2 * kPi * kPi * big * small * small, 0.01));
}

TEST(MarchingCubes, FieldInsideEverywhereIsCappedHalfAVoxelOutside) {
  Volume<float> f({4, 5, 6}, Vec3(0.5, 1.0, 2.0), Vec3(10, 20, 30), Mat3::Identity(), -1.f);
  const auto mesh = marching_cubes(f);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  // The box from −½ to n−½ voxels along each axis (the capped border) with its 12 edges
  // bevelled (a prism of cross-section ⅛ voxel² along the n−1 inner voxels of each edge)
  // and its 8 corners cut (each corner octant [−½,0]³ keeps only the simplex of volume
  // 1/48, losing 5/48): V = abc − 8·5/48 − 4·⅛·(a+b+c−3), in voxels, times the voxel volume.
  const double a = 4, b = 5, c = 6;
  const double voxels = a * b * c - 8.0 * 5.0 / 48.0 - 0.5 * (a + b + c - 3);
  EXPECT_TRUE(rel_near(geometry::signed_volume(mesh), voxels * 0.5 * 1.0 * 2.0, 1e-9));
  const auto r = check_mesh(mesh);
  EXPECT_TRUE(near(r.bounds_min.x(), 10 - 0.25, 1e-12));
  EXPECT_TRUE(near(r.bounds_max.z(), 30 + 5 * 2.0 + 1.0, 1e-12));
}

TEST(MarchingCubes, ValuesEqualToIsoAreOutside) {
  Volume<float> f({5, 5, 5}, Vec3::Ones(), Vec3::Zero(), Mat3::Identity(), 0.f);
  EXPECT_TRUE(marching_cubes(f).triangles.empty());
  f(2, 2, 2) = -1.f;
  const auto mesh = marching_cubes(f);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  EXPECT_EQ(mesh.vertices.size(), 6u);  // an octahedron, vertices pulled towards the neighbours
  EXPECT_EQ(mesh.triangles.size(), 8u);
}

TEST(MarchingCubesMask, SingleVoxelIsAnOctahedronWithMidpointVertices) {
  Volume<std::uint8_t> m({3, 3, 3}, Vec3(1.0, 2.0, 3.0), Vec3::Zero(), Mat3::Identity(), 0);
  m(1, 1, 1) = 1;
  const auto mesh = marching_cubes_mask(m);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  EXPECT_EQ(mesh.vertices.size(), 6u);
  EXPECT_EQ(mesh.triangles.size(), 8u);
  // Octahedron with half-axes 0.5, 1.0, 1.5 mm: volume (4/3)·a·b·c.
  EXPECT_TRUE(rel_near(geometry::signed_volume(mesh), 4.0 / 3.0 * 0.5 * 1.0 * 1.5, 1e-12));
}

TEST(MarchingCubesMask, DiagonalVoxelsStaySeparate) {
  // Two voxels touching along an edge and two touching at a corner: inside is 6-connected,
  // so each voxel is its own closed surface.
  Volume<std::uint8_t> m({4, 4, 4});
  m(0, 0, 0) = 1;
  m(1, 1, 0) = 1;
  m(2, 2, 1) = 1;
  const auto mesh = marching_cubes_mask(m);
  ASSERT_TRUE(closed_oriented_manifold(mesh));
  const auto r = check_mesh(mesh);
  EXPECT_EQ(r.components, 3);
  EXPECT_EQ(r.euler_characteristic, 6);
}

TEST(MarchingCubes, EmptyInputGivesEmptyMesh) {
  EXPECT_TRUE(marching_cubes(Volume<float>()).triangles.empty());
  EXPECT_THROW((void)marching_cubes(Volume<float>({2, 2, 2}), {.iso_value = NAN}), InvalidInput);
}

}  // namespace ido::meshing

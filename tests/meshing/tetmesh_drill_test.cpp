// SPDX-License-Identifier: Apache-2.0
// Stuffed meshes (uniform and graded lattice) survive a file round trip and can be drilled:
// the loaded mesh builds a drilling hierarchy holding the meshed volume, and a burr sweep
// through the inside removes the analytic swept volume within the hierarchy's resolution.
#include <cmath>

#include <gtest/gtest.h>

#include "ido/drill/erosion.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/tet_quality.h"
#include "ido/io/mesh_io.h"
#include "ido/meshing/tetrahedralize.h"
#include "support/test_support.h"

namespace ido::meshing {
namespace {

image::Volume<float> sphere_field(double r, std::int64_t n, double s) {
  const Vec3 origin = Vec3::Constant(-0.5 * double(n - 1) * s);
  image::Volume<float> v({n, n, n}, Vec3::Constant(s), origin);
  for (std::int64_t k = 0; k < n; ++k)
    for (std::int64_t j = 0; j < n; ++j)
      for (std::int64_t i = 0; i < n; ++i)
        v(i, j, k) = float(v.index_to_world(Vec3(double(i), double(j), double(k))).norm() - r);
  return v;
}

TEST(TetmeshDrill, StuffedMeshesLoadAndDrill) {
  const auto dir = test::scratch_dir("meshing-tetmesh-drill");
  const auto field = sphere_field(7.0, 35, 0.5);
  for (const bool graded : {false, true}) {
    SCOPED_TRACE(graded ? "graded" : "uniform");
    const auto mesh = tetrahedralize(field, {.edge_mm = 1.0, .graded = graded});
    const double volume = geometry::check_tet_mesh(mesh).volume_mm3;
    for (const char* name : {"m.vtu", "m.msh", "m.node"}) {
      io::write_tet_mesh(dir / name, mesh);
      const auto loaded = io::read_tet_mesh(dir / name);  // rejects inverted tetrahedra
      ASSERT_EQ(loaded.tets, mesh.tets) << name;
      ASSERT_EQ(loaded.vertices.size(), mesh.vertices.size()) << name;
      EXPECT_TRUE(test::rel_near(geometry::check_tet_mesh(loaded).volume_mm3, volume, 1e-6)) << name;
    }
    const auto loaded = io::read_tet_mesh(dir / "m.vtu");
    drill::TetHierarchy h(loaded);
    const double before = h.material_volume();
    EXPECT_TRUE(test::rel_near(before, volume, 1e-6));

    // a straight sweep of a 1.5 mm burr well inside the sphere
    const int depth = 4;
    drill::Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = depth});
    const Vec3 a(-2.5, 0.3, -0.2), b(2.5, -0.4, 0.5);
    const double r = 1.5;
    const int steps = 200;
    for (int i = 0; i <= steps; ++i) eroder.erode(h, a + (b - a) * i / steps, r, 1.0, 0.0);
    (void)eroder.finish(h);
    const double removed = before - h.material_volume();
    const double len = (b - a).norm();
    const double analytic = kPi * r * r * len + 4.0 / 3.0 * kPi * r * r * r;
    const double area = 2 * kPi * r * len + 4 * kPi * r * r;
    double diam = 0;
    for (std::size_t i = 0; i < h.root_count(); ++i) diam = std::max(diam, h.root_diameter(i));
    // the removed region differs from the swept one by at most a leaf layer over its surface
    EXPECT_LE(std::abs(removed - analytic), area * diam / std::ldexp(1.0, depth))
        << "removed " << removed << " mm³, analytic " << analytic << " mm³";
    EXPECT_GT(removed, 0.5 * analytic);
  }
}

}  // namespace
}  // namespace ido::meshing

// SPDX-License-Identifier: Apache-2.0
// The unit conversions against their definitions (1 N = 1 kg·m/s², 1 Pa = 1 N/m²), and the
// places the library applies them: a newton on a kilogram accelerates it by 1 m/s², a kilogram
// at 1 m/s carries ½ J, a kilogram per cubic metre fills a cubic metre with a kilogram, and a
// bar of modulus E pascals stores ½ E ε² joules per cubic metre.
#include "ido/sim/units.h"

#include <gtest/gtest.h>

#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_linear.h"
#include "ido/sim/generators.h"
#include "ido/sim/world.h"
#include "support/test_support.h"

namespace ido {
namespace {

constexpr double kMmPerM = 1000.0;

TEST(Units, ConstantsFollowFromTheirDefinitions) {
  EXPECT_TRUE(test::rel_near(sim::kKgMmPerS2ToNewton * kMmPerM, 1.0, 1e-15));   // kg·m/s² = N
  EXPECT_TRUE(test::rel_near(sim::kPascalToNPerMm2 * kMmPerM * kMmPerM, 1.0, 1e-15));  // N/m² in N/mm²
  EXPECT_TRUE(test::rel_near(sim::kKgPerM3ToKgPerMm3 * kMmPerM * kMmPerM * kMmPerM, 1.0, 1e-15));
  EXPECT_TRUE(test::rel_near(sim::kStandardGravityMmPerS2 / kMmPerM, 9.80665, 1e-15));  // CGPM 1901
}

TEST(Units, TheWorldConvertsWhereTheHeaderSays) {
  sim::World w;
  w.particles().add(Vec3::Zero(), 1.0, Vec3(kMmPerM, 0, 0));  // 1 kg at 1 m/s
  w.external().point_loads.push_back({0, Vec3(0, 1.0, 0)});     // 1 N
  w.compute_forces();
  EXPECT_TRUE(test::rel_near(w.accelerations()[0].y(), kMmPerM, 1e-15)) << "1 N on 1 kg: 1 m/s²";
  EXPECT_TRUE(test::rel_near(sim::energies(w).kinetic_mj, 500.0, 1e-15)) << "1 kg at 1 m/s: 0.5 J";

  // A 10 mm cube of density 1000 kg/m³ (water) weighs 1 g.
  sim::World cube;
  const auto mesh = sim::make_cube(10.0, 2);
  cube.add_tet_body(mesh, 1000.0);
  double mass = 0.0;
  for (double m : cube.particles().masses()) mass += m;
  EXPECT_TRUE(test::rel_near(mass, 1e-3, 1e-12));
  // Stretched by ε along x with ν = 0, E = 1 MPa: ½ E ε² V = ½ · 1e6 Pa · 1e-6 · 1e-6 m³ = 0.5 µJ.
  sim::Particles p = cube.particles();
  for (auto& x : p.positions()) x.x() *= 1.001;
  const sim::LinearFem bar(mesh.tets, mesh.vertices, {1e6, 0.0});
  EXPECT_TRUE(test::rel_near(bar.energy(p), 0.5e-3, 1e-9)) << "mJ";
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// Plane contact (World::step's perfectly inelastic projection) must not inject energy: an
// undamped elastic cube dropped on the floor, or resting on it, may only lose energy (up to
// the integrator's own small energy error, bounded here).
#include <algorithm>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/units.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

constexpr double kEdge = 20.0;   // mm

sim::World cube_over_floor(double drop_height_mm, const std::string& scheme) {
  sim::World w;
  w.set_threaded(false);
  const auto cube = sim::make_cube(kEdge, 3, Vec3(0, 0, 0.5 * kEdge + drop_height_mm));
  w.add_tet_body(cube, 1000.0);
  w.emplace_model<sim::CorotationalFem>(cube.tets, w.particles().positions(),
                                        sim::ElasticMaterial{2e5, 0.3});
  w.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  w.external().planes.push_back({Vec3::Zero(), Vec3::UnitZ()});
  w.set_integrator(scheme);
  w.implicit_options().cg_tolerance = 1e-10;
  return w;
}

double total_mass(const sim::World& w) {
  double m = 0.0;
  for (double mi : w.particles().masses()) m += mi;
  return m;
}

double lowest_z(const sim::World& w) {
  double z = 1e300;
  for (const auto& x : w.particles().positions()) z = std::min(z, x.z());
  return z;
}

// Largest E(t) − E(0) over the run, as a fraction of m g × edge (the cube's own energy
// scale); @p lowest_mm gets the lowest particle height reached.
double worst_energy_gain(sim::World& w, double dt_s, int steps, double& lowest_mm) {
  const double e0 = sim::energies(w).total_mj();
  const double scale = total_mass(w) * sim::kKgMmPerS2ToNewton * sim::kStandardGravityMmPerS2 * kEdge;
  double worst = -1e300;
  lowest_mm = lowest_z(w);
  for (int s = 0; s < steps; ++s) {
    w.step(dt_s);
    worst = std::max(worst, (sim::energies(w).total_mj() - e0) / scale);
    lowest_mm = std::min(lowest_mm, lowest_z(w));
  }
  return worst;
}

TEST(PlaneContact, DroppedElasticCubeGainsNoEnergy) {
  for (const std::string scheme : {"symplectic_euler", "implicit_euler"}) {
    auto w = cube_over_floor(10.0, scheme);
    const double dt = scheme == "implicit_euler" ? 1e-4 : 2e-5;
    double lowest = 0.0;
    const double gain = worst_energy_gain(w, dt, static_cast<int>(0.1 / dt), lowest);  // hits at ≈ 45 ms
    std::printf("%s: largest energy gain %.2e m g edge\n", scheme.c_str(), gain);
    EXPECT_LT(gain, 1e-4) << scheme;
    EXPECT_TRUE(test::near(lowest, 0.0, 1e-9)) << scheme;   // it did reach the floor
  }
}

TEST(PlaneContact, CubeRestingOnTheFloorGainsNoEnergy) {
  for (const std::string scheme : {"symplectic_euler", "implicit_euler"}) {
    auto w = cube_over_floor(0.0, scheme);
    const double dt = scheme == "implicit_euler" ? 1e-4 : 2e-5;
    double lowest = 0.0;
    EXPECT_LT(worst_energy_gain(w, dt, static_cast<int>(0.05 / dt), lowest), 1e-4) << scheme;
    EXPECT_GT(lowest, -1e-9) << scheme;   // contact holds it on the floor
  }
}

}  // namespace
}  // namespace ido

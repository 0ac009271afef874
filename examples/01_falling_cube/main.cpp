// SPDX-License-Identifier: Apache-2.0
// A soft Neo-Hookean cube falls onto the floor and settles. The program owns the loop:
// each World::step() call advances exactly one time step.
#include <cstdio>

#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_neo_hookean.h"
#include "ido/sim/generators.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"

int main() {
  using namespace ido;
  const auto cube = sim::make_cube(/*edge_mm=*/20.0, /*cells=*/3, /*centre_mm=*/Vec3(0, 0, 30));
  sim::World world;
  world.add_tet_body(cube, /*density_kg_m3=*/1000.0);
  world.emplace_model<sim::NeoHookeanFem>(cube.tets, world.particles().positions(),
                                          sim::ElasticMaterial{/*youngs_modulus_pa=*/2e5, /*poisson_ratio=*/0.4});
  world.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  world.external().damping.mass_per_s = 5.0;
  world.external().planes.push_back({Vec3::Zero(), Vec3::UnitZ()});   // the floor z = 0
  world.set_integrator("implicit_euler");

  const double dt_s = 1e-3;
  std::printf("time_s  lowest_z_mm  kinetic_mJ\n");
  for (int step = 0; step <= 500; ++step) {
    if (step % 50 == 0) {
      double lowest = 1e9;
      for (const auto& x : world.particles().positions()) lowest = std::min(lowest, x.z());
      std::printf("%6.3f  %11.3f  %10.5f\n", world.time_s(), lowest, sim::energies(world).kinetic_mj);
    }
    world.step(dt_s);
  }
  return 0;
}

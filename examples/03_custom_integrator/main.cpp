// SPDX-License-Identifier: Apache-2.0
// Registers a user-written time integrator (explicit midpoint, a second-order Runge–Kutta
// scheme) under a name at run time, and switches to it in the middle of a run: the paper's
// pluggable integrators. The world keeps its state across the switch.
#include <cstdio>
#include <vector>

#include "ido/sim/diagnostics.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/world.h"

namespace {

/// Explicit midpoint: evaluate the acceleration at the half step, then take the full step.
void explicit_midpoint(ido::sim::World& world, double dt_s) {
  auto& p = world.particles();
  const std::vector<ido::Vec3> x0 = p.positions(), v0 = p.velocities();
  world.compute_forces();
  const auto a0 = world.accelerations();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.fixed(i)) continue;
    p.positions()[i] = x0[i] + 0.5 * dt_s * v0[i];
    p.velocities()[i] = v0[i] + 0.5 * dt_s * a0[i];
  }
  world.compute_forces();
  const auto a_half = world.accelerations();
  const std::vector<ido::Vec3> v_half = p.velocities();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.fixed(i)) continue;
    p.positions()[i] = x0[i] + dt_s * v_half[i];
    p.velocities()[i] = v0[i] + dt_s * a_half[i];
  }
}

}  // namespace

int main() {
  using namespace ido;
  const auto block = sim::make_beam({40, 10, 10}, {8, 2, 2});
  sim::World world;
  world.add_tet_body(block, 1000.0);
  world.emplace_model<sim::MassSpring>(sim::MassSpring::from_tet_edges(block, 0, /*stiffness_n_per_mm=*/0.05));
  for (std::size_t i = 0; i < block.vertices.size(); ++i)
    if (block.vertices[i].x() < 1e-9) world.particles().set_fixed(i, true);
  world.particles().velocities().assign(world.particles().size(), Vec3(0, 0, 50));
  for (std::size_t i = 0; i < world.particles().size(); ++i)
    if (world.particles().fixed(i)) world.particles().velocities()[i].setZero();

  world.integrators().add("explicit_midpoint", explicit_midpoint);
  world.set_integrator("symplectic_euler");
  const double dt_s = 2e-5;
  std::printf("step  integrator          total_energy_mJ\n");
  for (int step = 0; step <= 4000; ++step) {
    if (step == 2000) world.set_integrator("explicit_midpoint");   // switch mid-run
    if (step % 500 == 0)
      std::printf("%4d  %-18s  %.6f\n", step, world.integrator().c_str(), sim::energies(world).total_mj());
    world.step(dt_s);
  }
  return 0;
}

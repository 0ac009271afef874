// SPDX-License-Identifier: Apache-2.0
// Forces that come from no force model, as World applies them: gravity (a free fall is exact
// under velocity Verlet, and gravity's work becomes kinetic energy), Rayleigh damping −(αM + βK)v,
// point loads, and frictionless planes that stop what falls on them without bouncing.
#include "ido/sim/external_forces.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"
#include "support/test_support.h"

namespace ido {
namespace {

// x(t) = x₀ + v₀ t + ½ g t² under velocity Verlet (exact for a constant force); the work of
// gravity, m g·(x − x₀), is the kinetic energy gained, and the total energy
// (kinetic + gravitational) stays what it was.
TEST(ExternalForces, FreeFallFollowsTheParabolaAndGravitysWorkIsKineticEnergy) {
  const Vec3 g(0, 0, -sim::kStandardGravityMmPerS2), x0(1, 2, 300), v0(20, -10, 50);
  sim::World w;
  w.particles().add(x0, 0.25, v0);
  w.external().gravity_mm_s2 = g;
  w.set_integrator("velocity_verlet");
  const double e0 = sim::energies(w).total_mj(), k0 = sim::energies(w).kinetic_mj;
  for (int s = 0; s < 100; ++s) w.step(0.002);
  const double t = w.time_s();
  const Vec3 x = w.particles().positions()[0];
  EXPECT_TRUE(test::near((x - (x0 + v0 * t + 0.5 * g * t * t)).norm(), 0.0, 1e-9));
  EXPECT_TRUE(test::near((w.particles().velocities()[0] - (v0 + g * t)).norm(), 0.0, 1e-9));
  const double work_mj = 0.25 * g.dot(x - x0) * sim::kKgMmPerS2ToNewton;
  EXPECT_TRUE(test::rel_near(sim::energies(w).kinetic_mj - k0, work_mj, 1e-9));
  EXPECT_TRUE(test::rel_near(sim::energies(w).total_mj(), e0, 1e-9));
}

// The force on each particle: m g − α m v − β (K v) + its loads (N, kg·mm/s² converted), zero
// on a fixed particle. Here K is one spring's at rest along x: k n nᵀ, so β K v = β k v_x x̂ on
// the free end.
TEST(ExternalForces, GravityRayleighDampingAndLoadsAddUp) {
  constexpr double m = 0.5, alpha = 3.0, beta = 0.01, k = 2.0;
  const Vec3 g(0, -9000, 0), v(4, 5, -6), load(0.1, 0.2, 0.3);
  sim::World w;
  w.particles().add(Vec3::Zero(), m);
  w.particles().add(Vec3(10, 0, 0), m, v);
  w.particles().add(Vec3(0, 20, 0), m, v);
  w.particles().set_fixed(0, true);
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{0, 1, 10.0, k, 0.0}});
  w.external().gravity_mm_s2 = g;
  w.external().damping = {alpha, beta};
  w.external().point_loads = {{1, load}, {2, load}, {2, load}, {0, load}};
  w.compute_forces();
  const auto& f = w.particles().forces();
  const Vec3 body = sim::kKgMmPerS2ToNewton * m * (g - alpha * v);
  EXPECT_TRUE(test::near((f[1] - (body - beta * k * Vec3(v.x(), 0, 0) + load)).norm(), 0.0, 1e-12));
  EXPECT_TRUE(test::near((f[2] - (body + 2.0 * load)).norm(), 0.0, 1e-12));
  EXPECT_EQ(f[0], Vec3::Zero());
  w.external().point_loads.push_back({3, load});
  EXPECT_THROW(w.compute_forces(), InvalidInput) << "a load on a particle that does not exist";
}

// A plane tilted 30° about x; a particle thrown at it ends each step on or above it (projected
// along the normal), loses its normal velocity when it hits (no bounce) and keeps the
// tangential one (no friction); a fixed particle below the plane is left where it is.
TEST(ExternalForces, PlanesStopWhatFallsWithoutBouncingOrFriction) {
  const Vec3 n = Vec3(0, -std::sin(kPi / 6), std::cos(kPi / 6));
  sim::World w;
  w.external().planes.push_back({Vec3(0, 0, 0), 2.0 * n});  // normalised on use
  const Vec3 v0 = Vec3(30, 0, 0) - 200.0 * n;               // tangential along x, into the plane
  w.particles().add(Vec3(0, 0, 0) + 1.0 * n, 1.0, v0);
  w.particles().add(Vec3(0, 0, 0) - 3.0 * n, 1.0);
  w.particles().set_fixed(1, true);
  w.set_integrator("symplectic_euler");
  bool hit = false;
  for (int s = 0; s < 20; ++s) {
    w.step(0.001);
    const Vec3& x = w.particles().positions()[0];
    const Vec3& v = w.particles().velocities()[0];
    EXPECT_GE(x.dot(n), -1e-12) << "step " << s;
    if (x.dot(n) < 1e-12) {
      hit = true;
      EXPECT_TRUE(test::near(v.dot(n), 0.0, 1e-12)) << "bounced at step " << s;
    }
    EXPECT_TRUE(test::near(v.x(), 30.0, 1e-12)) << "friction at step " << s;
  }
  EXPECT_TRUE(hit);
  EXPECT_TRUE(test::near((w.particles().positions()[1] + 3.0 * n).norm(), 0.0, 1e-15));
}

}  // namespace
}  // namespace ido

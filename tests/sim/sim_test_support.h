// SPDX-License-Identifier: Apache-2.0
// Small builders shared by the sim tests.
#pragma once

#include <random>

#include "ido/sim/fem_common.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/world.h"

namespace ido::test {

/// One particle on a spring to a fixed anchor at the origin, moving along x:
/// k = 1e-3 N/mm, m = 1 kg, so ω² = k / (m · 1e-3) = 1 rad²/s². Starts 1 mm from rest
/// (rest length 10 mm), at rest: x(t) = 10 + cos t, v(t) = −sin t.
inline sim::World harmonic_oscillator() {
  sim::World w;
  w.set_threaded(false);
  w.particles().add(Vec3::Zero(), 1.0);
  w.particles().add(Vec3(11.0, 0.0, 0.0), 1.0);
  w.particles().set_fixed(0, true);
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{0, 1, 10.0, 1e-3, 0.0}});
  return w;
}

/// A random rotation matrix.
inline Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

}  // namespace ido::test

// SPDX-License-Identifier: Apache-2.0
// Particles: indices in order of addition, inverse masses kept consistent with the fixed flag
// through every change, velocities zeroed when fixed, growth, and non-positive masses refused.
#include "ido/sim/particles.h"

#include <cmath>

#include <gtest/gtest.h>

#include "ido/core/error.h"

namespace ido {
namespace {

TEST(Particles, InverseMassFollowsMassAndFixedFlag) {
  sim::Particles p;
  EXPECT_EQ(p.add(Vec3(1, 2, 3), 2.0, Vec3(4, 5, 6)), 0u);
  EXPECT_EQ(p.add(Vec3(7, 8, 9), 0.5), 1u);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.positions()[1], Vec3(7, 8, 9));
  EXPECT_EQ(p.velocities()[0], Vec3(4, 5, 6));
  EXPECT_EQ(p.velocities()[1], Vec3::Zero());
  EXPECT_EQ(p.forces()[0], Vec3::Zero());
  EXPECT_EQ(p.inverse_masses()[0], 0.5);
  EXPECT_EQ(p.inverse_masses()[1], 2.0);
  EXPECT_FALSE(p.fixed(0));

  p.set_fixed(0, true);  // fixed: at rest, infinite mass, but its mass is kept
  EXPECT_TRUE(p.fixed(0));
  EXPECT_EQ(p.velocities()[0], Vec3::Zero());
  EXPECT_EQ(p.inverse_masses()[0], 0.0);
  EXPECT_EQ(p.masses()[0], 2.0);
  p.set_mass(0, 4.0);  // a fixed particle's new mass does not free it
  EXPECT_EQ(p.inverse_masses()[0], 0.0);
  p.set_fixed(0, false);
  EXPECT_EQ(p.inverse_masses()[0], 0.25);
  p.set_mass(1, 8.0);
  EXPECT_EQ(p.inverse_masses()[1], 0.125);

  p.forces()[1] = Vec3(1, 1, 1);
  p.clear_forces();
  EXPECT_EQ(p.forces()[1], Vec3::Zero());
}

TEST(Particles, GrowsWithUnitMassesAtRestAndRefusesNonPositiveMasses) {
  sim::Particles p;
  p.add(Vec3(1, 1, 1), 3.0);
  p.resize(4);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p.masses()[0], 3.0);
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_EQ(p.positions()[i], Vec3::Zero());
    EXPECT_EQ(p.velocities()[i], Vec3::Zero());
    EXPECT_EQ(p.masses()[i], 1.0);
    EXPECT_EQ(p.inverse_masses()[i], 1.0);
    EXPECT_FALSE(p.fixed(i));
  }
  for (const double m : {0.0, -1.0, std::nan("")}) {
    EXPECT_THROW(p.add(Vec3::Zero(), m), InvalidInput) << m;
    EXPECT_THROW(p.set_mass(0, m), InvalidInput) << m;
  }
  EXPECT_EQ(p.size(), 4u);
  EXPECT_EQ(p.masses()[0], 3.0);
}

}  // namespace
}  // namespace ido

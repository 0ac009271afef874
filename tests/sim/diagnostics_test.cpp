// SPDX-License-Identifier: Apache-2.0
// Diagnostics: the kinetic, gravitational and per-model elastic energies of a known state, and
// the momentum of a rigid spin (L = I ω about its axis, P = 0) and of a translation, with the
// change of reference point L_o' = L_o − (o' − o) × P.
#include "ido/sim/diagnostics.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "ido/sim/mass_spring.h"
#include "ido/sim/units.h"
#include "ido/sim/world.h"
#include "support/test_support.h"

namespace ido {
namespace {

// Two particles on a stretched spring and a third one alone, moving, under a slanted gravity:
// kinetic ½ Σ m v², gravitational −Σ m g·x (kg·mm/s² · mm converted to mJ), and each model's
// elastic energy in the order of World::models(), with its kind.
TEST(Diagnostics, EnergiesOfAKnownState) {
  sim::World w;
  w.particles().add(Vec3(0, 0, 0), 0.5, Vec3(10, 0, 0));
  w.particles().add(Vec3(12, 0, 0), 0.25, Vec3(0, -20, 0));
  w.particles().add(Vec3(1, 2, 3), 2.0, Vec3(1, 2, 2));
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{0, 1, 10.0, 0.3, 0.0}});
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{1, 2, 1.0, 2.0, 0.0}});
  w.external().gravity_mm_s2 = Vec3(0, 3000, -9000);
  const sim::EnergyReport e = sim::energies(w);
  const double c = sim::kKgMmPerS2ToNewton;
  EXPECT_TRUE(test::rel_near(e.kinetic_mj, 0.5 * (0.5 * 100 + 0.25 * 400 + 2.0 * 9) * c, 1e-15));
  EXPECT_TRUE(test::rel_near(e.gravitational_mj, -(0.25 * 0 + 2.0 * (3000.0 * 2 - 9000.0 * 3)) * c, 1e-15));
  ASSERT_EQ(e.elastic_mj.size(), 2u);
  EXPECT_TRUE(test::rel_near(e.elastic_mj[0], 0.5 * 0.3 * 2.0 * 2.0, 1e-14));
  const double l = (Vec3(12, 0, 0) - Vec3(1, 2, 3)).norm();
  EXPECT_TRUE(test::rel_near(e.elastic_mj[1], 0.5 * 2.0 * (l - 1.0) * (l - 1.0), 1e-14));
  EXPECT_EQ(e.model_kinds, (std::vector<std::string>{"mass_spring", "mass_spring"}));
  EXPECT_TRUE(test::rel_near(e.elastic_total_mj(), e.elastic_mj[0] + e.elastic_mj[1], 1e-15));
  EXPECT_TRUE(test::rel_near(e.total_mj(), e.kinetic_mj + e.gravitational_mj + e.elastic_total_mj(), 1e-15));
}

// Particles on a ring of radius r in the plane z = h, spinning at ω about the z axis: no linear
// momentum, angular momentum (0, 0, Σ m r² ω) about any point of the axis; translated at u, the
// linear momentum is M u and the angular momentum about o' follows L_o − (o' − o) × P.
TEST(Diagnostics, MomentumOfASpinAndOfATranslation) {
  constexpr double r = 7.0, h = 3.0, omega = 2.5;
  sim::Particles p;
  double mass = 0.0;
  for (int i = 0; i < 6; ++i) {
    const double a = 2.0 * kPi * i / 6.0, m = 0.1 * (1 + i % 2);  // alternate masses, still balanced
    const Vec3 x(r * std::cos(a), r * std::sin(a), h);
    p.add(x, m, omega * Vec3(-x.y(), x.x(), 0));
    mass += m;
  }
  const double i_zz = mass * r * r;
  for (const Vec3& o : {Vec3(0, 0, 0), Vec3(0, 0, -20)}) {
    const sim::Momentum m = sim::momentum(p, o);
    EXPECT_TRUE(test::near(m.linear_kg_mm_s.norm(), 0.0, 1e-12));
    EXPECT_TRUE(test::near((m.angular_kg_mm2_s - Vec3(0, 0, i_zz * omega)).norm(), 0.0, 1e-11));
  }
  const Vec3 u(3, -4, 12);
  for (auto& v : p.velocities()) v = u;
  const sim::Momentum about_origin = sim::momentum(p);
  EXPECT_TRUE(test::near((about_origin.linear_kg_mm_s - mass * u).norm(), 0.0, 1e-12));
  const Vec3 o(5, -1, 8);
  const sim::Momentum about_o = sim::momentum(p, o);
  EXPECT_TRUE(test::near((about_o.angular_kg_mm2_s - (about_origin.angular_kg_mm2_s - o.cross(about_origin.linear_kg_mm_s))).norm(),
                         0.0, 1e-11));
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// Mass–spring: one spring's force, damping and energy against Hooke's law, the springs along a
// mesh's edges, the spring checks, and the stiffness against finite differences.
#include "ido/sim/mass_spring.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

// One spring (k = 0.4 N/mm, L₀ = 5 mm) stretched to l along a slanted direction n, the ends
// moving apart along n at 3 mm/s and sideways: f_a = −[k (l − L₀) + c (v_a − v_b)·n] n = −f_b
// (the sideways motion gives no force), energy ½ k (l − L₀)², also when compressed.
TEST(MassSpring, OneSpringFollowsHookesLawAlongItself) {
  constexpr double k = 0.4, c = 0.05, rest = 5.0;
  const Vec3 n = Vec3(1, -2, 2).normalized();
  for (const double l : {7.5, 3.0}) {
    sim::Particles p;
    p.add(Vec3(1, 2, 3) + l * n, 1.0, 1.5 * n + Vec3(2, 1, 0).cross(n));
    p.add(Vec3(1, 2, 3), 1.0, -1.5 * n);
    const sim::MassSpring spring({{0, 1, rest, k, c}});
    const auto f = test::model_forces(spring, p);
    const Vec3 expected = -(k * (l - rest) + c * 3.0) * n;
    EXPECT_TRUE(test::near((f[0] - expected).norm(), 0.0, 1e-14)) << "l = " << l;
    EXPECT_TRUE(test::near((f[0] + f[1]).norm(), 0.0, 1e-15)) << "l = " << l;
    EXPECT_TRUE(test::rel_near(spring.energy(p), 0.5 * k * (l - rest) * (l - rest), 1e-14)) << "l = " << l;
  }
}

// The springs of a mesh's edges: one per unique edge (a single Kuhn-split cube: 12 edges, 6 face
// diagonals, the main diagonal), with the mesh's lengths as rest lengths and indices offset by
// the first particle; the mesh at rest has no force and no energy.
TEST(MassSpring, SpringsAlongTheUniqueEdgesOfAMesh) {
  const auto cube = sim::make_cube(2.0, 1);
  const auto model = sim::MassSpring::from_tet_edges(cube, 3, 0.7, 0.01);
  ASSERT_EQ(model.springs().size(), 19u);
  int sides = 0, diagonals = 0, main = 0;
  for (const sim::Spring& s : model.springs()) {
    ASSERT_GE(s.a, 3);
    ASSERT_GE(s.b, 3);
    const double l = (cube.vertices[std::size_t(s.a - 3)] - cube.vertices[std::size_t(s.b - 3)]).norm();
    EXPECT_EQ(s.rest_length_mm, l);
    EXPECT_EQ(s.stiffness_n_per_mm, 0.7);
    EXPECT_EQ(s.damping_n_s_per_mm, 0.01);
    sides += std::abs(l - 2.0) < 1e-12;
    diagonals += std::abs(l - 2.0 * std::sqrt(2.0)) < 1e-12;
    main += std::abs(l - 2.0 * std::sqrt(3.0)) < 1e-12;
  }
  EXPECT_EQ(sides, 12);
  EXPECT_EQ(diagonals, 6);
  EXPECT_EQ(main, 1);
  sim::Particles p;
  for (int i = 0; i < 3; ++i) p.add(Vec3(-9, -9, -9), 1.0);
  for (const Vec3& v : cube.vertices) p.add(v, 1.0);
  for (const Vec3& f : test::model_forces(model, p)) EXPECT_EQ(f, Vec3::Zero());
  EXPECT_EQ(model.energy(p), 0.0);
}

TEST(MassSpring, BadSpringsAreRefusedNamingTheSpring) {
  auto message = [](const std::vector<sim::Spring>& springs) {
    try {
      (void)sim::MassSpring(springs);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const sim::Spring good{0, 1, 1.0, 1.0, 0.0};
  EXPECT_EQ(message({good}), "accepted");
  for (const sim::Spring& bad : {sim::Spring{0, 0, 1.0, 1.0, 0.0}, sim::Spring{-1, 1, 1.0, 1.0, 0.0},
                                 sim::Spring{0, 1, 0.0, 1.0, 0.0}, sim::Spring{0, 1, 1.0, -1.0, 0.0},
                                 sim::Spring{0, 1, 1.0, 1.0, -0.1}})
    EXPECT_EQ(message({good, bad}).rfind("spring 1: ", 0), 0u) << message({good, bad});
}

TEST(Stiffness, MassSpringMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  const auto mesh = test::irregular_cube();
  const auto model = sim::MassSpring::from_tet_edges(mesh, 0, 2.0);
  EXPECT_LT(test::stiffness_fd_error(model, test::deformed(mesh, 1.0, rng), rng), 1e-5);
}

}  // namespace
}  // namespace ido

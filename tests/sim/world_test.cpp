// SPDX-License-Identifier: Apache-2.0
// The world: tetrahedral bodies get lumped masses (a quarter of each tetrahedron's ρV per
// corner) and bad meshes are refused naming the element; a step advances time and count and
// keeps fixed particles at rest with zero force; threaded, serial and concurrent worlds give the
// same positions; the static solve reaches a tripod's analytic equilibrium, and refuses a body
// that nothing holds.
#include "ido/sim/world.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/units.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

using test::beam_world;

// Each vertex gets ¼ ρ V of every tetrahedron it belongs to, so the body's mass is ρ times its
// volume; a second body's particles follow the first's.
TEST(World, TetBodiesGetLumpedMassesAndFollowOneAnother) {
  sim::World w;
  const auto first = sim::make_beam({4, 3, 2}, {2, 3, 1});
  const auto second = sim::make_cube(2.0, 1, Vec3(10, 0, 0));
  EXPECT_EQ(w.add_tet_body(first, 1200.0), 0);
  EXPECT_EQ(w.add_tet_body(second, 800.0), std::int32_t(first.vertices.size()));
  ASSERT_EQ(w.particles().size(), first.vertices.size() + second.vertices.size());
  const double rho1 = 1200.0 * sim::kKgPerM3ToKgPerMm3, rho2 = 800.0 * sim::kKgPerM3ToKgPerMm3;
  std::vector<double> expected(w.particles().size(), 0.0);
  for (const auto& [mesh, rho, offset] : {std::tuple{&first, rho1, std::size_t(0)},
                                          std::tuple{&second, rho2, first.vertices.size()}})
    for (const Tet& t : mesh->tets) {
      const auto& v = mesh->vertices;
      const double vol = std::abs((v[std::size_t(t[1])] - v[std::size_t(t[0])])
                                      .dot((v[std::size_t(t[2])] - v[std::size_t(t[0])]).cross(v[std::size_t(t[3])] - v[std::size_t(t[0])]))) /
                         6.0;
      for (const auto i : t) expected[offset + std::size_t(i)] += 0.25 * rho * vol;
    }
  double m1 = 0.0, m2 = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_TRUE(test::rel_near(w.particles().masses()[i], expected[i], 1e-14)) << i;
    (i < first.vertices.size() ? m1 : m2) += w.particles().masses()[i];
    const Vec3& x = i < first.vertices.size() ? first.vertices[i] : second.vertices[i - first.vertices.size()];
    EXPECT_EQ(w.particles().positions()[i], x);
  }
  EXPECT_TRUE(test::rel_near(m1, rho1 * 24.0, 1e-13));
  EXPECT_TRUE(test::rel_near(m2, rho2 * 8.0, 1e-13));
}

TEST(World, BadBodiesAreRefusedNamingTheElement) {
  auto message = [](const geometry::TetMesh& mesh, double density) {
    sim::World w;
    try {
      (void)w.add_tet_body(mesh, density);
    } catch (const InvalidInput& e) {
      EXPECT_EQ(w.particles().size(), 0u) << "a refused body left particles";
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const auto cube = sim::make_cube(1.0, 1);
  EXPECT_EQ(message(cube, 1000.0), "accepted");
  EXPECT_NE(message(cube, 0.0).find("density"), std::string::npos);
  EXPECT_NE(message(geometry::TetMesh{}, 1000.0).find("no vertices"), std::string::npos);
  auto inverted = cube;
  std::swap(inverted.tets[4][2], inverted.tets[4][3]);
  EXPECT_NE(message(inverted, 1000.0).find("tetrahedron 4 is inverted"), std::string::npos) << message(inverted, 1000.0);
  auto out_of_range = cube;
  out_of_range.tets[2][1] = 8;
  EXPECT_NE(message(out_of_range, 1000.0).find("tetrahedron 2"), std::string::npos);
  auto unused = cube;
  unused.vertices.emplace_back(5, 5, 5);
  EXPECT_NE(message(unused, 1000.0).find("vertex 8 belongs to no tetrahedron"), std::string::npos);
}

// A step advances the time by dt and the count by one; a fixed particle gets no force, no
// acceleration and stays where it is; a bad dt is refused and changes nothing.
TEST(World, StepsCountTimeAndKeepFixedParticlesPut) {
  auto w = beam_world(false);
  const auto x0 = w.particles().positions();
  for (int i = 0; i < 3; ++i) w.step(0.004);
  EXPECT_EQ(w.step_count(), 3);
  EXPECT_TRUE(test::near(w.time_s(), 0.012, 1e-15));
  w.compute_forces();
  const auto a = w.accelerations();
  bool moved = false;
  for (std::size_t i = 0; i < x0.size(); ++i)
    if (w.particles().fixed(i)) {
      EXPECT_EQ(w.particles().positions()[i], x0[i]);
      EXPECT_EQ(w.particles().velocities()[i], Vec3::Zero());
      EXPECT_EQ(w.particles().forces()[i], Vec3::Zero());
      EXPECT_EQ(a[i], Vec3::Zero());
    } else {
      moved = moved || w.particles().positions()[i] != x0[i];
      EXPECT_TRUE(test::near((a[i] - w.particles().forces()[i] / (w.particles().masses()[i] * sim::kKgMmPerS2ToNewton)).norm(),
                             0.0, 1e-9 * a[i].norm()));
    }
  EXPECT_TRUE(moved);
  EXPECT_THROW(w.step(0.0), InvalidInput);
  EXPECT_THROW(w.step(std::nan("")), InvalidInput);
  EXPECT_EQ(w.step_count(), 3);
  const auto revision = w.model_revision();
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{0, 1, 1.0, 1.0, 0.0}});
  EXPECT_NE(w.model_revision(), revision) << "a scheme caching the models would not see the new one";
}

std::vector<Vec3> run_beam(bool threaded, int steps) {
  auto w = beam_world(threaded);
  for (int i = 0; i < steps; ++i) w.step(0.01);
  EXPECT_GT(w.last_step().cg_iterations, 0);
  return w.particles().positions();
}

TEST(WorldDeterminism, ThreadedAndConcurrentWorldsMatchSerial) {
  const auto serial = run_beam(false, 10);
  const auto threaded = run_beam(true, 10);
  std::vector<Vec3> a, b;
  std::thread t1([&] { a = run_beam(true, 10); });
  std::thread t2([&] { b = run_beam(false, 10); });
  t1.join();
  t2.join();
  double max_diff = 0.0;
  for (std::size_t i = 0; i < serial.size(); ++i)
    max_diff = std::max({max_diff, (serial[i] - threaded[i]).norm(), (serial[i] - a[i]).norm(),
                         (serial[i] - b[i]).norm()});
  EXPECT_TRUE(test::near(max_diff, 0.0, 0.0));
  // and the beam really moved (sagged under gravity)
  double min_z = 1e9;
  for (const auto& x : serial) min_z = std::min(min_z, x.z());
  EXPECT_LT(min_z, -0.01);
}

// Three springs (k, rest length L₀) from a fixed triangle of radius r to a free apex pulled up
// by F: by symmetry the apex stays on the axis at the height z where 3 k (l − L₀) z / l = F,
// l = √(r² + z²). Newton with the springs' exact stiffness lands there.
TEST(SolveStatic, TripodReachesItsAnalyticEquilibrium) {
  constexpr double k = 0.3, r = 5.0, h = 4.0, z_star = 4.6;
  sim::World w;
  for (int i = 0; i < 3; ++i) {
    const double a = 2.0 * kPi * i / 3.0;
    w.particles().add(Vec3(r * std::cos(a), r * std::sin(a), 0.0), 1.0);
    w.particles().set_fixed(std::size_t(i), true);
  }
  w.particles().add(Vec3(0, 0, h), 1.0);
  const double rest = std::hypot(r, h), l_star = std::hypot(r, z_star);
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{0, 3, rest, k, 0.0}, {1, 3, rest, k, 0.0}, {2, 3, rest, k, 0.0}});
  const double f = 3.0 * k * (l_star - rest) * z_star / l_star;
  w.external().point_loads.push_back({3, Vec3(0, 0, f)});
  w.particles().velocities()[3] = Vec3(1, 2, 3);
  const auto result = sim::solve_static(w, {.max_newton_iterations = 20, .force_tolerance_n = 1e-13});
  EXPECT_TRUE(result.converged);
  EXPECT_LE(result.max_residual_force_n, 1e-13);
  EXPECT_TRUE(test::near((w.particles().positions()[3] - Vec3(0, 0, z_star)).norm(), 0.0, 1e-10));
  EXPECT_EQ(w.particles().velocities()[3], Vec3::Zero());

  for (int i = 0; i < 3; ++i) w.particles().set_fixed(std::size_t(i), false);
  EXPECT_THROW((void)sim::solve_static(w), InvalidInput) << "nothing holds the tripod";
}

}  // namespace
}  // namespace ido

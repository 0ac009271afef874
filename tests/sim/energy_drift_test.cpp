// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "ido/sim/diagnostics.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

// A free 3×3×3 spring lattice (springs along the edges of a tetrahedralised cube) with
// random initial velocities; no damping, no gravity.
sim::World lattice() {
  sim::World w;
  w.set_threaded(false);
  const auto mesh = sim::make_cube(20.0, 2);
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<sim::MassSpring>(sim::MassSpring::from_tet_edges(mesh, 0, 1.0));
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 100.0);
  for (auto& v : w.particles().velocities()) v = Vec3(n(rng), n(rng), n(rng));
  return w;
}

// Largest angular frequency of the lattice at rest: √λ_max of M⁻¹K (M in N·s²/mm).
double max_omega(const sim::World& w) {
  const Eigen::MatrixXd k = Eigen::MatrixXd(w.models()[0]->stiffness_matrix(w.particles()));
  Eigen::VectorXd m(k.rows());
  for (std::size_t i = 0; i < w.particles().size(); ++i)
    m.segment<3>(static_cast<Eigen::Index>(3 * i)).setConstant(1e-3 * w.particles().masses()[i]);
  const Eigen::MatrixXd a = m.cwiseInverse().cwiseSqrt().asDiagonal() * k *
                            m.cwiseInverse().cwiseSqrt().asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a);
  return std::sqrt(eig.eigenvalues().maxCoeff());
}

// Largest |E(t) − E(0)| / E(0) over 1e5 steps.
double max_relative_drift(const std::string& scheme) {
  auto w = lattice();
  w.set_integrator(scheme);
  const double dt = 5e-4 / max_omega(w);
  const double e0 = sim::energies(w).total_mj();
  double worst = 0.0;
  for (int s = 0; s < 100000; ++s) {
    w.step(dt);
    if (s % 10 == 0) worst = std::max(worst, std::abs(sim::energies(w).total_mj() - e0) / e0);
  }
  return worst;
}

TEST(EnergyDrift, SymplecticEulerBelowOnePerMille) {
  EXPECT_LT(max_relative_drift("symplectic_euler"), 1e-3);
}

TEST(EnergyDrift, VelocityVerletBelowOnePerMille) {
  EXPECT_LT(max_relative_drift("velocity_verlet"), 1e-3);
}

TEST(EnergyDrift, ExplicitEulerGainsEnergy) {
  auto w = lattice();
  w.set_integrator("explicit_euler");
  const double dt = 5e-4 / max_omega(w);
  const double e0 = sim::energies(w).total_mj();
  for (int s = 0; s < 100000; ++s) w.step(dt);
  // Same run, same criterion: explicit Euler fails it, and the error is a gain.
  EXPECT_GT((sim::energies(w).total_mj() - e0) / e0, 1e-3);
}

TEST(Momentum, FreeLatticeConservesLinearAndAngularMomentum) {
  auto w = lattice();
  w.set_integrator("velocity_verlet");
  const auto m0 = sim::momentum(w.particles());
  const double dt = 0.1 / max_omega(w);
  for (int s = 0; s < 2000; ++s) w.step(dt);
  const auto m1 = sim::momentum(w.particles());
  const double scale = m0.linear_kg_mm_s.norm() + 1e-3;
  EXPECT_TRUE(test::near((m1.linear_kg_mm_s - m0.linear_kg_mm_s).norm(), 0.0, 1e-10 * scale));
  EXPECT_TRUE(test::near((m1.angular_kg_mm2_s - m0.angular_kg_mm2_s).norm(), 0.0,
                         1e-8 * (m0.angular_kg_mm2_s.norm() + 1.0)));
}

}  // namespace
}  // namespace ido

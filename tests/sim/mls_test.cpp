// SPDX-License-Identifier: Apache-2.0
// Point-based MLS elasticity (Müller et al. 2004): the strain of a linear displacement is
// reproduced exactly, forces are the negative energy gradient, rigid motion gives no force and a
// stretched body relaxes, and too small a support is refused.
#include "ido/sim/mls.h"

#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

sim::MlsOptions mls_options() {
  return {.support_radius_mm = 4.5, .material = {1e6, 0.3}, .volume_stiffness_pa = 1e5};
}

std::vector<std::int32_t> all_indices(std::size_t n) {
  std::vector<std::int32_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::int32_t>(i);
  return v;
}

TEST(Mls, ReproducesStrainOfLinearDisplacementExactly) {
  auto p = test::point_cloud();
  const sim::MlsElasticity model(p, all_indices(p.size()), mls_options());
  Mat3 g;
  g << 0.05, -0.02, 0.03, 0.01, 0.04, -0.06, 0.02, 0.07, -0.03;
  for (auto& x : p.positions()) x = x + g * x + Vec3(1, 2, 3);
  const Mat3 expected = 0.5 * (g + g.transpose() + g.transpose() * g);
  for (const auto& e : model.green_strains(p))
    EXPECT_TRUE(test::near((e - expected).cwiseAbs().maxCoeff(), 0.0, 1e-10));
}

TEST(Mls, ForcesAreTheNegativeEnergyGradient) {
  auto p = test::point_cloud();
  const sim::MlsElasticity model(p, all_indices(p.size()), mls_options());
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (auto& x : p.positions()) x += Vec3(u(rng), u(rng), u(rng));
  std::vector<Vec3> f(p.size(), Vec3::Zero());
  model.add_forces(p, f, true);
  const double h = 1e-6;
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < p.size(); i += 17)
    for (int c = 0; c < 3; ++c) {
      auto q = p;
      q.positions()[i][c] += h;
      const double ep = model.energy(q);
      q.positions()[i][c] -= 2 * h;
      const double em = model.energy(q);
      worst = std::max(worst, std::abs(-(ep - em) / (2 * h) - f[i][c]));
      scale = std::max(scale, std::abs(f[i][c]));
    }
  EXPECT_LT(worst, 1e-5 * scale);
}

TEST(Mls, RigidMotionGivesNoForceAndSimulationRelaxes) {
  sim::World w;
  w.particles() = test::point_cloud();
  w.emplace_model<sim::MlsElasticity>(w.particles(), all_indices(w.particles().size()), mls_options());
  std::mt19937 rng(4);
  const Mat3 r = test::random_rotation(rng);
  auto q = w.particles();
  for (auto& x : q.positions()) x = r * x;
  std::vector<Vec3> f(q.size(), Vec3::Zero());
  w.models()[0]->add_forces(q, f, true);
  for (const auto& fi : f) EXPECT_TRUE(test::near(fi.norm(), 0.0, 1e-12));
  // Stretch by 10 %, let it relax with damping: energy falls to ~0.
  for (auto& x : w.particles().positions()) x.x() *= 1.1;
  const double e0 = w.models()[0]->energy(w.particles());
  w.external().damping.mass_per_s = 200.0;
  for (int s = 0; s < 1000; ++s) w.step(1e-4);
  EXPECT_LT(w.models()[0]->energy(w.particles()), 1e-3 * e0);
}

TEST(Mls, RejectsTooSmallSupport) {
  const auto p = test::point_cloud();
  auto options = mls_options();
  options.support_radius_mm = 1.0;
  EXPECT_THROW(sim::MlsElasticity(p, all_indices(p.size()), options), InvalidInput);
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// Corotational FEM cantilever under a small tip load against Euler–Bernoulli beam theory,
// δ = F L³ / (3 E I), I = b h³ / 12.
#include <cmath>

#include <gtest/gtest.h>

#include "ido/sim/fem_corotational.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

constexpr double kLength = 100.0, kWidth = 10.0, kHeight = 10.0;   // mm
constexpr double kYoung = 1e6;                                      // Pa
constexpr double kTipLoad = 1e-3;                                   // N (small: linear regime)

// Two cells across the width: with ν = 0 there is no anticlastic bending, so the width
// direction needs little resolution; bending accuracy of linear tetrahedra is governed by
// the cells through the height (shear locking falls as O(h²)).
double tip_deflection(int cells_through_thickness) {
  const int n = cells_through_thickness;
  const auto mesh = sim::make_beam({kLength, kWidth, kHeight}, {10 * n, 2, n});
  sim::World w;
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<sim::CorotationalFem>(mesh.tets, w.particles().positions(),
                                        sim::ElasticMaterial{kYoung, 0.0});
  std::vector<std::int32_t> tip;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (mesh.vertices[i].x() < 1e-9) w.particles().set_fixed(i, true);
    if (mesh.vertices[i].x() > kLength - 1e-9) tip.push_back(static_cast<std::int32_t>(i));
  }
  for (auto i : tip) w.external().point_loads.push_back({i, Vec3(0, 0, -kTipLoad / tip.size())});
  // Equilibrium to 1e-8 of the applied load: the deflection error studied here is ≥ 1e-3, and
  // an absolute 1e-12 N sits at the round-off floor of the summed element forces.
  const auto r = sim::solve_static(w, {.max_newton_iterations = 10, .force_tolerance_n = 1e-8 * kTipLoad});
  EXPECT_TRUE(r.converged) << "residual " << r.max_residual_force_n << " N after " << r.newton_iterations;
  double sum = 0.0;
  for (auto i : tip) sum += mesh.vertices[static_cast<std::size_t>(i)].z() -
                            w.particles().positions()[static_cast<std::size_t>(i)].z();
  return sum / tip.size();
}

TEST(Cantilever, TipDeflectionConvergesToEulerBernoulli) {
  const double e = kYoung * 1e-6;   // N/mm²
  const double inertia = kWidth * std::pow(kHeight, 3) / 12.0;
  const double analytic = kTipLoad * std::pow(kLength, 3) / (3.0 * e * inertia);
  double previous_error = 1e9;
  for (int n : {4, 8, 16}) {
    const double err = std::abs(tip_deflection(n) - analytic) / analytic;
    std::printf("cells through thickness %d: relative error %.4f\n", n, err);
    EXPECT_LT(err, previous_error);
    previous_error = err;
  }
  EXPECT_LT(previous_error, 0.02);
}

}  // namespace
}  // namespace ido

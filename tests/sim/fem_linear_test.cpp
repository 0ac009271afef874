// SPDX-License-Identifier: Apache-2.0
// Linear FEM: the patch test, the analytic stress and stored energy of a uniaxial stretch, forces
// as the negative energy gradient, stiffness against finite differences, and the spurious
// forces under rotation that corotational FEM exists to remove.
#include "ido/sim/fem_linear.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ido/sim/units.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(LinearFem, PatchTestAffineDisplacementGivesConstantStrainAndZeroInteriorForce) {
  const auto mesh = test::irregular_cube();
  auto p = test::particles_of(mesh);
  sim::LinearFem model(mesh.tets, p.positions(), test::kFemMaterial);
  Mat3 a;
  a << 0.010, 0.002, -0.003, 0.001, -0.008, 0.004, 0.002, 0.003, 0.006;
  const Vec3 t(0.5, -0.2, 0.1);
  for (auto& x : p.positions()) x = x + a * x + t;
  const Mat3 eps = 0.5 * (a + a.transpose());
  for (const auto& F : model.deformation_gradients(p)) {
    const Mat3 e = 0.5 * (F + F.transpose()) - Mat3::Identity();
    EXPECT_TRUE(test::near((e - eps).cwiseAbs().maxCoeff(), 0.0, 1e-10));
  }
  const auto f = test::model_forces(model, p);
  double boundary_max = 0.0, interior_max = 0.0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const bool interior = mesh.vertices[i].cwiseAbs().maxCoeff() < 10.0 - 1e-9;
    (interior ? interior_max : boundary_max) = std::max(interior ? interior_max : boundary_max, f[i].norm());
  }
  EXPECT_GT(boundary_max, 1e-4);   // the boundary carries the traction
  EXPECT_TRUE(test::near(interior_max, 0.0, 1e-10 * boundary_max));
}

TEST(LinearFem, IsNotRotationInvariant) {
  // The reason corotational FEM exists: linear FEM gives spurious forces under rotation.
  const auto mesh = sim::make_cube(20.0, 2);
  auto p = test::particles_of(mesh);
  const sim::LinearFem model(mesh.tets, p.positions(), test::kFemMaterial);
  const Mat3 r = Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix();
  for (auto& x : p.positions()) x = r * x;
  EXPECT_GT(model.energy(p), 1.0);
}

TEST(Stiffness, LinearFemMatchesFiniteDifferences) {
  std::mt19937 rng(1);
  const auto mesh = test::irregular_cube();
  const sim::LinearFem model(mesh.tets, mesh.vertices, test::kFemMaterial);
  EXPECT_LT(test::stiffness_fd_error(model, test::deformed(mesh, 1.0, rng), rng), 1e-5);
}

TEST(FemModel, ElementFieldsUniaxialStretchGiveExpectedStress) {
  // Linear FEM, small uniaxial strain ε along x with free lateral contraction (−ν ε):
  // σ_xx = E ε, other components 0, von Mises = |σ_xx|.
  const auto mesh = sim::make_cube(10.0, 2);
  auto p = test::particles_of(mesh);
  const sim::LinearFem model(mesh.tets, p.positions(), test::kFemMaterial);
  const double eps = 1e-4;
  for (auto& x : p.positions()) x = Vec3(x.x() * (1 + eps), x.y() * (1 - 0.3 * eps), x.z() * (1 - 0.3 * eps));
  const auto fields = model.element_fields(p);
  ASSERT_TRUE(fields.has_value());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    EXPECT_TRUE(test::rel_near(fields->cauchy_stress_pa[e](0, 0), 1e6 * eps, 1e-3));
    EXPECT_TRUE(test::near(fields->cauchy_stress_pa[e](1, 1), 0.0, 1e-3 * 1e6 * eps));
    EXPECT_TRUE(test::rel_near(fields->von_mises_pa[e], 1e6 * eps, 1e-3));
    EXPECT_TRUE(test::rel_near(fields->green_strain[e](0, 0), eps + 0.5 * eps * eps, 1e-9));
  }
}

// The same stretch stores Ψ V = ½ σ:ε V = ½ E ε² V: linear strain is exactly uniform on any
// mesh under an affine map, so the sum over elements is the analytic value to rounding.
TEST(LinearFem, UniaxialStretchStoresHalfEEpsilonSquaredTimesVolume) {
  const auto mesh = test::irregular_cube();
  auto p = test::particles_of(mesh);
  const sim::LinearFem model(mesh.tets, p.positions(), test::kFemMaterial);
  const double eps = 1e-3, nu = test::kFemMaterial.poisson_ratio;
  for (auto& x : p.positions()) x = Vec3(x.x() * (1 + eps), x.y() * (1 - nu * eps), x.z() * (1 - nu * eps));
  const double e_n_per_mm2 = test::kFemMaterial.youngs_modulus_pa * sim::kPascalToNPerMm2;
  EXPECT_TRUE(test::rel_near(model.energy(p), 0.5 * e_n_per_mm2 * eps * eps * 20.0 * 20.0 * 20.0, 1e-9));
}

TEST(LinearFem, ForcesAreTheNegativeEnergyGradient) {
  std::mt19937 rng(21);
  const auto mesh = test::irregular_cube();
  const sim::LinearFem model(mesh.tets, mesh.vertices, test::kFemMaterial);
  EXPECT_LT(test::force_gradient_fd_error(model, test::deformed(mesh, 1.0, rng), rng), 1e-6);
}

}  // namespace
}  // namespace ido

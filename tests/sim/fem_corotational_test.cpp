// SPDX-License-Identifier: Apache-2.0
// Corotational linear FEM: no force or energy under rigid motion, the linear model's energy for a
// rotated pure stretch, forces as the negative energy gradient, the frozen-rotation stiffness
// at rotated rest shapes, and recovery from an inverted element.
#include "ido/sim/fem_corotational.h"

#include <random>

#include <gtest/gtest.h>

#include "ido/sim/fem_linear.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(CorotationalFem, ZeroForceAndEnergyUnder100RandomRotations) {
  test::expect_rotation_invariance<sim::CorotationalFem>();
}

// F = R S with S a symmetric stretch: the rotation of the polar decomposition is R, so the
// corotational energy μ|F − R|² + ½λ tr²(RᵀF − I) is the linear energy of S, however the body is
// turned.
TEST(CorotationalFem, RotatedStretchStoresTheLinearEnergyOfTheStretch) {
  const auto mesh = test::irregular_cube();
  const sim::CorotationalFem corotational(mesh.tets, mesh.vertices, test::kFemMaterial);
  const sim::LinearFem linear(mesh.tets, mesh.vertices, test::kFemMaterial);
  Mat3 s;
  s << 1.02, 0.01, -0.005, 0.01, 0.97, 0.008, -0.005, 0.008, 1.01;
  auto stretched = test::particles_of(mesh);
  for (auto& x : stretched.positions()) x = s * x;
  const double expected = linear.energy(stretched);
  ASSERT_GT(expected, 0.0);
  std::mt19937 rng(5);
  for (int k = 0; k < 20; ++k) {
    const Mat3 r = test::random_rotation(rng);
    auto q = stretched;
    for (auto& x : q.positions()) x = r * x + Vec3(k, 1, -k);
    EXPECT_TRUE(test::rel_near(corotational.energy(q), expected, 1e-9)) << "rotation " << k;
  }
}

TEST(CorotationalFem, ForcesAreTheNegativeEnergyGradient) {
  std::mt19937 rng(22);
  const auto mesh = test::irregular_cube();
  const sim::CorotationalFem model(mesh.tets, mesh.vertices, test::kFemMaterial);
  EXPECT_LT(test::force_gradient_fd_error(model, test::deformed(mesh, 1.0, rng), rng), 1e-6);
}

TEST(Stiffness, CorotationalMatchesFiniteDifferencesAtRotatedRest) {
  // The frozen-rotation tangent R K₀ Rᵀ is exact at rigidly moved rest shapes.
  std::mt19937 rng(4);
  const auto mesh = test::irregular_cube();
  const sim::CorotationalFem model(mesh.tets, mesh.vertices, test::kFemMaterial);
  auto p = test::particles_of(mesh);
  const Mat3 r = test::random_rotation(rng);
  for (auto& x : p.positions()) x = r * x + Vec3(3, 4, 5);
  EXPECT_LT(test::stiffness_fd_error(model, p, rng), 1e-5);
}

TEST(CorotationalFem, InvertedElementRecovers) { test::expect_inverted_element_recovers<sim::CorotationalFem>(); }

}  // namespace
}  // namespace ido

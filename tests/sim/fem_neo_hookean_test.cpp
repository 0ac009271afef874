// SPDX-License-Identifier: Apache-2.0
// Stable Neo-Hookean FEM: no force or energy under rigid motion, forces as the negative energy
// gradient, stiffness against finite differences when largely deformed, and recovery from an
// inverted element.
#include "ido/sim/fem_neo_hookean.h"

#include <random>

#include <gtest/gtest.h>

#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

TEST(NeoHookeanFem, ZeroForceAndEnergyUnder100RandomRotations) {
  test::expect_rotation_invariance<sim::NeoHookeanFem>();
}

TEST(NeoHookeanFem, ForcesAreTheNegativeEnergyGradient) {
  std::mt19937 rng(23);
  const auto mesh = test::irregular_cube();
  const sim::NeoHookeanFem model(mesh.tets, mesh.vertices, test::kFemMaterial);
  EXPECT_LT(test::force_gradient_fd_error(model, test::deformed(mesh, 2.0, rng), rng), 1e-6);
}

TEST(Stiffness, NeoHookeanMatchesFiniteDifferencesWhenLargelyDeformed) {
  std::mt19937 rng(2);
  const auto mesh = test::irregular_cube();
  sim::NeoHookeanFem model(mesh.tets, mesh.vertices, test::kFemMaterial);
  model.set_definite_stiffness(false);
  EXPECT_LT(test::stiffness_fd_error(model, test::deformed(mesh, 1.0, rng), rng), 1e-5);
}

TEST(NeoHookeanFem, InvertedElementRecovers) { test::expect_inverted_element_recovers<sim::NeoHookeanFem>(); }

}  // namespace
}  // namespace ido

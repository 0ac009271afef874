// SPDX-License-Identifier: Apache-2.0
// What the tetrahedral FEM models share: the polar rotation (against the SVD, and its quadratic
// convergence from a warm start), Lamé parameters, von Mises stress, signed volumes, and the
// checks of rest shapes and materials.
#include "ido/sim/fem_common.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/fem_linear.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

// The rotation maximising tr(RᵀF) over proper rotations, from the SVD F = U Σ Vᵀ (Kabsch):
// R = U diag(1, 1, det(U Vᵀ)) Vᵀ, the polar rotation when det F > 0.
Mat3 svd_rotation(const Mat3& F) {
  const Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

// F = Q1 diag(s) Q2 with well separated singular values in [0.3, 3]; inverted if asked.
Mat3 random_deformation(std::mt19937& rng, bool inverted) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double s0 = 0.3 + 0.8 * u(rng), s1 = 1.2 + 0.7 * u(rng), s2 = 2.0 + u(rng);
  Vec3 s(s0, s1, s2);
  if (inverted) s.x() = -s.x();
  return test::random_rotation(rng) * s.asDiagonal() * test::random_rotation(rng);
}

TEST(ExtractRotation, MatchesSvdForStretchedAndInvertedFromAnyStart) {
  std::mt19937 rng(11);
  for (int k = 0; k < 200; ++k) {
    const bool inverted = k % 2 == 1;
    const Mat3 F = random_deformation(rng, inverted);
    Eigen::Quaterniond q(test::random_rotation(rng));   // arbitrary (far) warm start
    const Mat3 r = sim::extract_rotation(F, q);
    EXPECT_TRUE(test::near((r - svd_rotation(F)).norm(), 0.0, 1e-9)) << "case " << k;
    EXPECT_TRUE(test::near(r.determinant(), 1.0, 1e-12));
    EXPECT_TRUE(test::near((q.toRotationMatrix() - r).norm(), 0.0, 1e-12));
  }
}

TEST(ExtractRotation, ConvergesQuadraticallyFromANearbyWarmStart) {
  // From a warm start 1e-3 rad off (a typical time step), four iterations must reach the
  // rotation to 1e-12: linear convergence at rate 1/3 (the plain Müller et al. iteration)
  // would need about twenty.
  std::mt19937 rng(12);
  for (int k = 0; k < 100; ++k) {
    const Mat3 F = random_deformation(rng, false);
    const Mat3 exact = svd_rotation(F);
    const Vec3 axis = test::random_rotation(rng).col(0);
    Eigen::Quaterniond q(Mat3(exact * Eigen::AngleAxisd(1e-3, axis).toRotationMatrix()));
    const Mat3 r = sim::extract_rotation(F, q, 4);
    EXPECT_TRUE(test::near((r - exact).norm(), 0.0, 1e-12)) << "case " << k;
  }
}

TEST(FemModel, RejectsInvertedRestShapeAndBadMaterial) {
  std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), Vec3(0, 0, 10)};
  EXPECT_THROW(sim::LinearFem({Tet{0, 2, 1, 3}}, x, test::kFemMaterial), InvalidInput);
  EXPECT_THROW(sim::LinearFem({Tet{0, 1, 2, 3}}, x, {1e6, 0.5}), InvalidInput);
  EXPECT_THROW(sim::LinearFem({Tet{0, 1, 2, 3}}, x, {-1.0, 0.3}), InvalidInput);
  EXPECT_THROW(sim::LinearFem({Tet{0, 1, 2, 7}}, x, test::kFemMaterial), InvalidInput);
}

// μ = E / (2(1 + ν)), λ = E ν / ((1 + ν)(1 − 2ν)) in N/mm²; they give back E = μ(3λ + 2μ)/(λ + μ)
// and ν = λ / (2(λ + μ)). Out-of-range materials are refused naming the parameter.
TEST(FemCommon, LameParametersAndMaterialChecks) {
  for (const sim::ElasticMaterial m : {sim::ElasticMaterial{1e6, 0.3}, sim::ElasticMaterial{2.5e4, 0.45},
                                       sim::ElasticMaterial{1e9, -0.2}, sim::ElasticMaterial{3e3, 0.0}}) {
    const sim::Lame l = sim::lame_parameters(m);
    const double e = m.youngs_modulus_pa * 1e-6, nu = m.poisson_ratio;
    EXPECT_TRUE(test::rel_near(l.mu, e / (2.0 * (1.0 + nu)), 1e-15));
    EXPECT_TRUE(test::near(l.lambda, e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), 1e-15 * e));
    EXPECT_TRUE(test::rel_near(l.mu * (3.0 * l.lambda + 2.0 * l.mu) / (l.lambda + l.mu), e, 1e-12));
    EXPECT_TRUE(test::near(l.lambda / (2.0 * (l.lambda + l.mu)), nu, 1e-12));
  }
  auto message = [](const sim::ElasticMaterial& m) {
    try {
      sim::check_material(m, "here");
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message({1e5, 0.3}), "accepted");
  for (const double e : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()})
    EXPECT_NE(message({e, 0.3}).find("here: youngs_modulus_pa"), std::string::npos) << message({e, 0.3});
  for (const double nu : {0.5, -1.0, 0.7, std::nan("")})
    EXPECT_NE(message({1e5, nu}).find("here: poisson_ratio"), std::string::npos) << message({1e5, nu});
  EXPECT_THROW((void)sim::lame_parameters({1e5, 0.5}), InvalidInput);
}

// Von Mises stress √(3/2 s:s): |σ| for uniaxial stress, √3 τ for pure shear, 0 for a pressure,
// unchanged by a change of frame.
TEST(FemCommon, VonMisesOfUniaxialShearAndHydrostaticStress) {
  Mat3 uniaxial = Mat3::Zero();
  uniaxial(0, 0) = -7.0;
  EXPECT_TRUE(test::rel_near(sim::von_mises(uniaxial), 7.0, 1e-15));
  Mat3 shear = Mat3::Zero();
  shear(0, 1) = shear(1, 0) = 2.0;
  EXPECT_TRUE(test::rel_near(sim::von_mises(shear), 2.0 * std::sqrt(3.0), 1e-15));
  EXPECT_TRUE(test::near(sim::von_mises(5.0 * Mat3::Identity()), 0.0, 1e-14));
  std::mt19937 rng(3);
  Mat3 a = Mat3::Random();
  const Mat3 sigma = a + a.transpose();
  const Mat3 r = test::random_rotation(rng);
  EXPECT_TRUE(test::rel_near(sim::von_mises(r * sigma * r.transpose()), sim::von_mises(sigma), 1e-12));
}

// (b − a)·((c − a) × (d − a)) / 6: 1/6 for the unit corner tetrahedron, the sign of the
// orientation, and invariant under translation; scaled by s³.
TEST(FemCommon, TetSignedVolume) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
  EXPECT_TRUE(test::rel_near(sim::tet_signed_volume(a, b, c, d), 1.0 / 6.0, 1e-15));
  EXPECT_TRUE(test::rel_near(sim::tet_signed_volume(a, c, b, d), -1.0 / 6.0, 1e-15));
  const Vec3 t(3, -4, 5);
  EXPECT_TRUE(test::rel_near(sim::tet_signed_volume(2.0 * a + t, 2.0 * b + t, 2.0 * c + t, 2.0 * d + t), 8.0 / 6.0, 1e-14));
  EXPECT_EQ(sim::tet_signed_volume(a, b, c, Vec3(0.5, 0.5, 0)), 0.0);
}

}  // namespace
}  // namespace ido

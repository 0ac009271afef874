// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <random>

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/fem_linear.h"
#include "ido/sim/fem_neo_hookean.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

constexpr sim::ElasticMaterial kMaterial{1e6, 0.3};   // 1 MPa, soft tissue-like

// A 4×4×4-cell cube (20 mm) whose interior vertices are randomly displaced, so the patch
// test runs on an irregular mesh.
geometry::TetMesh irregular_cube() {
  auto mesh = sim::make_cube(20.0, 4, Vec3::Zero());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& v : mesh.vertices)
    if (v.cwiseAbs().maxCoeff() < 10.0 - 1e-9) v += Vec3(u(rng), u(rng), u(rng));
  return mesh;
}

std::vector<Vec3> forces(const sim::ForceModel& model, const sim::Particles& p) {
  std::vector<Vec3> f(p.size(), Vec3::Zero());
  model.add_forces(p, f, true);
  return f;
}

sim::Particles particles_of(const geometry::TetMesh& mesh) {
  sim::Particles p;
  for (const auto& v : mesh.vertices) p.add(v, 1.0);
  return p;
}

TEST(LinearFem, PatchTestAffineDisplacementGivesConstantStrainAndZeroInteriorForce) {
  const auto mesh = irregular_cube();
  auto p = particles_of(mesh);
  sim::LinearFem model(mesh.tets, p.positions(), kMaterial);
  Mat3 a;
  a << 0.010, 0.002, -0.003, 0.001, -0.008, 0.004, 0.002, 0.003, 0.006;
  const Vec3 t(0.5, -0.2, 0.1);
  for (auto& x : p.positions()) x = x + a * x + t;
  const Mat3 eps = 0.5 * (a + a.transpose());
  for (const auto& F : model.deformation_gradients(p)) {
    const Mat3 e = 0.5 * (F + F.transpose()) - Mat3::Identity();
    EXPECT_TRUE(test::near((e - eps).cwiseAbs().maxCoeff(), 0.0, 1e-10));
  }
  const auto f = forces(model, p);
  double boundary_max = 0.0, interior_max = 0.0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const bool interior = mesh.vertices[i].cwiseAbs().maxCoeff() < 10.0 - 1e-9;
    (interior ? interior_max : boundary_max) = std::max(interior ? interior_max : boundary_max, f[i].norm());
  }
  EXPECT_GT(boundary_max, 1e-4);   // the boundary carries the traction
  EXPECT_TRUE(test::near(interior_max, 0.0, 1e-10 * boundary_max));
}

template <class Model>
void expect_rotation_invariance() {
  const auto mesh = irregular_cube();
  auto p = particles_of(mesh);
  const Model model(mesh.tets, p.positions(), kMaterial);
  // Force scale: what a 1 % stretch gives.
  auto stretched = p;
  for (auto& x : stretched.positions()) x.x() *= 1.01;
  double f_scale = 0.0;
  for (const auto& f : forces(model, stretched)) f_scale = std::max(f_scale, f.norm());
  const double e_scale = model.energy(stretched);
  ASSERT_GT(f_scale, 0.0);
  ASSERT_GT(e_scale, 0.0);
  std::mt19937 rng(11);
  for (int k = 0; k < 100; ++k) {
    const Mat3 r = test::random_rotation(rng);
    const Vec3 t(k, -2.0 * k, 0.5 * k);
    auto q = p;
    for (std::size_t i = 0; i < q.size(); ++i) q.positions()[i] = r * mesh.vertices[i] + t;
    double fmax = 0.0;
    for (const auto& f : forces(model, q)) fmax = std::max(fmax, f.norm());
    EXPECT_TRUE(test::near(fmax, 0.0, 1e-9 * f_scale)) << "rotation " << k;
    EXPECT_TRUE(test::near(model.energy(q), 0.0, 1e-9 * e_scale)) << "rotation " << k;
  }
}

TEST(CorotationalFem, ZeroForceAndEnergyUnder100RandomRotations) {
  expect_rotation_invariance<sim::CorotationalFem>();
}
TEST(NeoHookeanFem, ZeroForceAndEnergyUnder100RandomRotations) {
  expect_rotation_invariance<sim::NeoHookeanFem>();
}

TEST(LinearFem, IsNotRotationInvariant) {
  // The reason corotational FEM exists: linear FEM gives spurious forces under rotation.
  const auto mesh = sim::make_cube(20.0, 2);
  auto p = particles_of(mesh);
  const sim::LinearFem model(mesh.tets, p.positions(), kMaterial);
  const Mat3 r = Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix();
  for (auto& x : p.positions()) x = r * x;
  EXPECT_GT(model.energy(p), 1.0);
}

// Relative error of K·δ against central differences of the forces, over random δ.
double stiffness_fd_error(const sim::ForceModel& model, const sim::Particles& p, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double h = 1e-6;
  double worst = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<Vec3> d(p.size());
    for (auto& v : d) v = Vec3(n(rng), n(rng), n(rng));
    std::vector<Vec3> kd(p.size(), Vec3::Zero());
    model.add_stiffness_product(p, d, kd);
    auto plus = p, minus = p;
    for (std::size_t i = 0; i < p.size(); ++i) {
      plus.positions()[i] += h * d[i];
      minus.positions()[i] -= h * d[i];
    }
    const auto fp = forces(model, plus), fm = forces(model, minus);
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec3 fd = -(fp[i] - fm[i]) / (2.0 * h);
      num += (fd - kd[i]).squaredNorm();
      den += kd[i].squaredNorm();
    }
    worst = std::max(worst, std::sqrt(num / den));
  }
  return worst;
}

sim::Particles deformed(const geometry::TetMesh& mesh, double amount, std::mt19937& rng) {
  auto p = particles_of(mesh);
  std::uniform_real_distribution<double> u(-amount, amount);
  for (auto& x : p.positions()) x += Vec3(u(rng), u(rng), u(rng));
  return p;
}

TEST(Stiffness, LinearFemMatchesFiniteDifferences) {
  std::mt19937 rng(1);
  const auto mesh = irregular_cube();
  const sim::LinearFem model(mesh.tets, mesh.vertices, kMaterial);
  EXPECT_LT(stiffness_fd_error(model, deformed(mesh, 1.0, rng), rng), 1e-5);
}

TEST(Stiffness, NeoHookeanMatchesFiniteDifferencesWhenLargelyDeformed) {
  std::mt19937 rng(2);
  const auto mesh = irregular_cube();
  sim::NeoHookeanFem model(mesh.tets, mesh.vertices, kMaterial);
  model.set_definite_stiffness(false);
  EXPECT_LT(stiffness_fd_error(model, deformed(mesh, 1.0, rng), rng), 1e-5);
}

TEST(Stiffness, MassSpringMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  const auto mesh = irregular_cube();
  const auto model = sim::MassSpring::from_tet_edges(mesh, 0, 2.0);
  EXPECT_LT(stiffness_fd_error(model, deformed(mesh, 1.0, rng), rng), 1e-5);
}

TEST(Stiffness, CorotationalMatchesFiniteDifferencesAtRotatedRest) {
  // The frozen-rotation tangent R K₀ Rᵀ is exact at rigidly moved rest shapes.
  std::mt19937 rng(4);
  const auto mesh = irregular_cube();
  const sim::CorotationalFem model(mesh.tets, mesh.vertices, kMaterial);
  auto p = particles_of(mesh);
  const Mat3 r = test::random_rotation(rng);
  for (auto& x : p.positions()) x = r * x + Vec3(3, 4, 5);
  EXPECT_LT(stiffness_fd_error(model, p, rng), 1e-5);
}

template <class Model>
void expect_inverted_element_recovers() {
  // One tetrahedron with its apex pushed through the opposite face; damped dynamics must
  // bring it back to positive volume with finite forces all the way.
  geometry::TetMesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), Vec3(0, 0, 10)};
  mesh.tets = {Tet{0, 1, 2, 3}};
  sim::World w;
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<Model>(mesh.tets, w.particles().positions(), kMaterial);
  w.external().damping.mass_per_s = 200.0;
  w.particles().positions()[3] = Vec3(1, 1, -3);
  w.set_integrator("symplectic_euler");
  for (int s = 0; s < 20000; ++s) {
    w.step(1e-6);
    for (const auto& f : w.particles().forces()) ASSERT_TRUE(f.allFinite());
  }
  const auto& x = w.particles().positions();
  EXPECT_GT(sim::tet_signed_volume(x[0], x[1], x[2], x[3]), 100.0);
}

TEST(CorotationalFem, InvertedElementRecovers) { expect_inverted_element_recovers<sim::CorotationalFem>(); }
TEST(NeoHookeanFem, InvertedElementRecovers) { expect_inverted_element_recovers<sim::NeoHookeanFem>(); }

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
  EXPECT_THROW(sim::LinearFem({Tet{0, 2, 1, 3}}, x, kMaterial), InvalidInput);
  EXPECT_THROW(sim::LinearFem({Tet{0, 1, 2, 3}}, x, {1e6, 0.5}), InvalidInput);
  EXPECT_THROW(sim::LinearFem({Tet{0, 1, 2, 3}}, x, {-1.0, 0.3}), InvalidInput);
  EXPECT_THROW(sim::LinearFem({Tet{0, 1, 2, 7}}, x, kMaterial), InvalidInput);
}

TEST(FemModel, ElementFieldsUniaxialStretchGiveExpectedStress) {
  // Linear FEM, small uniaxial strain ε along x with free lateral contraction (−ν ε):
  // σ_xx = E ε, other components 0, von Mises = |σ_xx|.
  const auto mesh = sim::make_cube(10.0, 2);
  auto p = particles_of(mesh);
  const sim::LinearFem model(mesh.tets, p.positions(), kMaterial);
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

}  // namespace
}  // namespace ido

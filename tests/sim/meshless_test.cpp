// SPDX-License-Identifier: Apache-2.0
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/mls.h"
#include "ido/sim/shape_matching.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

// Particles on a jittered 6×6×6 grid of spacing 2 mm, 1 g each.
sim::Particles point_cloud() {
  sim::Particles p;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) p.add(Vec3(2.0 * i + u(rng), 2.0 * j + u(rng), 2.0 * k + u(rng)), 1e-3);
  return p;
}

// RMS distance between two shapes after removing the best rigid motion (Kabsch).
double shape_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= a.size();
  cb /= b.size();
  Mat3 h = Mat3::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) h += (b[i] - cb) * (a[i] - ca).transpose();
  Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Mat3 r = svd.matrixU() * d * svd.matrixV().transpose();
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += (r * (a[i] - ca) + cb - b[i]).squaredNorm();
  return std::sqrt(s / a.size());
}

class ShapeMatchingReturn : public ::testing::TestWithParam<sim::ShapeMatchingMode> {};

TEST_P(ShapeMatchingReturn, ReturnsToRestShapeFromLargeDeformation) {
  sim::World w;
  w.particles() = point_cloud();
  const auto rest = w.particles().positions();
  const auto clusters = sim::grid_clusters(rest, 6.0);
  ASSERT_GT(clusters.size(), 1u);
  sim::ShapeMatchingOptions options;
  options.mode = GetParam();
  options.beta = 0.3;
  w.emplace_model<sim::ShapeMatching>(w.particles(), clusters, options);
  // Large deformation: shear by 60 %, squash z to half, twist.
  for (auto& x : w.particles().positions()) {
    const double a = 0.05 * x.z();
    x = Vec3(std::cos(a) * (x.x() + 0.6 * x.z()) - std::sin(a) * x.y(),
             std::sin(a) * (x.x() + 0.6 * x.z()) + std::cos(a) * x.y(), 0.5 * x.z());
  }
  const double before = shape_distance(w.particles().positions(), rest);
  ASSERT_GT(before, 1.0);
  w.external().damping.mass_per_s = 50.0;
  w.set_integrator("symplectic_euler");
  // ω = √k = 100 rad/s, damping ratio α / 2ω = 0.25: decays as e^(−25 t).
  for (int s = 0; s < 1500; ++s) w.step(1e-3);
  const double after = shape_distance(w.particles().positions(), rest);
  EXPECT_LT(after, 1e-3 * before) << "before " << before << " after " << after;
  EXPECT_TRUE(test::near(w.models()[0]->energy(w.particles()), 0.0, 1e-9));
}

INSTANTIATE_TEST_SUITE_P(Modes, ShapeMatchingReturn,
                         ::testing::Values(sim::ShapeMatchingMode::Rigid, sim::ShapeMatchingMode::Linear,
                                           sim::ShapeMatchingMode::Quadratic));

TEST(ShapeMatching, RigidMotionGivesNoForce) {
  auto p = point_cloud();
  sim::ShapeMatchingOptions options;
  options.mode = sim::ShapeMatchingMode::Quadratic;
  const sim::ShapeMatching model(p, sim::grid_clusters(p.positions(), 4.0), options);
  // Scale: the largest force under a 1 % stretch.
  auto stretched = p;
  for (auto& x : stretched.positions()) x.x() *= 1.01;
  std::vector<Vec3> fs(p.size(), Vec3::Zero());
  model.add_forces(stretched, fs, true);
  double scale = 0.0;
  for (const auto& fi : fs) scale = std::max(scale, fi.norm());
  ASSERT_GT(scale, 0.0);
  std::mt19937 rng(9);
  const Mat3 r = test::random_rotation(rng);
  for (auto& x : p.positions()) x = r * x + Vec3(5, 6, 7);
  std::vector<Vec3> f(p.size(), Vec3::Zero());
  model.add_forces(p, f, true);
  for (const auto& fi : f) EXPECT_TRUE(test::near(fi.norm(), 0.0, 1e-5 * scale));
}

TEST(ShapeMatching, RejectsBadClusters) {
  const auto p = point_cloud();
  EXPECT_THROW(sim::ShapeMatching(p, {{}}), InvalidInput);
  EXPECT_THROW(sim::ShapeMatching(p, {{0, 1, 999}}), InvalidInput);
  sim::ShapeMatchingOptions linear;
  linear.mode = sim::ShapeMatchingMode::Linear;
  EXPECT_THROW(sim::ShapeMatching(p, {{0, 1, 2}}, linear), InvalidInput);
}

sim::MlsOptions mls_options() {
  return {.support_radius_mm = 4.5, .material = {1e6, 0.3}, .volume_stiffness_pa = 1e5};
}

std::vector<std::int32_t> all_indices(std::size_t n) {
  std::vector<std::int32_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::int32_t>(i);
  return v;
}

TEST(Mls, ReproducesStrainOfLinearDisplacementExactly) {
  auto p = point_cloud();
  const sim::MlsElasticity model(p, all_indices(p.size()), mls_options());
  Mat3 g;
  g << 0.05, -0.02, 0.03, 0.01, 0.04, -0.06, 0.02, 0.07, -0.03;
  for (auto& x : p.positions()) x = x + g * x + Vec3(1, 2, 3);
  const Mat3 expected = 0.5 * (g + g.transpose() + g.transpose() * g);
  for (const auto& e : model.green_strains(p))
    EXPECT_TRUE(test::near((e - expected).cwiseAbs().maxCoeff(), 0.0, 1e-10));
}

TEST(Mls, ForcesAreTheNegativeEnergyGradient) {
  auto p = point_cloud();
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
  w.particles() = point_cloud();
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
  const auto p = point_cloud();
  auto options = mls_options();
  options.support_radius_mm = 1.0;
  EXPECT_THROW(sim::MlsElasticity(p, all_indices(p.size()), options), InvalidInput);
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// Shape matching (Müller et al. 2005): rigid, linear and quadratic matches return a body to its
// rest shape from a large deformation, rigid motion gives no force, a single cluster's goal
// positions and energy follow their definition, and bad clusters are refused.
#include "ido/sim/shape_matching.h"

#include <cmath>
#include <random>

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/units.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

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
  w.particles() = test::point_cloud();
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
  auto p = test::point_cloud();
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
  const auto p = test::point_cloud();
  EXPECT_THROW(sim::ShapeMatching(p, {{}}), InvalidInput);
  EXPECT_THROW(sim::ShapeMatching(p, {{0, 1, 999}}), InvalidInput);
  sim::ShapeMatchingOptions linear;
  linear.mode = sim::ShapeMatchingMode::Linear;
  EXPECT_THROW(sim::ShapeMatching(p, {{0, 1, 2}}, linear), InvalidInput);
}

// One rigid cluster: moved rigidly, its goal positions are that motion of the rest shape and it
// stores no energy; deformed, each particle's force is k m (g − x) towards its goal and the
// energy is Σ ½ k m ‖g − x‖² (the force law of the header, one cluster per particle; kg·mm/s²
// converted to N and mJ, units.h).
TEST(ShapeMatching, RigidClusterPullsEachParticleTowardsItsGoal) {
  auto p = test::point_cloud();
  std::vector<std::int32_t> all(p.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = std::int32_t(i);
  sim::ShapeMatchingOptions options;
  options.mode = sim::ShapeMatchingMode::Rigid;
  options.stiffness_per_s2 = 2e3;
  const sim::ShapeMatching model(p, {all}, options);
  std::mt19937 rng(8);
  const Mat3 r = test::random_rotation(rng);
  const Vec3 t(1, -2, 3);
  const std::vector<Vec3> rest = p.positions();
  for (auto& x : p.positions()) x = r * x + t;
  auto goals = model.goal_positions(p);
  ASSERT_EQ(goals.size(), p.size());
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_TRUE(test::near((goals[i] - (r * rest[i] + t)).norm(), 0.0, 1e-10));
  EXPECT_TRUE(test::near(model.energy(p), 0.0, 1e-18));

  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (auto& x : p.positions()) x += Vec3(u(rng), u(rng), u(rng));
  goals = model.goal_positions(p);
  const auto f = test::model_forces(model, p);
  double energy = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3 pull = options.stiffness_per_s2 * p.masses()[i] * (goals[i] - p.positions()[i]) * sim::kKgMmPerS2ToNewton;
    EXPECT_TRUE(test::near((f[i] - pull).norm(), 0.0, 1e-12 * pull.norm() + 1e-18)) << "particle " << i;
    energy += 0.5 * options.stiffness_per_s2 * p.masses()[i] * (goals[i] - p.positions()[i]).squaredNorm() *
              sim::kKgMmPerS2ToNewton;
  }
  EXPECT_GT(energy, 0.0);
  EXPECT_TRUE(test::rel_near(model.energy(p), energy, 1e-12));
}

}  // namespace
}  // namespace ido

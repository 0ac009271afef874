// SPDX-License-Identifier: Apache-2.0
// Small builders shared by the sim tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ido/sim/fem_common.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/world.h"
#include "support/test_support.h"

namespace ido::test {

/// One particle on a spring to a fixed anchor at the origin, moving along x:
/// k = 1e-3 N/mm, m = 1 kg, so ω² = k / (m · 1e-3) = 1 rad²/s². Starts 1 mm from rest
/// (rest length 10 mm), at rest: x(t) = 10 + cos t, v(t) = −sin t.
inline sim::World harmonic_oscillator() {
  sim::World w;
  w.set_threaded(false);
  w.particles().add(Vec3::Zero(), 1.0);
  w.particles().add(Vec3(11.0, 0.0, 0.0), 1.0);
  w.particles().set_fixed(0, true);
  w.emplace_model<sim::MassSpring>(std::vector<sim::Spring>{{0, 1, 10.0, 1e-3, 0.0}});
  return w;
}

/// A random rotation matrix.
inline Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// The FEM tests' material, soft-tissue-like: E = 1 MPa, ν = 0.3.
inline constexpr sim::ElasticMaterial kFemMaterial{1e6, 0.3};

/// A 4×4×4-cell cube (20 mm, centred at the origin) whose interior vertices are randomly
/// displaced, so that tests run on an irregular mesh.
inline geometry::TetMesh irregular_cube() {
  auto mesh = sim::make_cube(20.0, 4, Vec3::Zero());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& v : mesh.vertices)
    if (v.cwiseAbs().maxCoeff() < 10.0 - 1e-9) v += Vec3(u(rng), u(rng), u(rng));
  return mesh;
}

/// Particles of 1 kg at the vertices of @p mesh.
inline sim::Particles particles_of(const geometry::TetMesh& mesh) {
  sim::Particles p;
  for (const auto& v : mesh.vertices) p.add(v, 1.0);
  return p;
}

/// Particles on a jittered 6×6×6 grid of spacing 2 mm, 1 g each (the meshless models' tests).
inline sim::Particles point_cloud() {
  sim::Particles p;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) p.add(Vec3(2.0 * i + u(rng), 2.0 * j + u(rng), 2.0 * k + u(rng)), 1e-3);
  return p;
}

/// The forces (N) of @p model alone at @p p.
inline std::vector<Vec3> model_forces(const sim::ForceModel& model, const sim::Particles& p) {
  std::vector<Vec3> f(p.size(), Vec3::Zero());
  model.add_forces(p, f, true);
  return f;
}

/// @p mesh's particles, each moved by a uniform random offset in [−amount, amount]³ (mm).
inline sim::Particles deformed(const geometry::TetMesh& mesh, double amount, std::mt19937& rng) {
  auto p = particles_of(mesh);
  std::uniform_real_distribution<double> u(-amount, amount);
  for (auto& x : p.positions()) x += Vec3(u(rng), u(rng), u(rng));
  return p;
}

/// Relative error of K·δ against central differences of the forces, over random δ.
inline double stiffness_fd_error(const sim::ForceModel& model, const sim::Particles& p, std::mt19937& rng) {
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
    const auto fp = model_forces(model, plus), fm = model_forces(model, minus);
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

/// Relative error of the forces against the negative energy gradient: over random directions
/// δ, |f·δ + (E(x + hδ) − E(x − hδ)) / 2h| / |f·δ| (forces in N, energy in mJ = N·mm).
inline double force_gradient_fd_error(const sim::ForceModel& model, const sim::Particles& p, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double h = 1e-5;
  const auto f = model_forces(model, p);
  double worst = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    auto plus = p, minus = p;
    double f_dot_d = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec3 d(n(rng), n(rng), n(rng));
      plus.positions()[i] += h * d;
      minus.positions()[i] -= h * d;
      f_dot_d += f[i].dot(d);
    }
    const double fd = -(model.energy(plus) - model.energy(minus)) / (2.0 * h);
    worst = std::max(worst, std::abs(fd - f_dot_d) / std::abs(f_dot_d));
  }
  return worst;
}

/// Zero force and energy (relative to a 1 % stretch's) for @p Model on irregular_cube() under
/// 100 random rigid motions.
template <class Model>
void expect_rotation_invariance() {
  const auto mesh = irregular_cube();
  auto p = particles_of(mesh);
  const Model model(mesh.tets, p.positions(), kFemMaterial);
  // Force scale: what a 1 % stretch gives.
  auto stretched = p;
  for (auto& x : stretched.positions()) x.x() *= 1.01;
  double f_scale = 0.0;
  for (const auto& f : model_forces(model, stretched)) f_scale = std::max(f_scale, f.norm());
  const double e_scale = model.energy(stretched);
  ASSERT_GT(f_scale, 0.0);
  ASSERT_GT(e_scale, 0.0);
  std::mt19937 rng(11);
  for (int k = 0; k < 100; ++k) {
    const Mat3 r = random_rotation(rng);
    const Vec3 t(k, -2.0 * k, 0.5 * k);
    auto q = p;
    for (std::size_t i = 0; i < q.size(); ++i) q.positions()[i] = r * mesh.vertices[i] + t;
    double fmax = 0.0;
    for (const auto& f : model_forces(model, q)) fmax = std::max(fmax, f.norm());
    EXPECT_TRUE(near(fmax, 0.0, 1e-9 * f_scale)) << "rotation " << k;
    EXPECT_TRUE(near(model.energy(q), 0.0, 1e-9 * e_scale)) << "rotation " << k;
  }
}

/// One tetrahedron with its apex pushed through the opposite face: damped dynamics with
/// @p Model bring it back to positive volume with finite forces all the way.
template <class Model>
void expect_inverted_element_recovers() {
  geometry::TetMesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), Vec3(0, 0, 10)};
  mesh.tets = {Tet{0, 1, 2, 3}};
  sim::World w;
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<Model>(mesh.tets, w.particles().positions(), kFemMaterial);
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

/// A 40 × 10 × 10 mm corotational beam (16 × 4 × 4 cells, E = 1 MPa, ν = 0.45) clamped at
/// x = 0, under gravity, stepped by implicit Euler.
inline sim::World beam_world(bool threaded) {
  sim::World w;
  w.set_threaded(threaded);
  const auto mesh = sim::make_beam({40, 10, 10}, {16, 4, 4});
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<sim::CorotationalFem>(mesh.tets, w.particles().positions(), sim::ElasticMaterial{1e6, 0.45});
  for (std::size_t i = 0; i < w.particles().size(); ++i)
    if (w.particles().positions()[i].x() < 1e-9) w.particles().set_fixed(i, true);
  w.external().gravity_mm_s2 = Vec3(0, 0, -9810);
  w.set_integrator("implicit_euler");
  return w;
}

}  // namespace ido::test

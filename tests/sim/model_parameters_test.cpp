// SPDX-License-Identifier: Apache-2.0
// Force models' parameters changed between steps (set_youngs_modulus, set_poisson_ratio,
// set_stiffness, set_damping, ...): each change gives what the analytic answer says for the
// new value, and a value out of range is refused by name with the model left as it was.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/fem_linear.h"
#include "ido/sim/mls.h"
#include "ido/sim/shape_matching.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

constexpr double kLength = 100.0, kWidth = 10.0, kHeight = 10.0;   // mm

/// A bar along x clamped at x = 0, with @p Model on its tetrahedra.
template <class Model>
struct Bar {
  geometry::TetMesh mesh;
  sim::World world;
  Model* model = nullptr;
  Bar(const Vec3i& cells, const sim::ElasticMaterial& material) : mesh(sim::make_beam({kLength, kWidth, kHeight}, cells)) {
    world.add_tet_body(mesh, 1000.0);
    model = &world.emplace_model<Model>(mesh.tets, world.particles().positions(), material);
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      if (mesh.vertices[i].x() < 1e-9) world.particles().set_fixed(i, true);
  }
  /// Vertices of the face x = L.
  [[nodiscard]] std::vector<std::size_t> end() const {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
      if (mesh.vertices[i].x() > kLength - 1e-9) out.push_back(i);
    return out;
  }
  /// Static equilibrium from the rest shape, to @p tolerance_n of residual force; returns the
  /// end face's mean displacement (mm).
  Vec3 solve(double tolerance_n) {
    world.particles().positions() = mesh.vertices;
    const auto r = sim::solve_static(world, {.max_newton_iterations = 10, .force_tolerance_n = tolerance_n});
    EXPECT_TRUE(r.converged) << "residual " << r.max_residual_force_n << " N";
    Vec3 sum = Vec3::Zero();
    for (auto i : end()) sum += world.particles().positions()[i] - mesh.vertices[i];
    return sum / double(end().size());
  }
};

// A bar pulled by a uniform traction σ on its free end, ν = 0: the exact solution is
// u_x = σ x / E (linear, which linear tetrahedra reproduce), so the elongation is
// F L / (E A). Doubling E with set_youngs_modulus halves it.
TEST(ModelParameters, YoungsModulusSetsTheBarElongation) {
  constexpr double kYoung = 1e6, kForce = 1.0;   // Pa, N
  Bar<sim::LinearFem> bar({20, 2, 2}, {kYoung, 0.0});
  // Consistent nodal loads of the uniform traction: a third of each end triangle's force to
  // each of its corners.
  const double area = kWidth * kHeight;
  std::vector<Vec3> load(bar.mesh.vertices.size(), Vec3::Zero());
  for (const auto& t : bar.mesh.tets)
    for (int skip = 0; skip < 4; ++skip) {
      std::vector<std::size_t> f;
      for (int c = 0; c < 4; ++c)
        if (c != skip) f.push_back(static_cast<std::size_t>(t[static_cast<std::size_t>(c)]));
      bool on_end = true;
      for (auto i : f) on_end = on_end && bar.mesh.vertices[i].x() > kLength - 1e-9;
      if (!on_end) continue;
      const auto& v = bar.mesh.vertices;
      const double a = 0.5 * (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).norm();
      for (auto i : f) load[i] += Vec3(kForce * a / area / 3.0, 0, 0);
    }
  for (std::size_t i = 0; i < load.size(); ++i)
    if (load[i].squaredNorm() > 0) bar.world.external().point_loads.push_back({std::int32_t(i), load[i]});

  for (const double young : {kYoung, 2.0 * kYoung, 0.5 * kYoung}) {
    if (young != kYoung) bar.model->set_youngs_modulus(young);
    EXPECT_TRUE(test::rel_near(bar.model->material().youngs_modulus_pa, young, 1e-15));
    const double analytic = kForce * kLength / (young * 1e-6 * area);
    const Vec3 u = bar.solve(1e-8 * kForce);
    EXPECT_TRUE(test::rel_near(u.x(), analytic, 1e-9)) << "E = " << young;
    EXPECT_LT(std::abs(u.y()) + std::abs(u.z()), 1e-9 * analytic);
  }
}

// A cantilever under a tip load: Euler–Bernoulli's δ = F L³ / (3 E I) is inversely
// proportional to E, and so is the linear FEM's deflection when the modulus is changed on the
// model; at every modulus the deflection is within the mesh's discretisation error (shear
// locking of linear tetrahedra, 8 cells through the height: 4.2 %) of the analytic value.
TEST(ModelParameters, YoungsModulusSetsTheCantileverDeflection) {
  constexpr double kYoung = 1e6, kTipLoad = 1e-3;
  Bar<sim::LinearFem> beam({80, 2, 8}, {kYoung, 0.0});
  const auto tip = beam.end();
  for (auto i : tip) beam.world.external().point_loads.push_back({std::int32_t(i), Vec3(0, 0, -kTipLoad / double(tip.size()))});
  const double inertia = kWidth * std::pow(kHeight, 3) / 12.0;
  const double first = -beam.solve(1e-8 * kTipLoad).z();
  for (const double factor : {4.0, 0.25}) {
    beam.model->set_youngs_modulus(factor * kYoung);
    const double deflection = -beam.solve(1e-8 * kTipLoad).z();
    const double analytic = kTipLoad * std::pow(kLength, 3) / (3.0 * factor * kYoung * 1e-6 * inertia);
    EXPECT_TRUE(test::rel_near(first / deflection, factor, 1e-9)) << factor;
    EXPECT_TRUE(test::rel_near(deflection, analytic, 0.05)) << deflection << " vs " << analytic;
    std::printf("E x %g: deflection %.6g mm, Euler-Bernoulli %.6g mm\n", factor, deflection, analytic);
  }
}

// Poisson's ratio changed on the model: far from the clamp, the bar under axial tension
// contracts sideways by −ν times its axial strain.
TEST(ModelParameters, PoissonRatioSetsTheLateralContraction) {
  Bar<sim::LinearFem> bar({40, 4, 4}, {1e6, 0.0});
  for (auto i : bar.end()) bar.world.external().point_loads.push_back({std::int32_t(i), Vec3(1.0 / double(bar.end().size()), 0, 0)});
  auto strains = [&]() {
    (void)bar.solve(1e-8);
    // Axial strain between x = 40 and 60 mm, lateral strain across the width at x = 50 mm.
    double u40 = 0, u60 = 0, y_lo = 0, y_hi = 0;
    int n40 = 0, n60 = 0, nlo = 0, nhi = 0;
    const auto& x = bar.world.particles().positions();
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Vec3& X = bar.mesh.vertices[i];
      if (std::abs(X.x() - 40) < 1e-9) u40 += x[i].x() - X.x(), ++n40;
      if (std::abs(X.x() - 60) < 1e-9) u60 += x[i].x() - X.x(), ++n60;
      if (std::abs(X.x() - 50) < 1e-9 && X.y() < 1e-9) y_lo += x[i].y(), ++nlo;
      if (std::abs(X.x() - 50) < 1e-9 && X.y() > kWidth - 1e-9) y_hi += x[i].y(), ++nhi;
    }
    const double axial = (u60 / n60 - u40 / n40) / 20.0;
    const double lateral = (y_hi / nhi - y_lo / nlo - kWidth) / kWidth;
    return std::pair{axial, lateral};
  };
  const auto [axial0, lateral0] = strains();
  EXPECT_LT(std::abs(lateral0), 1e-6 * axial0);
  for (const double nu : {0.3, 0.45}) {
    bar.model->set_poisson_ratio(nu);
    EXPECT_TRUE(test::rel_near(bar.model->material().poisson_ratio, nu, 1e-15));
    const auto [axial, lateral] = strains();
    EXPECT_TRUE(test::rel_near(-lateral / axial, nu, 0.02)) << "nu " << nu << ": " << -lateral / axial;
  }
}

// The oscillator of test::harmonic_oscillator (k = 1e-3 N/mm, m = 1 kg: ω = 1 rad/s) with its
// spring made 4 times stiffer: ω = 2 rad/s, x(t) = 10 + cos 2t.
TEST(ModelParameters, SpringStiffnessSetsTheFrequency) {
  auto w = test::harmonic_oscillator();
  auto& spring = dynamic_cast<sim::MassSpring&>(*w.models()[0]);
  spring.set_stiffness(4e-3);
  EXPECT_TRUE(test::rel_near(spring.springs()[0].stiffness_n_per_mm, 4e-3, 1e-15));
  w.set_integrator("rk4");
  for (int s = 0; s < 1000; ++s) w.step(1e-3);
  EXPECT_TRUE(test::near(w.particles().positions()[1].x(), 10.0 + std::cos(2.0), 1e-9));
  EXPECT_TRUE(test::near(w.particles().velocities()[1].x(), -2.0 * std::sin(2.0), 1e-9));
}

// Spring damping c set on the model: the under-damped oscillator with ζ = c / (2 √(k m)) = 0.1,
// x − L = e^{−ζt} (cos ω_d t + ζ/√(1−ζ²) sin ω_d t), ω_d = √(1−ζ²) rad/s.
TEST(ModelParameters, SpringDampingSetsTheDecay) {
  auto w = test::harmonic_oscillator();
  auto& spring = dynamic_cast<sim::MassSpring&>(*w.models()[0]);
  spring.set_damping(2e-4);   // N·s/mm; √(k m) = √(1e-3 N/mm · 1e-3 N·s²/mm) = 1e-3 N·s/mm
  w.set_integrator("rk4");
  for (int s = 0; s < 2000; ++s) w.step(1e-3);
  const double zeta = 0.1, wd = std::sqrt(1.0 - zeta * zeta), t = 2.0;
  const double analytic = std::exp(-zeta * t) * (std::cos(wd * t) + zeta / wd * std::sin(wd * t));
  EXPECT_TRUE(test::near(w.particles().positions()[1].x() - 10.0, analytic, 1e-9));
}

/// The message of the InvalidInput @p f throws, or "no exception".
template <class F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "no exception";
}

// Out-of-range values are refused naming the parameter, and the model keeps its values.
TEST(ModelParameters, BadValuesAreRefusedByNameAndChangeNothing) {
  Bar<sim::CorotationalFem> bar({4, 1, 1}, {1e5, 0.3});
  auto& fem = *bar.model;
  for (const double e : {0.0, -1.0, std::nan("")})
    EXPECT_NE(refusal([&] { fem.set_youngs_modulus(e); }).find("youngs_modulus_pa"), std::string::npos) << e;
  for (const double nu : {0.5, -1.0, 0.7})
    EXPECT_NE(refusal([&] { fem.set_poisson_ratio(nu); }).find("poisson_ratio"), std::string::npos) << nu;
  EXPECT_TRUE(test::rel_near(fem.material().youngs_modulus_pa, 1e5, 1e-15));
  EXPECT_TRUE(test::rel_near(fem.material().poisson_ratio, 0.3, 1e-15));
  const auto lame = sim::lame_parameters({1e5, 0.3});
  EXPECT_TRUE(test::rel_near(fem.lame().mu, lame.mu, 1e-15));
  EXPECT_TRUE(test::rel_near(fem.lame().lambda, lame.lambda, 1e-15));

  auto w = test::harmonic_oscillator();
  auto& spring = dynamic_cast<sim::MassSpring&>(*w.models()[0]);
  EXPECT_NE(refusal([&] { spring.set_stiffness(-1.0); }).find("stiffness_n_per_mm"), std::string::npos);
  EXPECT_NE(refusal([&] { spring.set_stiffness(std::nan("")); }).find("stiffness_n_per_mm"), std::string::npos);
  EXPECT_NE(refusal([&] { spring.set_damping(-1e-3); }).find("damping_n_s_per_mm"), std::string::npos);
  EXPECT_TRUE(test::rel_near(spring.springs()[0].stiffness_n_per_mm, 1e-3, 1e-15));
  EXPECT_EQ(spring.springs()[0].damping_n_s_per_mm, 0.0);

  const auto cube = sim::make_cube(10.0, 3);
  sim::World m;
  m.add_tet_body(cube, 1000.0);
  std::vector<std::int32_t> ids(cube.vertices.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = std::int32_t(i);
  auto& mls = m.emplace_model<sim::MlsElasticity>(m.particles(), ids,
                                                  sim::MlsOptions{.support_radius_mm = 8.0, .material = {1e5, 0.3}});
  EXPECT_NE(refusal([&] { mls.set_material({-5.0, 0.3}); }).find("youngs_modulus_pa"), std::string::npos);
  EXPECT_NE(refusal([&] { mls.set_material({1e5, 0.5}); }).find("poisson_ratio"), std::string::npos);
  EXPECT_NE(refusal([&] { mls.set_volume_stiffness(-1.0); }).find("volume_stiffness_pa"), std::string::npos);
  EXPECT_TRUE(test::rel_near(mls.options().material.youngs_modulus_pa, 1e5, 1e-15));
  auto& sm = m.emplace_model<sim::ShapeMatching>(m.particles(), sim::grid_clusters(cube.vertices, 5.0),
                                                 sim::ShapeMatchingOptions{.mode = sim::ShapeMatchingMode::Linear});
  EXPECT_NE(refusal([&] { sm.set_beta(1.5); }).find("beta"), std::string::npos);
  EXPECT_NE(refusal([&] { sm.set_stiffness(-1.0); }).find("stiffness_per_s2"), std::string::npos);
  EXPECT_TRUE(test::rel_near(sm.options().beta, 0.5, 1e-15));
}

// MLS and shape matching: the energy of a stretched state scales with the modulus / the
// stiffness set on the model (both are linear in it).
TEST(ModelParameters, MeshlessModelsScaleWithTheirStiffness) {
  const auto cube = sim::make_cube(10.0, 3);
  sim::World m;
  m.add_tet_body(cube, 1000.0);
  std::vector<std::int32_t> ids(cube.vertices.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = std::int32_t(i);
  auto& mls = m.emplace_model<sim::MlsElasticity>(m.particles(), ids,
                                                  sim::MlsOptions{.support_radius_mm = 8.0, .material = {1e5, 0.3}});
  auto& sm = m.emplace_model<sim::ShapeMatching>(m.particles(), sim::grid_clusters(cube.vertices, 5.0),
                                                 sim::ShapeMatchingOptions{.mode = sim::ShapeMatchingMode::Linear});
  for (auto& x : m.particles().positions()) x = Vec3(1.1 * x.x(), x.y(), 0.95 * x.z());
  const double e_mls = mls.energy(m.particles()), e_sm = sm.energy(m.particles());
  ASSERT_GT(e_mls, 0.0);
  ASSERT_GT(e_sm, 0.0);
  mls.set_material({3e5, 0.3});
  sm.set_stiffness(5e4);
  EXPECT_TRUE(test::rel_near(mls.energy(m.particles()), 3.0 * e_mls, 1e-12));
  EXPECT_TRUE(test::rel_near(sm.energy(m.particles()), 5.0 * e_sm, 1e-12));
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// sim::run, the stepping driver: what its observers see and when, integrators switched
// mid-run, and a diverging run stopped before any bad state reaches an observer; the
// divergence rule (DivergenceWatch) on its own.
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/runner.h"
#include "ido/sim/units.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

/// Records what run() hands over.
struct Recorder final : sim::RunObserver {
  std::vector<std::int64_t> steps, sample_steps, frame_steps, frame_indices;
  std::vector<double> frame_times_s, sample_energy_mj, frame_max_speed_mm_s;
  int finished = 0;
  std::int64_t finished_frames = -1;
  void on_step(sim::World&, std::int64_t step, double step_ms) override {
    steps.push_back(step);
    EXPECT_GE(step_ms, 0.0);
  }
  void on_sample(const sim::World&, std::int64_t step, const sim::EnergyReport& e) override {
    sample_steps.push_back(step);
    sample_energy_mj.push_back(e.kinetic_mj + e.elastic_total_mj());
  }
  void on_frame(const sim::World& world, std::int64_t frame, std::int64_t step) override {
    frame_indices.push_back(frame);
    frame_steps.push_back(step);
    frame_times_s.push_back(world.time_s());
    double speed = 0.0;
    for (const auto& v : world.particles().velocities()) speed = std::max(speed, v.norm());
    frame_max_speed_mm_s.push_back(speed);
  }
  void on_finish(const sim::World&, const sim::RunResult& result) override {
    ++finished;
    finished_frames = result.frames;
  }
};

// Frames at the start, every frame_every steps and at the last step; a sample per step here
// (steps / 2000 < 1); the energy series conserves the oscillator's energy as symplectic Euler
// does (bounded oscillation of relative size ~dt).
TEST(Runner, ObserversSeeTheStartEveryFrameAndTheEnd) {
  auto w = test::harmonic_oscillator();
  Recorder rec;
  std::vector<sim::RunObserver*> observers{&rec};
  const auto r = sim::run(w, {.dt_s = 0.01, .steps = 110, .frame_every = 25}, observers);
  EXPECT_EQ(rec.frame_steps, (std::vector<std::int64_t>{0, 25, 50, 75, 100, 110}));
  EXPECT_EQ(rec.frame_indices, (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5}));
  for (std::size_t k = 0; k < rec.frame_steps.size(); ++k)
    EXPECT_TRUE(test::near(rec.frame_times_s[k], 0.01 * double(rec.frame_steps[k]), 1e-12));
  EXPECT_EQ(r.frames, 6);
  EXPECT_EQ(rec.finished, 1);
  EXPECT_EQ(rec.finished_frames, 6);
  ASSERT_EQ(rec.steps.size(), 110u);
  EXPECT_EQ(rec.steps.front(), 1);
  EXPECT_EQ(rec.steps.back(), 110);
  ASSERT_EQ(rec.sample_steps.size(), 111u);
  ASSERT_EQ(r.time_s.size(), 111u);
  EXPECT_EQ(r.step_ms.size(), 110u);
  EXPECT_EQ(r.cg_iterations.size(), 110u);
  // E = ½ k (x − L)² + ½ m v² = ½ · 1e-3 N/mm · 1 mm² = 5e-4 mJ.
  for (std::size_t k = 0; k < r.total_mj.size(); ++k) {
    EXPECT_TRUE(test::rel_near(r.total_mj[k], 5e-4, 0.02)) << "sample " << k;
    EXPECT_TRUE(test::near(r.total_mj[k], rec.sample_energy_mj[k], 1e-15));
  }
  EXPECT_TRUE(test::near(r.final_energy.total_mj(), r.total_mj.back(), 1e-15));
}

/// Switches the world's integrator before a given step.
struct Switcher final : sim::RunObserver {
  std::int64_t after_step;
  std::string to;
  Switcher(std::int64_t s, std::string name) : after_step(s), to(std::move(name)) {}
  void on_step(sim::World& world, std::int64_t step, double) override {
    if (step == after_step) world.set_integrator(to);
  }
};

// An observer switches the integrator between two steps of the driver: the same trajectory as
// a loop that switches by hand (the paper's run-time switchable integrators).
TEST(Runner, IntegratorSwitchedMidRunByAnObserver) {
  auto by_hand = test::harmonic_oscillator();
  by_hand.set_integrator("rk4");
  for (int s = 1; s <= 80; ++s) {
    by_hand.step(0.05);
    if (s == 30) by_hand.set_integrator("implicit_euler");
  }
  auto w = test::harmonic_oscillator();
  w.set_integrator("rk4");
  Switcher sw(30, "implicit_euler");
  std::vector<sim::RunObserver*> observers{&sw};
  (void)sim::run(w, {.dt_s = 0.05, .steps = 80}, observers);
  EXPECT_EQ(w.integrator(), "implicit_euler");
  EXPECT_TRUE(test::near(w.particles().positions()[1].x(), by_hand.particles().positions()[1].x(), 0.0));
  EXPECT_TRUE(test::near(w.particles().velocities()[1].x(), by_hand.particles().velocities()[1].x(), 0.0));
  // Implicit Euler damps the oscillation that RK4 kept (numerical dissipation, a factor
  // 1 / (1 + ω² dt²) of the energy per step): the end energy is below what RK4 alone keeps.
  auto rk4_only = test::harmonic_oscillator();
  rk4_only.set_integrator("rk4");
  const auto r = sim::run(rk4_only, {.dt_s = 0.05, .steps = 80});
  const double switched_mj = sim::energies(w).total_mj();
  EXPECT_TRUE(test::rel_near(r.final_energy.total_mj(), 5e-4, 1e-6));
  EXPECT_TRUE(test::rel_near(switched_mj, 5e-4 * std::pow(1.0 / (1.0 + 0.05 * 0.05), 50), 0.01)) << switched_mj;
}

/// A 10-mm cube clamped at its base, sagging under gravity with stiffness damping, stepped by
/// explicit Euler (the scene of the CLI's divergence test).
sim::World clamped_cube() {
  sim::World w;
  const auto mesh = sim::make_cube(10.0, 2);
  w.add_tet_body(mesh, 1000.0);
  w.emplace_model<sim::CorotationalFem>(mesh.tets, w.particles().positions(), sim::ElasticMaterial{1e4, 0.3});
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (mesh.vertices[i].z() < -4.9) w.particles().set_fixed(i, true);
  w.external().gravity_mm_s2 = Vec3(0, 0, -sim::kStandardGravityMmPerS2);
  w.external().damping.stiffness_s = 0.002;
  w.set_integrator("explicit_euler");
  return w;
}

// Explicit Euler far beyond its stable step: the energy grows ×1e4 within a few steps. The
// driver throws Diverged naming the step before the bad state reaches any observer: every
// frame and sample handed over came before that step, with finite, small speeds; on_finish
// never runs.
TEST(Runner, ExplicitEulerDivergenceIsCaughtBeforeAnyBadFrame) {
  auto w = clamped_cube();
  Recorder rec;
  std::vector<sim::RunObserver*> observers{&rec};
  std::int64_t diverged_at = -1;
  try {
    (void)sim::run(w, {.dt_s = 0.01, .steps = 4000, .frame_every = 1, .label = "cube.json"}, observers);
    FAIL() << "no divergence";
  } catch (const sim::Diverged& e) {
    diverged_at = e.step();
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("cube.json: simulation diverged at step " + std::to_string(e.step()) + " of 4000", 0), 0u)
        << what;
    EXPECT_NE(what.find("reduce dt_s (now 0.01)"), std::string::npos) << what;
  }
  ASSERT_GT(diverged_at, 0);
  EXPECT_LE(diverged_at, 10);
  EXPECT_EQ(rec.finished, 0);
  ASSERT_FALSE(rec.frame_steps.empty());
  EXPECT_EQ(rec.frame_steps.front(), 0);
  for (std::size_t k = 0; k < rec.frame_steps.size(); ++k) {
    EXPECT_LT(rec.frame_steps[k], diverged_at);
    EXPECT_TRUE(std::isfinite(rec.frame_max_speed_mm_s[k]));
  }
  for (const auto s : rec.sample_steps) EXPECT_LT(s, diverged_at);
  // The state the driver refused: its energy is far above everything it handed over.
  const double refused_mj = sim::energies(w).kinetic_mj + sim::energies(w).elastic_total_mj();
  for (const double e : rec.sample_energy_mj) EXPECT_GT(refused_mj, 100.0 * e);
}

// Just below the stable step (0.2 ms) the same scene runs to the end: nothing is called
// divergence, and the cube settles.
TEST(Runner, StableExplicitRunIsNotCalledDiverged) {
  auto w = clamped_cube();
  const auto r = sim::run(w, {.dt_s = 0.0002, .steps = 4000, .frame_every = 100, .energy_floor_mj = 5e-6});
  EXPECT_EQ(r.frames, 41);
  EXPECT_LT(r.final_energy.kinetic_mj, 1e-9);
}

// The divergence rule on its own (sim::DivergenceWatch, the one run() and the viewer's Deform
// session apply). The clamped cube stepped stably is not diverged; a NaN position or velocity is
// reported naming the particle; the energy bound is the documented one — the start energy plus
// Σ (|loads| + m |g|)(|x − x⁰| + |v| dt) plus the floor — and an energy just over 10 times it is
// reported while one just under is not; a non-finite energy is reported.
TEST(DivergenceWatch, ReportsNonFiniteStatesAndEnergyOverTheBoundOnly) {
  auto w = clamped_cube();
  const double dt = 0.0002, floor_mj = 5e-6;
  w.external().point_loads.push_back({std::int32_t(w.particles().size() - 1), Vec3(0, 0.002, 0)});
  const std::vector<Vec3> x0 = w.particles().positions();
  const sim::DivergenceWatch watch(w, dt, floor_mj);
  for (int s = 0; s < 100; ++s) w.step(dt);
  ASSERT_GT((w.particles().positions().back() - x0.back()).norm(), 0.0) << "the cube moved";
  EXPECT_FALSE(watch.check_finite(w));
  const sim::EnergyReport e = sim::energies(w);
  EXPECT_FALSE(watch.check_energy(w, e)) << *watch.check_energy(w, e);

  // The bound, from its definition (the start state was at rest: no start energy).
  const auto& p = w.particles();
  double bound_mj = floor_mj;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double load_n = i + 1 == p.size() ? 0.002 : 0.0;
    const double coefficient_n = load_n + p.masses()[i] * sim::kStandardGravityMmPerS2 * sim::kKgMmPerS2ToNewton;
    bound_mj += coefficient_n * ((p.positions()[i] - x0[i]).norm() + p.velocities()[i].norm() * dt);
  }
  EXPECT_TRUE(test::rel_near(watch.energy_bound_mj(w), bound_mj, 1e-12));
  sim::EnergyReport over = e, under = e;
  over.kinetic_mj = 10.0 * bound_mj * (1.0 + 1e-6) - e.elastic_total_mj();
  under.kinetic_mj = 10.0 * bound_mj * (1.0 - 1e-6) - e.elastic_total_mj();
  const auto cause = watch.check_energy(w, over);
  ASSERT_TRUE(cause);
  EXPECT_NE(cause->find("kinetic + elastic energy"), std::string::npos) << *cause;
  EXPECT_NE(cause->find("over 10 times"), std::string::npos) << *cause;
  EXPECT_FALSE(watch.check_energy(w, under));
  sim::EnergyReport nan = e;
  nan.kinetic_mj = std::nan("");
  EXPECT_EQ(watch.check_energy(w, nan), std::optional<std::string>("the energy is not finite"));

  w.particles().positions()[5].y() = std::nan("");
  EXPECT_EQ(watch.check_finite(w), std::optional<std::string>("particle 5 has a non-finite position"));
  w.particles().positions()[5].y() = x0[5].y();
  w.particles().velocities()[7].z() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(watch.check_finite(w), std::optional<std::string>("particle 7 has a non-finite velocity"));
}

TEST(Runner, BadOptionsAreRejectedByName) {
  auto w = test::harmonic_oscillator();
  auto message = [&](const sim::RunOptions& o) {
    try {
      (void)sim::run(w, o);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message({.dt_s = 0.0, .steps = 1}).find("dt_s"), std::string::npos);
  EXPECT_NE(message({.dt_s = std::numeric_limits<double>::infinity(), .steps = 1}).find("dt_s"), std::string::npos);
  EXPECT_NE(message({.dt_s = 0.01, .steps = 0}).find("steps"), std::string::npos);
  EXPECT_NE(message({.dt_s = 0.01, .steps = 1, .frame_every = 0}).find("frame_every"), std::string::npos);
  EXPECT_NE(message({.dt_s = 0.01, .steps = 1, .energy_floor_mj = -1.0}).find("energy_floor_mj"), std::string::npos);
  EXPECT_EQ(w.step_count(), 0);
}

}  // namespace
}  // namespace ido

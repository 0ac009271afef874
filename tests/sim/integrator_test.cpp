// SPDX-License-Identifier: Apache-2.0
// The integrators and their registry: each scheme's order of convergence on a harmonic
// oscillator, unknown names refused, user schemes (callbacks and objects with state) registered,
// switched between steps and made anew when registered again. Implicit Euler's solver has its
// own test file.
#include "ido/sim/integrator.h"

#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/sim/implicit_euler.h"
#include "sim_test_support.h"
#include "support/test_support.h"

namespace ido {
namespace {

double oscillator_error(const std::string& scheme, int steps) {
  auto w = test::harmonic_oscillator();
  w.set_integrator(scheme);
  w.implicit_options().cg_tolerance = 1e-15;
  const double dt = 1.0 / steps;
  for (int s = 0; s < steps; ++s) w.step(dt);
  const double t = w.time_s();
  const double ex = 10.0 + std::cos(t), ev = -std::sin(t);
  return std::abs(w.particles().positions()[1].x() - ex) +
         std::abs(w.particles().velocities()[1].x() - ev);
}

struct OrderCase {
  const char* scheme;
  double order;
  int steps;
};

class ConvergenceOrder : public ::testing::TestWithParam<OrderCase> {};

TEST_P(ConvergenceOrder, MatchesTheory) {
  const auto c = GetParam();
  const double e1 = oscillator_error(c.scheme, c.steps);
  const double e2 = oscillator_error(c.scheme, 2 * c.steps);
  const double e3 = oscillator_error(c.scheme, 4 * c.steps);
  EXPECT_TRUE(test::near(std::log2(e1 / e2), c.order, 0.2)) << c.scheme;
  EXPECT_TRUE(test::near(std::log2(e2 / e3), c.order, 0.2)) << c.scheme;
}

INSTANTIATE_TEST_SUITE_P(HarmonicOscillator, ConvergenceOrder,
                         ::testing::Values(OrderCase{"explicit_euler", 1.0, 200},
                                           OrderCase{"symplectic_euler", 1.0, 200},
                                           OrderCase{"velocity_verlet", 2.0, 50},
                                           OrderCase{"rk4", 4.0, 10},
                                           OrderCase{"implicit_euler", 1.0, 200}),
                         [](const auto& param_info) { return std::string(param_info.param.scheme); });

TEST(IntegratorRegistry, UnknownNameIsRejectedWithTheKnownOnes) {
  sim::World w;
  try {
    w.set_integrator("leapfrog");
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("leapfrog"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("rk4"), std::string::npos);
  }
  EXPECT_THROW(w.step(0.0), InvalidInput);
  EXPECT_THROW(w.step(-1.0), InvalidInput);
}

TEST(IntegratorRegistry, UserSchemeIsCalledAndSwitchingKeepsState) {
  // Reference: 20 RK4 steps then 20 symplectic Euler steps.
  auto ref = test::harmonic_oscillator();
  ref.set_integrator("rk4");
  for (int i = 0; i < 20; ++i) ref.step(0.01);
  const Vec3 x_mid = ref.particles().positions()[1];
  ref.set_integrator("symplectic_euler");
  EXPECT_EQ(ref.particles().positions()[1], x_mid);  // switching touches nothing
  for (int i = 0; i < 20; ++i) ref.step(0.01);

  // Same run, but the second half through a user-registered copy of symplectic Euler.
  auto w = test::harmonic_oscillator();
  int calls = 0;
  w.integrators().add("my_symplectic", [&calls](sim::World& world, double dt) {
    ++calls;
    world.compute_forces();
    const auto a = world.accelerations();
    auto& p = world.particles();
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.fixed(i)) continue;
      p.velocities()[i] += dt * a[i];
      p.positions()[i] += dt * p.velocities()[i];
    }
  });
  w.set_integrator("rk4");
  for (int i = 0; i < 20; ++i) w.step(0.01);
  w.set_integrator("my_symplectic");
  for (int i = 0; i < 20; ++i) w.step(0.01);
  EXPECT_EQ(calls, 20);
  EXPECT_TRUE(test::near(w.particles().positions()[1].x(), ref.particles().positions()[1].x(), 0.0));
  EXPECT_TRUE(test::near(w.particles().velocities()[1].x(), ref.particles().velocities()[1].x(), 0.0));
  EXPECT_TRUE(test::near(w.time_s(), 0.4, 1e-12));
}

// ---- integrators as objects --------------------------------------------------------------

/// Velocity Verlet that carries the acceleration of the end of one step into the next (the
/// state a stateless callback cannot keep): one force evaluation per step instead of two. The
/// carried acceleration is used only when this instance took the previous step (another
/// scheme may have moved the particles in between); otherwise it is computed afresh.
class CarriedVerlet final : public sim::Integrator {
 public:
  explicit CarriedVerlet(int& instances) { ++instances; }
  void step(sim::World& world, double dt_s) override {
    auto& p = world.particles();
    if (world.step_count() != m_next_step || m_a.size() != p.size()) {
      world.compute_forces();
      m_a = world.accelerations();
      ++fresh_starts;
    }
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.fixed(i)) continue;
      p.velocities()[i] += 0.5 * dt_s * m_a[i];
      p.positions()[i] += dt_s * p.velocities()[i];
    }
    world.compute_forces();
    m_a = world.accelerations();
    for (std::size_t i = 0; i < p.size(); ++i)
      if (!p.fixed(i)) p.velocities()[i] += 0.5 * dt_s * m_a[i];
    m_next_step = world.step_count() + 1;
  }
  [[nodiscard]] std::string_view name() const override { return "carried_verlet"; }
  int fresh_starts = 0;

 private:
  std::vector<Vec3> m_a;           // mm/s², at the end of the last step
  std::int64_t m_next_step = -1;   // World::step_count() of the step that may reuse m_a
};

// A user scheme with state, registered by factory: its state persists across steps (one force
// evaluation per step after the first, where velocity Verlet without state needs two), it
// gives velocity Verlet's trajectory, and switching to RK4 and back keeps the same instance,
// which notices the gap and recomputes the acceleration once.
TEST(IntegratorObject, UserSchemeKeepsItsStateAcrossStepsAndSwitches) {
  // fresh_starts is read while the world lives (the scheme instance is the world's).
  auto run = [](const std::string& scheme, int* instances, int* fresh_starts, std::vector<int>* evaluations) {
    auto w = test::harmonic_oscillator();
    if (instances)
      w.integrators().add("carried_verlet", sim::IntegratorFactory([instances] {
                            return std::make_unique<CarriedVerlet>(*instances);
                          }));
    for (int phase = 0; phase < 3; ++phase) {
      w.set_integrator(phase == 1 ? "rk4" : scheme);
      for (int i = 0; i < 30; ++i) {
        w.step(0.01);
        if (evaluations && phase != 1) evaluations->push_back(w.last_step().force_evaluations);
      }
    }
    if (fresh_starts) *fresh_starts = w.scheme_as<CarriedVerlet>("carried_verlet").fresh_starts;
    return std::pair{w.particles().positions()[1], w.particles().velocities()[1]};
  };
  const auto [x_ref, v_ref] = run("velocity_verlet", nullptr, nullptr, nullptr);
  int instances = 0;
  int fresh_starts = -1;
  std::vector<int> evaluations;
  const auto [x, v] = run("carried_verlet", &instances, &fresh_starts, &evaluations);
  EXPECT_TRUE(test::near(x.x(), x_ref.x(), 1e-12));
  EXPECT_TRUE(test::near(v.x(), v_ref.x(), 1e-12));
  // One instance for the whole run, which started afresh twice: at the start and after RK4.
  EXPECT_EQ(instances, 1);
  EXPECT_EQ(fresh_starts, 2);
  ASSERT_EQ(evaluations.size(), 60u);
  for (std::size_t k = 0; k < evaluations.size(); ++k)
    EXPECT_EQ(evaluations[k], k % 30 == 0 ? 2 : 1) << "step " << k;
}

// Registering a scheme again under the same name gives the world a new instance (fresh state)
// before its next step with it; a factory that makes nothing is refused.
TEST(IntegratorObject, ReRegisteringMakesANewInstance) {
  auto w = test::harmonic_oscillator();
  int instances = 0;
  auto factory = sim::IntegratorFactory([&instances] { return std::make_unique<CarriedVerlet>(instances); });
  w.integrators().add("carried_verlet", factory);
  w.set_integrator("carried_verlet");
  w.step(0.01);
  w.step(0.01);
  EXPECT_EQ(instances, 1);
  EXPECT_EQ(w.scheme_as<CarriedVerlet>("carried_verlet").fresh_starts, 1);
  w.integrators().add("carried_verlet", factory);
  w.step(0.01);
  EXPECT_EQ(instances, 2);
  EXPECT_EQ(w.scheme_as<CarriedVerlet>("carried_verlet").fresh_starts, 1);
  EXPECT_THROW((void)w.scheme_as<sim::ImplicitEuler>("carried_verlet"), InvalidInput);
  w.integrators().add("nothing", sim::IntegratorFactory([] { return std::unique_ptr<sim::Integrator>(); }));
  EXPECT_THROW(w.set_integrator("nothing"), InvalidInput);
  EXPECT_THROW(w.integrators().add("empty", sim::IntegratorFactory()), InvalidInput);
  EXPECT_THROW(w.integrators().add("", sim::IntegratorFn([](sim::World&, double) {})), InvalidInput);
}

}  // namespace
}  // namespace ido

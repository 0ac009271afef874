// SPDX-License-Identifier: Apache-2.0
// The scene the Deform workspace steps on its worker thread: single steps, the pull, the
// integrator switched between steps; parameters changed between steps continue the run bit for
// bit as the library does (a model's setter in place, or the scene read again for a density);
// the divergence rule is sim::run's.
#include "ido/view/deform_session.h"

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "ido/io/scene.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/runner.h"
#include "support/clamped_cube_scene.h"
#include "support/test_support.h"

namespace ido {
namespace {

namespace fs = std::filesystem;

std::shared_ptr<const view::DeformState> wait_steps(view::DeformSession& s, std::int64_t steps) {
  for (auto t0 = std::chrono::steady_clock::now(); std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);) {
    auto st = s.latest();
    if (st && st->steps >= steps && !s.busy()) return st;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return s.latest();
}

TEST(DeformSession, StepsPullsSwitchesIntegratorAndReportsEnergy) {
  io::Scene scene = io::parse_scene(R"({
    "dt_s": 0.001, "steps": 1, "integrator": "implicit_euler",
    "damping": {"rayleigh_mass_per_s": 5.0, "rayleigh_stiffness_s": 0.0},
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [40, 10, 10], "cells": [8, 2, 2]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 2e3, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 11, 11]}]}]})",
                                     "beam", ".");
  const std::vector<Vec3> rest = scene.world.particles().positions();
  view::DeformSession session(std::move(scene));
  EXPECT_FALSE(session.running());
  // Paused: nothing moves until a step is asked for; then exactly those steps.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(session.latest()->steps, 0);
  for (int i = 0; i < 3; ++i) session.step_once();
  auto st = wait_steps(session, 3);
  EXPECT_EQ(st->steps, 3);
  EXPECT_EQ(st->integrator, "implicit_euler");
  ASSERT_EQ(st->von_mises_pa.size(), 1u);
  EXPECT_EQ(st->von_mises_pa[0].size(), session.bodies()[0].rest_mesh.tets.size());
  EXPECT_FALSE(st->history.empty());
  EXPECT_TRUE(test::near(st->history.back().total_mj, 0.0, 1e-12)) << "at rest, no load: no energy";
  // Pull the tip corner 5 mm down for 300 steps: it moves down, the body stores elastic energy.
  std::int32_t tip = -1;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if ((rest[i] - Vec3(40, 0, 10)).norm() < 1e-9) tip = std::int32_t(i);
  ASSERT_GE(tip, 0);
  session.set_grab({true, tip, Vec3(40, 0, 5), 0.1});
  for (int i = 0; i < 300; ++i) session.step_once();
  st = wait_steps(session, 303);
  const double pulled = rest[std::size_t(tip)].z() - st->positions_mm[std::size_t(tip)].z();
  EXPECT_GT(pulled, 2.0);
  EXPECT_GT(st->grab_stiffness_n_per_mm, 0.0);
  EXPECT_LE(st->grab_stiffness_n_per_mm, 0.1);
  EXPECT_GT(st->history.back().elastic_mj, 0.0);
  double vm_max = 0;
  for (double v : st->von_mises_pa[0]) vm_max = std::max(vm_max, v);
  EXPECT_GT(vm_max, 0.0);
  // Released, under another integrator switched between steps, it springs back.
  session.set_grab({});
  session.set_integrator("rk4");
  EXPECT_THROW(session.set_integrator("leapfrog"), InvalidInput);
  session.set_running(true);  // 2 s of simulated time (damping 5/s: e^-5 of the swing is left)
  for (auto t0 = std::chrono::steady_clock::now();
       session.latest()->steps < 2303 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  session.set_running(false);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the worker hands over where it stopped
  st = session.latest();
  EXPECT_EQ(st->integrator, "rk4");
  EXPECT_TRUE(st->error.empty()) << st->error;
  const double back = (st->positions_mm[std::size_t(tip)] - rest[std::size_t(tip)]).norm();
  EXPECT_LT(back, 0.25 * pulled) << "after " << st->steps << " steps";
}

TEST(DeformSession, ParametersChangedBetweenStepsContinueAsTheLibraryWithTheNewValues) {
  // A beam clamped at x = 0 sagging under gravity.
  const std::string text = R"({
    "dt_s": 0.005, "steps": 1, "integrator": "implicit_euler", "gravity_mm_s2": [0, 0, -9806.65],
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [30, 6, 6], "cells": [6, 1, 1]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 7, 7]}]}]})";
  const fs::path file = test::scratch_dir("deform-parameters") / "beam.json";
  std::ofstream(file) << text;
  view::DeformSession session(file);
  // What can change: the material's three numbers and the two damping coefficients.
  const auto& params = session.parameters();
  ASSERT_EQ(params.size(), 5u);
  EXPECT_EQ(params[0].pointer, "/bodies/0/material/youngs_modulus_pa");
  EXPECT_EQ(params[0].value, 1e5);
  EXPECT_EQ(params[2].pointer, "/bodies/0/material/density_kg_m3");
  EXPECT_EQ(params[3].pointer, "/damping/rayleigh_mass_per_s");
  EXPECT_EQ(params[3].value, 0.0);
  std::vector<double> values;
  for (const auto& p : params) values.push_back(p.value);
  EXPECT_THROW(session.set_parameters({1.0}), InvalidInput);

  // 7 steps; then a stiffer, denser, damped beam for 9 more. The density is a number the world
  // is built from (the particles' masses), so the scene read again takes over.
  for (int i = 0; i < 7; ++i) session.step_once();
  ASSERT_EQ(wait_steps(session, 7)->steps, 7);
  values[0] = 3e5;
  values[2] = 1500;
  values[3] = 4.0;
  session.set_parameters(values);
  for (int i = 0; i < 9; ++i) session.step_once();
  auto st = wait_steps(session, 16);
  ASSERT_EQ(st->steps, 16);
  EXPECT_EQ(st->parameters, values);
  ASSERT_EQ(st->changes.size(), 3u);
  for (const auto& c : st->changes) EXPECT_EQ(c.step, 7);
  EXPECT_TRUE(st->parameter_error.empty()) << st->parameter_error;

  // The library: 7 steps of the file's scene; the scene with the new values from that state on.
  io::Scene a = io::parse_scene(text, "beam.json", file.parent_path());
  for (int i = 0; i < 7; ++i) a.world.step(a.dt_s);
  nlohmann::json doc = nlohmann::json::parse(text);
  doc["bodies"][0]["material"]["youngs_modulus_pa"] = 3e5;
  doc["bodies"][0]["material"]["density_kg_m3"] = 1500;
  doc["damping"]["rayleigh_mass_per_s"] = 4.0;
  io::Scene b = io::parse_scene(doc.dump(), "beam.json", file.parent_path());
  b.world.particles().positions() = a.world.particles().positions();
  b.world.particles().velocities() = a.world.particles().velocities();
  b.world.set_integrator(a.world.integrator());
  for (int i = 0; i < 9; ++i) {
    b.world.step(b.dt_s);
    a.world.step(a.dt_s);
  }
  EXPECT_TRUE(st->positions_mm == b.world.particles().positions()) << "not the library's run with the new values";
  EXPECT_FALSE(st->positions_mm == a.world.particles().positions()) << "the new values made no difference";
  EXPECT_TRUE(test::near(st->time_s, 16 * 0.005, 1e-12)) << "time goes on across the change";

  // A bad value is refused with the scene reader's message (naming its JSON pointer); the run
  // goes on with the values in use.
  std::vector<double> bad = values;
  bad[1] = 0.6;
  session.set_parameters(bad);
  session.step_once();
  st = wait_steps(session, 17);
  EXPECT_EQ(st->steps, 17);
  EXPECT_NE(st->parameter_error.find("/bodies/0/material/poisson_ratio"), std::string::npos) << st->parameter_error;
  EXPECT_EQ(st->parameters, values);
  EXPECT_EQ(st->changes.size(), 3u);
  b.world.step(b.dt_s);
  EXPECT_TRUE(st->positions_mm == b.world.particles().positions());
}

/// The newest state once it shows @p changes parameter changes (the session publishes at once
/// while paused).
std::shared_ptr<const view::DeformState> wait_changes(view::DeformSession& s, std::size_t changes) {
  for (auto t0 = std::chrono::steady_clock::now(); std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);) {
    auto st = s.latest();
    if (st && (st->changes.size() >= changes || !st->parameter_error.empty())) return st;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return s.latest();
}

// Young's modulus changed between steps goes to the running model (set_material): the state
// goes on where it was — the positions and the momentum (so the velocities) right after the
// change are those before it — and the run is, bit for bit, the library's run that calls the
// model's set_youngs_modulus at that step, the implicit solver's warm start and the
// corotational rotations kept (a world built anew from the changed scene, which starts them
// afresh, ends elsewhere).
TEST(DeformSession, ModulusChangedMidRunGoesOnAsTheModelsSetYoungsModulus) {
  const std::string text = R"({
    "dt_s": 0.005, "steps": 1, "integrator": "implicit_euler", "gravity_mm_s2": [0, 0, -9806.65],
    "damping": {"rayleigh_mass_per_s": 2.0},
    "bodies": [{"name": "beam", "mesh": {"generator": "beam", "size_mm": [30, 6, 6], "cells": [6, 1, 1]},
                "model": "corotational_fem",
                "material": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 7, 7]}]}]})";
  const fs::path file = test::scratch_dir("deform-modulus") / "beam.json";
  std::ofstream(file) << text;
  view::DeformSession session(file);
  ASSERT_EQ(session.parameters()[0].pointer, "/bodies/0/material/youngs_modulus_pa");
  std::vector<double> values;
  for (const auto& p : session.parameters()) values.push_back(p.value);

  for (int i = 0; i < 7; ++i) session.step_once();
  const auto before = wait_steps(session, 7);
  ASSERT_EQ(before->steps, 7);
  values[0] = 3e5;
  session.set_parameters(values);
  const auto changed = wait_changes(session, 1);
  ASSERT_EQ(changed->changes.size(), 1u) << changed->parameter_error;
  EXPECT_EQ(changed->changes[0].step, 7);
  EXPECT_EQ(changed->steps, 7);
  EXPECT_EQ(changed->time_s, before->time_s);
  EXPECT_TRUE(changed->positions_mm == before->positions_mm) << "the change moved the particles";
  EXPECT_TRUE(changed->linear_momentum == before->linear_momentum) << "the change touched the velocities";
  for (int i = 0; i < 9; ++i) session.step_once();
  const auto st = wait_steps(session, 16);
  ASSERT_EQ(st->steps, 16);

  // The library: the scene's world, the model's setter after step 7, on to step 16.
  io::Scene lib = io::parse_scene(text, "beam.json", file.parent_path());
  for (int i = 0; i < 7; ++i) lib.world.step(lib.dt_s);
  const std::vector<Vec3> x7 = lib.world.particles().positions(), v7 = lib.world.particles().velocities();
  dynamic_cast<sim::TetFemModel&>(*lib.world.models()[lib.bodies[0].model_index]).set_youngs_modulus(3e5);
  for (int i = 0; i < 9; ++i) lib.world.step(lib.dt_s);
  EXPECT_TRUE(st->positions_mm == lib.world.particles().positions()) << "not the library's run with the setter";
  EXPECT_TRUE(st->linear_momentum == sim::momentum(lib.world.particles()).linear_kg_mm_s);
  EXPECT_EQ(st->time_s, lib.world.time_s());

  // A world built anew from the changed scene, given the same positions and velocities.
  nlohmann::json doc = nlohmann::json::parse(text);
  doc["bodies"][0]["material"]["youngs_modulus_pa"] = 3e5;
  io::Scene fresh = io::parse_scene(doc.dump(), "beam.json", file.parent_path());
  fresh.world.particles().positions() = x7;
  fresh.world.particles().velocities() = v7;
  for (int i = 0; i < 9; ++i) fresh.world.step(fresh.dt_s);
  EXPECT_FALSE(st->positions_mm == fresh.world.particles().positions()) << "the integrator's state was not kept";
}

// A spring body's stiffness and the Rayleigh damping changed between steps go to the running
// world (MassSpring::set_stiffness, ExternalForces::damping): bit for bit the library's run with
// those calls at that step.
TEST(DeformSession, SpringStiffnessAndDampingChangeInPlace) {
  const std::string text = R"({
    "dt_s": 0.002, "steps": 1, "integrator": "implicit_euler", "gravity_mm_s2": [0, 0, -9806.65],
    "bodies": [{"name": "springs", "mesh": {"generator": "beam", "size_mm": [20, 4, 4], "cells": [5, 1, 1]},
                "model": "mass_spring", "mass_spring": {"stiffness_n_per_mm": 0.5},
                "material": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000},
                "fixed": [{"box_min_mm": [-1, -1, -1], "box_max_mm": [0.001, 5, 5]}]}]})";
  const fs::path file = test::scratch_dir("deform-springs") / "springs.json";
  std::ofstream(file) << text;
  view::DeformSession session(file);
  const auto& params = session.parameters();
  ASSERT_EQ(params.size(), 6u);
  EXPECT_EQ(params[3].pointer, "/bodies/0/mass_spring/stiffness_n_per_mm");
  EXPECT_EQ(params[4].pointer, "/damping/rayleigh_mass_per_s");
  std::vector<double> values;
  for (const auto& p : params) values.push_back(p.value);
  for (int i = 0; i < 5; ++i) session.step_once();
  ASSERT_EQ(wait_steps(session, 5)->steps, 5);
  values[3] = 2.0;
  values[4] = 3.0;
  session.set_parameters(values);
  ASSERT_EQ(wait_changes(session, 2)->changes.size(), 2u);
  for (int i = 0; i < 10; ++i) session.step_once();
  const auto st = wait_steps(session, 15);
  ASSERT_EQ(st->steps, 15);

  io::Scene lib = io::parse_scene(text, "springs.json", file.parent_path());
  io::Scene unchanged = io::parse_scene(text, "springs.json", file.parent_path());
  for (int i = 0; i < 5; ++i) lib.world.step(lib.dt_s);
  dynamic_cast<sim::MassSpring&>(*lib.world.models()[lib.bodies[0].model_index]).set_stiffness(2.0);
  lib.world.external().damping.mass_per_s = 3.0;
  for (int i = 0; i < 10; ++i) lib.world.step(lib.dt_s);
  for (int i = 0; i < 15; ++i) unchanged.world.step(unchanged.dt_s);
  EXPECT_TRUE(st->positions_mm == lib.world.particles().positions()) << "not the library's run with the setters";
  EXPECT_FALSE(st->positions_mm == unchanged.world.particles().positions()) << "the new values made no difference";
}

// The session stops a diverging run by sim::run's rule, at the same step: the clamped cube
// under explicit Euler far beyond its stable step (10 ms) stops with the energy bound's cause at
// the step at which sim::run throws Diverged (with the scene's floor, energy checked every
// step); just below the stable step (0.2 ms) it runs on.
TEST(DeformSession, DivergenceIsCalledAtTheStepSimRunCallsIt) {
  std::int64_t diverged_at = -1;
  {
    io::Scene scene = io::parse_scene(test::clamped_cube_scene("explicit_euler", 0.01, 4000, 1).dump(), "cube.json", ".");
    try {
      (void)sim::run(scene.world, io::run_options(scene));
    } catch (const sim::Diverged& e) {
      diverged_at = e.step();
    }
  }
  ASSERT_GT(diverged_at, 0);
  view::DeformSession session(
      io::parse_scene(test::clamped_cube_scene("explicit_euler", 0.01, 4000, 1).dump(), "cube.json", "."));
  session.set_running(true);
  std::shared_ptr<const view::DeformState> st;
  for (auto t0 = std::chrono::steady_clock::now(); std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);) {
    st = session.latest();
    if (st && !st->error.empty()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  session.set_running(false);
  ASSERT_TRUE(st);
  ASSERT_FALSE(st->error.empty()) << "no divergence after " << st->steps << " steps";
  EXPECT_EQ(st->steps, diverged_at);
  EXPECT_EQ(st->error.rfind("simulation diverged at step " + std::to_string(diverged_at) + " (t = ", 0), 0u) << st->error;
  EXPECT_NE(st->error.find("kinetic + elastic energy"), std::string::npos) << st->error;
  EXPECT_NE(st->error.find("reduce dt_s (now 0.01)"), std::string::npos) << st->error;

  view::DeformSession stable(
      io::parse_scene(test::clamped_cube_scene("explicit_euler", 0.0002, 4000, 1).dump(), "cube.json", "."));
  for (int i = 0; i < 500; ++i) stable.step_once();
  const auto settled = wait_steps(stable, 500);
  EXPECT_EQ(settled->steps, 500);
  EXPECT_TRUE(settled->error.empty()) << settled->error;
}

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// The scene the Deform workspace steps on its worker thread: single steps, the pull, the
// integrator switched between steps; parameters changed between steps continue the run bit for
// bit as the library's scene with the new values from that state does, and a bad value is
// refused naming its JSON pointer.
#include "ido/view/deform_session.h"

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "ido/core/error.h"
#include "ido/io/scene.h"
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

  // 7 steps; then a stiffer, denser, damped beam for 9 more.
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

}  // namespace
}  // namespace ido

// SPDX-License-Identifier: Apache-2.0
// The scene shared by the tests of runs that settle or diverge (io::run_scene, `ido simulate`,
// the Deform workspace's session).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace ido::test {

/// A scene file (docs/scene.md): a 10-mm cube (2 cells per side, centred at the origin)
/// clamped at its base z = −5 mm, corotational FEM (E = 10 kPa, ν = 0.3, 1000 kg/m³), sagging
/// under gravity with Rayleigh stiffness damping β = 0.002 s (so that explicit Euler has a
/// stable step, between 0.21 and 0.22 ms), stepped @p steps times by @p integrator at @p dt_s
/// with a frame every @p output_every steps.
inline nlohmann::json clamped_cube_scene(const std::string& integrator, double dt_s, int steps, int output_every) {
  nlohmann::json scene = nlohmann::json::parse(R"({
    "gravity_mm_s2": [0, 0, -9806.65],
    "damping": {"rayleigh_stiffness_s": 0.002},
    "bodies": [{
      "mesh": {"generator": "cube", "edge_mm": 10, "cells": 2},
      "model": "corotational_fem",
      "material": {"youngs_modulus_pa": 1e4, "poisson_ratio": 0.3, "density_kg_m3": 1000},
      "fixed": [{"box_min_mm": [-6, -6, -6], "box_max_mm": [6, 6, -4.9]}]
    }]})");
  scene["integrator"] = integrator;
  scene["dt_s"] = dt_s;
  scene["steps"] = steps;
  scene["output_every"] = output_every;
  return scene;
}

}  // namespace ido::test

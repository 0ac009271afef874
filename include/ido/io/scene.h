// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "ido/core/progress.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/world.h"

namespace ido::io {

/// One body of a scene: a tetrahedral mesh whose vertices are the particles
/// [first_particle, first_particle + rest_mesh.vertex_count()) of the world.
struct SceneBody {
  std::string name;
  std::int32_t first_particle = 0;
  geometry::TetMesh rest_mesh;      ///< rest shape (mm), tetrahedra indexed from 0
  std::size_t model_index = 0;      ///< the body's force model in World::models()
  /// The FEM model giving strain / stress output; out of range for spring and meshless
  /// bodies, whose output uses corotational elasticity with `material` (diagnostic only).
  std::size_t stress_model_index = 0;
  sim::ElasticMaterial material;
};

/// A simulation scene (docs/scene.md): a world ready to step plus the run settings.
struct Scene {
  sim::World world;
  std::vector<SceneBody> bodies;
  double dt_s = 0.0;
  std::int64_t steps = 0;
  std::int64_t output_every = 1;    ///< write a frame every this many steps (and the last)
};

/// Reads a JSON scene; relative mesh paths are resolved against the scene's folder.
/// @throws ido::IoError when the file cannot be read or is not JSON (with byte offset);
/// ido::InvalidInput naming the file and the JSON pointer of the offending value, e.g.
/// `scene.json: /bodies/0/material/poisson_ratio: must be < 0.5`.
[[nodiscard]] Scene load_scene(const std::filesystem::path& path);

/// Same from text; @p source_name prefixes messages, @p base_dir resolves mesh paths.
[[nodiscard]] Scene parse_scene(std::string_view json_text, const std::string& source_name,
                                const std::filesystem::path& base_dir);

/// What run_scene() measured.
struct SceneRunResult {
  std::vector<double> time_s;             ///< energy samples
  std::vector<double> kinetic_mj, elastic_mj, gravitational_mj, total_mj;
  std::vector<double> step_ms;            ///< wall time of each step
  std::vector<int> cg_iterations;         ///< per step (0 for explicit schemes)
  std::int64_t frames = 0;
  double wall_time_s = 0.0;
};

/// Runs the scene's steps, writing into @p out_dir (created if missing): frame_NNNN.vtu per
/// output frame (point data displacement_mm, velocity_mm_s; cell data green_strain,
/// cauchy_stress_pa, von_mises_pa, body), simulation.pvd, energy.csv and report.json.
/// Reports progress and honours cancellation (ido::Cancelled).
SceneRunResult run_scene(Scene& scene, const std::filesystem::path& out_dir,
                         Progress* progress = nullptr);

}  // namespace ido::io

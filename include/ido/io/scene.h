// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "ido/core/atomic_file.h"
#include "ido/core/progress.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_common.h"
#include "ido/sim/runner.h"
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
  std::string source;               ///< the scene file's name, prefixing run-time messages
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

/// What run_scene() measured (sim::run's result).
using SceneRunResult = sim::RunResult;

/// How far the bodies' kinetic + elastic energy may exceed what the start state, the loads and
/// gravity can have given them before a run is called diverged (sim::run).
using sim::kDivergenceEnergyFactor;

/// The settings sim::run() takes for @p scene: its dt_s and steps, a frame every output_every
/// steps, the scene's file name as the label, and as the divergence floor the elastic energy
/// that strains every body by 0.1 % (½ E ε² V summed over the bodies, ε = 10⁻³), so that
/// rounding noise of a body at rest is not "divergence".
[[nodiscard]] sim::RunOptions run_options(const Scene& scene);

/// The run's report.json (docs/scene.md): steps, dt_s, the integrator (at the end), particles,
/// tetrahedra, frames, wall time, ms per step (p50, p90, p99, max), the final energy and the
/// CG iterations (mean, max, total). run_scene() writes it; a caller adding its own keys (e.g.
/// pictures) builds it again from the same result instead of reading the file back.
[[nodiscard]] nlohmann::json scene_report(const Scene& scene, const SceneRunResult& result);

/// Receives each output frame of run_scene() as it is written: the frame's index (0, 1, …)
/// and its mesh (the bodies' tetrahedra at the current positions with the fields of the
/// frame file), e.g. to draw it without reading the file back.
using SceneFrameListener = std::function<void(std::int64_t frame, const geometry::TetMesh& mesh)>;

/// Runs the scene's steps with sim::run() and an observer that writes into @p out_dir
/// (created if missing): frame_NNNN.vtu per output frame (point data displacement_mm,
/// velocity_mm_s; cell data green_strain, cauchy_stress_pa, von_mises_pa, body),
/// simulation.pvd, energy.csv and report.json. @p observers watch the same run after the
/// writer (sim::RunObserver), and @p on_frame gets every frame's mesh as written.
/// The outputs are written all or none: they are staged beside their targets and put in place
/// when the run has ended, by run_scene itself, or by the caller when @p outputs is given (the
/// caller may then stage more files in the same batch and commit them together).
///
/// A diverging run stops before its bad state reaches a file or an observer (sim::run gives
/// the rule; the floor is run_options()'s).
/// @throws sim::Diverged (an ido::InvalidInput) "<scene>: simulation diverged at step N of M
/// (t = … s): <cause>; reduce dt_s or use implicit_euler" — nothing of the run is left written
/// (the batch is discarded and a folder the run created is removed); ido::Cancelled, likewise.
SceneRunResult run_scene(Scene& scene, const std::filesystem::path& out_dir, Progress* progress = nullptr,
                         FileBatch* outputs = nullptr, std::span<sim::RunObserver* const> observers = {},
                         const SceneFrameListener& on_frame = {});

}  // namespace ido::io

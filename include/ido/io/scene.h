// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "ido/core/atomic_file.h"
#include "ido/core/progress.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/diagnostics.h"
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

/// What run_scene() measured.
struct SceneRunResult {
  std::vector<double> time_s;             ///< energy samples
  std::vector<double> kinetic_mj, elastic_mj, gravitational_mj, total_mj;
  std::vector<double> step_ms;            ///< wall time of each step
  std::vector<int> cg_iterations;         ///< per step (0 for explicit schemes)
  sim::EnergyReport final_energy;         ///< at the last step, per model too
  std::int64_t frames = 0;
  double wall_time_s = 0.0;
};

/// How far the bodies' kinetic + elastic energy may exceed what the start state, the loads and
/// gravity can have given them before run_scene() calls the run diverged (see run_scene).
inline constexpr double kDivergenceEnergyFactor = 10.0;

/// Runs the scene's steps, writing into @p out_dir (created if missing): frame_NNNN.vtu per
/// output frame (point data displacement_mm, velocity_mm_s; cell data green_strain,
/// cauchy_stress_pa, von_mises_pa, body), simulation.pvd, energy.csv and report.json.
/// The outputs are written all or none: they are staged beside their targets and put in place
/// when the run has ended, by run_scene itself, or by the caller when @p outputs is given (the
/// caller may then stage more files in the same batch and commit them together).
///
/// A diverging run stops before its bad state reaches a file: after every step the positions
/// and velocities must be finite, and before every energy sample and frame the bodies' kinetic
/// + elastic energy must stay within kDivergenceEnergyFactor times an upper bound of what the
/// run can have received: the start energy, plus Σ (|loads on i| + m_i |g|)·(|x_i − x_i⁰| +
/// |v_i| dt) for the work of point loads, tractions and gravity, plus a floor of the energy
/// that strains every body by 0.1 % (so that rounding noise of a body at rest is not
/// "divergence"). A stable integrator keeps to the energy balance (explicit schemes gain a
/// little), so only a run whose state grows without bound is stopped.
/// @throws ido::InvalidInput "<scene>: simulation diverged at step N of M (t = … s): <cause>;
/// reduce dt_s or use implicit_euler" — nothing of the run is left written (the batch is
/// discarded and a folder the run created is removed); ido::Cancelled, likewise.
SceneRunResult run_scene(Scene& scene, const std::filesystem::path& out_dir,
                         Progress* progress = nullptr, FileBatch* outputs = nullptr);

}  // namespace ido::io

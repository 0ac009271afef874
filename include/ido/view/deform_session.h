// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/lock_free.h"
#include "ido/io/scene.h"

namespace ido::view {

/// One energy sample of a running scene.
struct EnergySample {
  double t_s = 0.0;
  double kinetic_mj = 0.0, elastic_mj = 0.0, total_mj = 0.0;  ///< millijoules (N·mm)
  double step_ms = 0.0;                                        ///< wall time of the step (ms)
};

/// A number of the scene file that can be changed between two steps: a body's material
/// (Young's modulus, Poisson ratio, density), the numbers its model's own settings give
/// (`mass_spring`, `shape_matching`, `mls`: those the file sets) and the Rayleigh damping
/// (docs/scene.md).
struct SceneParameter {
  std::string pointer;  ///< JSON pointer into the scene file, e.g. "/bodies/0/material/youngs_modulus_pa"
  std::string label;    ///< what the panel shows, e.g. "beam: Young's modulus (Pa)"
  double value = 0.0;   ///< the file's value (0 for a damping coefficient it leaves out)
};

/// One change of a scene parameter.
struct ParameterChange {
  std::int64_t step = 0;  ///< the steps taken before it: step `step + 1` is the first with the new value
  std::string pointer;    ///< SceneParameter::pointer
  double value = 0.0;     ///< the new value
};

/// What the render thread sees of a scene: an immutable picture after some step.
struct DeformState {
  std::int64_t steps = 0;
  double time_s = 0.0;
  std::string integrator;
  std::vector<Vec3> positions_mm;    ///< every particle
  Vec3 linear_momentum = Vec3::Zero();  ///< Σ m v (kg·mm/s)
  /// Per tetrahedron of each body in order (empty for a body whose model gives no element
  /// fields): von Mises stress (Pa) and the equivalent Green strain √(2/3 e:e), e its
  /// deviatoric part (dimensionless).
  std::vector<std::vector<double>> von_mises_pa, equivalent_strain;
  std::vector<EnergySample> history;  ///< the last samples (at most kHistory), oldest first
  double grab_stiffness_n_per_mm = 0.0;  ///< the pull spring's stiffness in use (after the stability cap)
  std::string error;                  ///< set when the run stopped (diverged)
  /// The values of DeformSession::parameters() in use, in that order.
  std::vector<double> parameters;
  /// Every parameter change applied so far, oldest first.
  std::vector<ParameterChange> changes;
  /// Why the last change asked for was refused (the scene reader's message), else empty.
  std::string parameter_error;
  static constexpr std::size_t kHistory = 600;
};

/// A spring pulling one particle, with the particles of the tetrahedra around it, towards a
/// point: force k (target − x_c) on the group's centre of mass x_c, shared by mass. The spring is
/// explicit within each step, so k is capped at half its stability limit for the step,
/// 2 M / (dt² · 1000 kg·mm/(N·s²)), M the group's mass.
struct GrabSpring {
  bool active = false;
  std::int32_t particle = 0;
  Vec3 target_mm = Vec3::Zero();
  double stiffness_n_per_mm = 0.0;
};

/// Steps a scene's world on a worker thread, one World::step(dt) at a time, while the window
/// shows it. Run, pause, single steps, the integrator (switched between steps) and a grab
/// spring (a point load recomputed before each step) are set by the render thread through
/// atomics and triple buffers; states come back through a triple buffer. No lock either way.
/// A run stops (DeformState::error) when a state fails the project's divergence rule
/// (sim::DivergenceWatch with the scene's energy floor, io::run_options), the watch starting
/// again from the present state whenever the loads or the parameters change between steps.
class DeformSession {
 public:
  /// Takes the scene over; its parameters cannot be changed (parameters() is empty).
  /// @throws ido::InvalidInput for a scene without bodies.
  explicit DeformSession(io::Scene scene);
  /// Reads the scene file @p scene_file (io::load_scene) and keeps its text, so that its
  /// parameters can be changed between steps (set_parameters()).
  /// @throws as io::load_scene; ido::InvalidInput for a scene without bodies.
  explicit DeformSession(const std::filesystem::path& scene_file);
  ~DeformSession();
  DeformSession(const DeformSession&) = delete;
  DeformSession& operator=(const DeformSession&) = delete;

  void set_running(bool running) { m_running.store(running); }
  [[nodiscard]] bool running() const { return m_running.load(); }
  void step_once() { m_step_requests.fetch_add(1); }
  /// Switches to integrator @p name before the next step (a name of integrators()).
  void set_integrator(const std::string& name);
  void set_grab(const GrabSpring& grab) { m_grab.write(grab); }
  /// The scene's changeable parameters (empty for a session made from an io::Scene).
  [[nodiscard]] const std::vector<SceneParameter>& parameters() const { return m_parameters; }
  /// Asks for @p values (one per parameters(), in order) from the next step on. The worker
  /// applies them between two steps (at once while paused) through the library. The scene file
  /// with these values is read again by io::parse_scene, which checks them, naming the JSON
  /// pointer of a bad one (DeformState::parameter_error; the run goes on unchanged). A number
  /// the running world's objects take in place is given to them: Young's modulus and Poisson
  /// ratio (TetFemModel::set_material, MlsElasticity::set_material), the spring stiffness and
  /// damping (MassSpring), the shape-matching stiffness and β, the MLS volume stiffness and the
  /// Rayleigh damping; positions, velocities, the integrator's state (e.g. implicit Euler's warm
  /// start) and the models' caches (corotational rotations) go on, so the run is a library run
  /// that calls those setters at that step. A number the world is built from (a density: the
  /// particles' masses; a shape-matching cluster size; an MLS support radius) makes the read
  /// scene's world take over instead, with the particles' positions and velocities, the
  /// integrator and the step count and time (its integrator state and caches start afresh).
  /// @throws ido::InvalidInput for a wrong number of values.
  void set_parameters(const std::vector<double>& values);
  [[nodiscard]] const std::vector<std::string>& integrators() const { return m_integrator_names; }
  /// The scene's bodies (rest meshes and particle ranges); their particles are in DeformState.
  [[nodiscard]] const std::vector<io::SceneBody>& bodies() const { return m_bodies; }
  [[nodiscard]] double dt_s() const { return m_dt_s; }
  /// The newest state (never waits). Also true once a requested step has been taken.
  [[nodiscard]] std::shared_ptr<const DeformState> latest();
  /// True while steps are requested or running.
  [[nodiscard]] bool busy() const { return m_step_requests.load() > 0; }

 private:
  void work();
  [[nodiscard]] std::vector<std::int32_t> grab_group(std::int32_t particle) const;

  /// Worker: gives the world @p values where they differ from @p in_use (true when it did).
  bool apply_parameters(const std::vector<double>& values, std::vector<double>& in_use,
                        std::vector<ParameterChange>& changes, std::string& error);

  io::Scene m_scene;  // the worker's alone once started
  std::string m_scene_text;              // the scene file (empty: parameters cannot change)
  std::filesystem::path m_base_dir;      // where its mesh paths are resolved
  std::vector<SceneParameter> m_parameters;
  drill::TripleBuffer<std::shared_ptr<const std::vector<double>>> m_parameter_requests;
  std::int64_t m_step_base = 0;  // steps and time of the worlds replaced by parameter changes
  double m_time_base_s = 0.0;
  std::vector<io::SceneBody> m_bodies;
  std::vector<std::string> m_integrator_names;
  double m_dt_s = 0.0;
  std::atomic<bool> m_running{false}, m_stop{false};
  std::atomic<std::int64_t> m_step_requests{0};
  std::atomic<int> m_integrator_request{-1};
  drill::TripleBuffer<GrabSpring> m_grab;
  drill::TripleBuffer<std::shared_ptr<const DeformState>> m_states;
  std::shared_ptr<const DeformState> m_latest;
  std::thread m_thread;
};

}  // namespace ido::view

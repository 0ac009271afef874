// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <atomic>
#include <cstdint>
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
class DeformSession {
 public:
  /// Takes the scene over. @throws ido::InvalidInput for a scene without bodies.
  explicit DeformSession(io::Scene scene);
  ~DeformSession();
  DeformSession(const DeformSession&) = delete;
  DeformSession& operator=(const DeformSession&) = delete;

  void set_running(bool running) { m_running.store(running); }
  [[nodiscard]] bool running() const { return m_running.load(); }
  void step_once() { m_step_requests.fetch_add(1); }
  /// Switches to integrator @p name before the next step (a name of integrators()).
  void set_integrator(const std::string& name);
  void set_grab(const GrabSpring& grab) { m_grab.write(grab); }
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

  io::Scene m_scene;  // the worker's alone once started
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

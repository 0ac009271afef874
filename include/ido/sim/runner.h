// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/math.h"
#include "ido/core/progress.h"
#include "ido/sim/diagnostics.h"

namespace ido::sim {

class World;

/// How far the world's kinetic + elastic energy may exceed what the start state, the loads
/// and gravity can have given it before run() calls the run diverged (see run()).
inline constexpr double kDivergenceEnergyFactor = 10.0;

/// Settings of run().
struct RunOptions {
  double dt_s = 0.0;                ///< step (s), > 0 and finite
  std::int64_t steps = 0;           ///< number of steps, ≥ 1
  /// RunObserver::on_frame after every this many steps, and after the last (≥ 1); frame 0 is
  /// the start state.
  std::int64_t frame_every = 1;
  /// Energy samples (RunObserver::on_sample, RunResult's series) every this many steps and
  /// after the last; 0: max(1, steps / 2000).
  std::int64_t sample_every = 0;
  /// Energy (mJ) below which no run is called diverged, so that rounding noise of a body at
  /// rest is not "divergence"; e.g. the elastic energy that strains every body by 0.1 %.
  double energy_floor_mj = 0.0;
  /// Names the run in the divergence message, e.g. the scene file.
  std::string label = "scene";
};

/// What run() measured.
struct RunResult {
  std::vector<double> time_s;             ///< energy samples
  std::vector<double> kinetic_mj, elastic_mj, gravitational_mj, total_mj;
  std::vector<double> step_ms;            ///< wall time of each step
  std::vector<int> cg_iterations;         ///< per step (0 for explicit schemes)
  EnergyReport final_energy;              ///< at the last step, per model too
  std::int64_t frames = 0;                ///< frames handed to the observers
  double wall_time_s = 0.0;               ///< of the steps
};

/// Watches a run() (energy sampling, frames written to files, pictures, a window): run()
/// calls it with states that passed the divergence checks only. Every call is optional.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// After each step, with its wall time; positions and velocities are finite. The world is
  /// the observer's to steer before the next step (switch the integrator, change a model's
  /// parameters, move a particle).
  virtual void on_step(World& world, std::int64_t step, double step_ms) {
    (void)world, (void)step, (void)step_ms;
  }
  /// An energy sample (step 0: the start state), within the divergence bound.
  virtual void on_sample(const World& world, std::int64_t step, const EnergyReport& energy) {
    (void)world, (void)step, (void)energy;
  }
  /// Frame @p frame (0, 1, …) at step @p step (0: the start state), within the divergence
  /// bound.
  virtual void on_frame(const World& world, std::int64_t frame, std::int64_t step) {
    (void)world, (void)frame, (void)step;
  }
  /// After the last step, with everything measured.
  virtual void on_finish(const World& world, const RunResult& result) { (void)world, (void)result; }
};

/// The project's rule for when a simulation has diverged, applied by run() and by any loop that
/// steps a world itself (the viewer's Deform workspace). A state has diverged when
/// - a position or velocity is not finite (check_finite(), after every step), or
/// - its kinetic + elastic energy is not finite or exceeds kDivergenceEnergyFactor times an upper
///   bound of what the world can have received since the watch's start (check_energy(), before
///   a state is handed on): the start energy, plus Σ (|loads on i| + m_i |g|)·(|x_i − x_i⁰| +
///   |v_i| dt) for the work of the point loads and gravity acting at the start, plus an energy
///   floor, so that rounding noise of a body at rest is not divergence.
/// A stable integrator keeps to the energy balance (explicit schemes gain a little), so only a
/// state that grows without bound fails. A caller that changes the world's loads or models
/// between steps starts a new watch from the changed state.
class DivergenceWatch {
 public:
  /// Takes @p world's present state as the start: positions, the point loads and gravity, and
  /// the kinetic + elastic energy. @p dt_s is the step (s), @p energy_floor_mj ≥ 0 the floor
  /// (mJ, RunOptions::energy_floor_mj).
  DivergenceWatch(const World& world, double dt_s, double energy_floor_mj = 0.0);
  /// Why @p world's state has diverged by its positions and velocities ("particle 12 has a
  /// non-finite velocity"), or nothing.
  [[nodiscard]] std::optional<std::string> check_finite(const World& world) const;
  /// Why @p world's state has diverged by its energy @p energy (energies(world)), e.g.
  /// "kinetic + elastic energy 5.11e+05 mJ is over 10 times what the start state, loads and
  /// gravity can have given (60.7 mJ)", or nothing.
  [[nodiscard]] std::optional<std::string> check_energy(const World& world, const EnergyReport& energy) const;
  /// The bound (mJ) the kinetic + elastic energy of @p world's present state is held to.
  [[nodiscard]] double energy_bound_mj(const World& world) const;
  /// What a caller says when a state fails: "simulation diverged at step N of M (t = … s):
  /// <cause>; reduce dt_s (now …) or use implicit_euler" (" of M" only with @p of_steps).
  [[nodiscard]] std::string message(std::int64_t step, std::optional<std::int64_t> of_steps, double time_s,
                                    const std::string& cause) const;

 private:
  std::vector<Vec3> m_start;            ///< positions at the start (mm)
  std::vector<double> m_coefficient_n;  ///< |Σ point loads| + m |g| per particle (N)
  double m_start_mj = 0.0;
  double m_dt_s = 0.0;
  double m_floor_mj = 0.0;
};

/// A run that diverged (run()): an InvalidInput naming the step.
class Diverged : public InvalidInput {
 public:
  Diverged(const std::string& what, std::int64_t step) : InvalidInput(what), m_step(step) {}
  /// The step after which the state failed the check.
  [[nodiscard]] std::int64_t step() const noexcept { return m_step; }

 private:
  std::int64_t m_step;
};

/// Steps @p world options.steps times with its current integrator (which may change between
/// steps, e.g. from an observer's on_step), sampling energies and calling the observers in the order
/// given: at the start on_sample and on_frame with the start state; after each step on_step,
/// then on_sample and on_frame when due; at the end on_finish. The library's convenience loop:
/// World::step() remains the one-step call for callers who own their loop.
///
/// A diverging run stops before its bad state reaches an observer: a DivergenceWatch started
/// with the world's state at the call (floor options.energy_floor_mj) checks the positions and
/// velocities after every step and the energy before every sample and frame.
/// @throws Diverged "<label>: simulation diverged at step N of M (t = … s): <cause>; reduce
/// dt_s (now …) or use implicit_euler"; ido::Cancelled through @p progress; ido::InvalidInput
/// for bad options; whatever an observer or the integrator throws.
RunResult run(World& world, const RunOptions& options, std::span<RunObserver* const> observers = {},
              Progress* progress = nullptr);

}  // namespace ido::sim

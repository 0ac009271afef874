// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ido/core/error.h"
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
/// A diverging run stops before its bad state reaches an observer: after every step the
/// positions and velocities must be finite, and before every sample and frame the world's
/// kinetic + elastic energy must stay within kDivergenceEnergyFactor times an upper bound of
/// what the run can have received: the start energy, plus Σ (|loads on i| + m_i |g|)·(|x_i −
/// x_i⁰| + |v_i| dt) for the work of point loads and gravity, plus options.energy_floor_mj.
/// A stable integrator keeps to the energy balance (explicit schemes gain a little), so only a
/// run whose state grows without bound is stopped.
/// @throws Diverged "<label>: simulation diverged at step N of M (t = … s): <cause>; reduce
/// dt_s (now …) or use implicit_euler"; ido::Cancelled through @p progress; ido::InvalidInput
/// for bad options; whatever an observer or the integrator throws.
RunResult run(World& world, const RunOptions& options, std::span<RunObserver* const> observers = {},
              Progress* progress = nullptr);

}  // namespace ido::sim

// SPDX-License-Identifier: Apache-2.0
#include "ido/sim/runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "ido/sim/units.h"
#include "ido/sim/world.h"

namespace ido::sim {

DivergenceWatch::DivergenceWatch(const World& world, double dt_s, double energy_floor_mj)
    : m_dt_s(dt_s), m_floor_mj(energy_floor_mj) {
  const auto& p = world.particles();
  m_start = p.positions();
  m_coefficient_n.assign(p.size(), 0.0);
  std::vector<Vec3> load(p.size(), Vec3::Zero());
  for (const auto& l : world.external().point_loads)
    if (l.particle >= 0 && static_cast<std::size_t>(l.particle) < p.size())
      load[static_cast<std::size_t>(l.particle)] += l.force_n;
  const double g = world.external().gravity_mm_s2.norm();
  for (std::size_t i = 0; i < p.size(); ++i)
    m_coefficient_n[i] = load[i].norm() + p.masses()[i] * g * kKgMmPerS2ToNewton;
  const auto e = energies(world);
  m_start_mj = e.kinetic_mj + e.elastic_total_mj();
}

std::optional<std::string> DivergenceWatch::check_finite(const World& world) const {
  const auto& p = world.particles();
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!p.positions()[i].allFinite() || !p.velocities()[i].allFinite())
      return fmt::format("particle {} has a non-finite {}", i, p.positions()[i].allFinite() ? "velocity" : "position");
  return std::nullopt;
}

double DivergenceWatch::energy_bound_mj(const World& world) const {
  const auto& p = world.particles();
  double work_mj = 0.0;
  for (std::size_t i = 0; i < m_start.size() && i < p.size(); ++i)
    if (m_coefficient_n[i] > 0.0)
      work_mj += m_coefficient_n[i] * ((p.positions()[i] - m_start[i]).norm() + p.velocities()[i].norm() * m_dt_s);
  return m_start_mj + work_mj + m_floor_mj;
}

std::optional<std::string> DivergenceWatch::check_energy(const World& world, const EnergyReport& e) const {
  const double mech_mj = e.kinetic_mj + e.elastic_total_mj();
  if (!std::isfinite(mech_mj) || !std::isfinite(e.gravitational_mj)) return std::string("the energy is not finite");
  const double bound_mj = energy_bound_mj(world);
  if (mech_mj > kDivergenceEnergyFactor * bound_mj)
    return fmt::format("kinetic + elastic energy {:.3g} mJ is over {:g} times what the start state, loads and "
                       "gravity can have given ({:.3g} mJ)",
                       mech_mj, kDivergenceEnergyFactor, bound_mj);
  return std::nullopt;
}

std::string DivergenceWatch::message(std::int64_t step, std::optional<std::int64_t> of_steps, double time_s,
                                     const std::string& cause) const {
  return fmt::format("simulation diverged at step {}{} (t = {:.6g} s): {}; reduce dt_s (now {:g}) or use implicit_euler",
                     step, of_steps ? fmt::format(" of {}", *of_steps) : std::string(), time_s, cause, m_dt_s);
}

RunResult run(World& world, const RunOptions& options, std::span<RunObserver* const> observers,
              Progress* progress) {
  if (!(options.dt_s > 0.0) || !std::isfinite(options.dt_s))
    throw InvalidInput(fmt::format("run: dt_s must be positive and finite, got {}", options.dt_s));
  if (options.steps < 1) throw InvalidInput(fmt::format("run: steps must be >= 1, got {}", options.steps));
  if (options.frame_every < 1)
    throw InvalidInput(fmt::format("run: frame_every must be >= 1, got {}", options.frame_every));
  if (options.sample_every < 0)
    throw InvalidInput(fmt::format("run: sample_every must be >= 0, got {}", options.sample_every));
  if (!(options.energy_floor_mj >= 0.0) || !std::isfinite(options.energy_floor_mj))
    throw InvalidInput(fmt::format("run: energy_floor_mj must be >= 0 and finite, got {}", options.energy_floor_mj));

  RunResult result;
  const std::int64_t sample_every =
      options.sample_every > 0 ? options.sample_every : std::max<std::int64_t>(1, options.steps / 2000);
  auto sample = [&](std::int64_t step, const EnergyReport& e) {
    result.time_s.push_back(world.time_s());
    result.kinetic_mj.push_back(e.kinetic_mj);
    result.elastic_mj.push_back(e.elastic_total_mj());
    result.gravitational_mj.push_back(e.gravitational_mj);
    result.total_mj.push_back(e.total_mj());
    for (auto* o : observers) o->on_sample(world, step, e);
  };
  auto frame = [&](std::int64_t step) {
    const std::int64_t index = result.frames++;
    for (auto* o : observers) o->on_frame(world, index, step);
  };

  const DivergenceWatch watch(world, options.dt_s, options.energy_floor_mj);
  // A state the watch refuses ends the run before anything of it is handed on.
  auto stop_if = [&](std::int64_t step, const std::optional<std::string>& cause) {
    if (!cause) return;
    throw Diverged(fmt::format("{}: {}", options.label.empty() ? std::string("scene") : options.label,
                               watch.message(step, options.steps, world.time_s(), *cause)),
                   step);
  };
  sample(0, energies(world));
  frame(0);
  const auto t_start = std::chrono::steady_clock::now();
  for (std::int64_t s = 1; s <= options.steps; ++s) {
    check_cancel(progress);
    const auto t0 = std::chrono::steady_clock::now();
    world.step(options.dt_s);
    const auto t1 = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    result.step_ms.push_back(ms);
    result.cg_iterations.push_back(world.last_step().cg_iterations);
    stop_if(s, watch.check_finite(world));
    for (auto* o : observers) o->on_step(world, s, ms);
    const bool sample_now = s % sample_every == 0 || s == options.steps;
    const bool frame_now = s % options.frame_every == 0 || s == options.steps;
    if (sample_now || frame_now) {
      // Checked before anything of this state is handed on: a diverged state reaches no file.
      const auto e = energies(world);
      stop_if(s, watch.check_energy(world, e));
      if (sample_now) sample(s, e);
      if (frame_now) frame(s);
    }
    report(progress, static_cast<double>(s) / static_cast<double>(options.steps), "simulating");
  }
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  result.final_energy = energies(world);
  for (auto* o : observers) o->on_finish(world, result);
  return result;
}

}  // namespace ido::sim

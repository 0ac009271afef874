// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace ido::sim {

class World;

/// A time-stepping scheme: advances @p world by @p dt_s seconds, reading forces through
/// World::compute_forces() / World::accelerations() and updating the particles' positions
/// and velocities (never touching fixed particles). Registered under a name in a world's
/// IntegratorRegistry (the paper's run-time pluggable integrator).
using IntegratorFn = std::function<void(World& world, double dt_s)>;

/// Integrators by name. Each World owns one (no global state), pre-filled with
/// explicit_euler, symplectic_euler, velocity_verlet, rk4 and implicit_euler.
class IntegratorRegistry {
 public:
  /// A registry holding the built-in schemes.
  IntegratorRegistry();
  /// Adds or replaces the scheme @p name. @throws ido::InvalidInput for an empty name or fn.
  void add(const std::string& name, IntegratorFn fn);
  [[nodiscard]] bool contains(const std::string& name) const;
  /// @throws ido::InvalidInput naming the unknown scheme and listing the known ones.
  [[nodiscard]] const IntegratorFn& get(const std::string& name) const;
  /// Names in alphabetical order.
  [[nodiscard]] std::vector<std::string> names() const;

 private:
  std::map<std::string, IntegratorFn> m_fns;
};

/// Built-in schemes as free functions (each uses only the world's current state, so the
/// scheme can change between steps with nothing lost).
namespace integrators {
/// x += dt v(t); v += dt a(x(t), v(t)). First order, energy grows.
void explicit_euler(World& world, double dt_s);
/// v += dt a(x(t), v(t)); x += dt v(t+dt). First order, symplectic.
void symplectic_euler(World& world, double dt_s);
/// Velocity Verlet (Swope et al. 1982): second order, symplectic; two force evaluations
/// per step because no acceleration is carried between steps.
void velocity_verlet(World& world, double dt_s);
/// Classical fourth-order Runge–Kutta on (x, v).
void rk4(World& world, double dt_s);
/// Backward Euler linearised once per step (Baraff & Witkin 1998):
/// (M + dt C + dt² K) Δv = dt (f − dt K v), solved with preconditioned conjugate gradients
/// (symmetric block SOR by default, or Jacobi) warm-started from the previous steps' Δv
/// (World::implicit_options()). K is assembled once per step into a block-sparse matrix
/// (upper block triangle only: the models' stiffness must be symmetric, with a symmetric
/// pattern) whose pattern is built once. Models without stiffness contribute their forces
/// only. @throws ido::InvalidInput for a relaxation outside (0, 2).
void implicit_euler(World& world, double dt_s);
}  // namespace integrators

}  // namespace ido::sim

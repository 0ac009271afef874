// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace ido::sim {

class World;

/// A time-stepping scheme as an object: it owns its options and whatever it carries from one
/// step to the next (implicit Euler its sparsity pattern and warm start, a Newmark scheme its
/// acceleration). step() advances the world by one step, reading forces through
/// World::compute_forces() / World::accelerations() and updating the particles' positions and
/// velocities (never moving fixed particles). A World makes one instance per scheme name from
/// its IntegratorRegistry, the first time the scheme is selected, and keeps it for its own
/// life: switching to another scheme and back keeps the instance and its state (the paper's
/// run-time switchable integrators). An instance serves one world.
class Integrator {
 public:
  Integrator() = default;
  virtual ~Integrator() = default;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  /// Advances @p world by @p dt_s seconds (> 0, checked by World::step).
  virtual void step(World& world, double dt_s) = 0;
  /// Short name of the scheme, e.g. "implicit_euler".
  [[nodiscard]] virtual std::string_view name() const = 0;
};

/// The simplest scheme: a function of the world's current state alone (it carries nothing
/// between steps). Registered with IntegratorRegistry::add(name, fn).
using IntegratorFn = std::function<void(World& world, double dt_s)>;

/// Makes a new instance of a scheme (with its default options and empty state).
using IntegratorFactory = std::function<std::unique_ptr<Integrator>()>;

/// Schemes by name. Each World owns one (no global state), pre-filled with explicit_euler,
/// symplectic_euler, velocity_verlet, rk4 and implicit_euler.
class IntegratorRegistry {
 public:
  /// A registry holding the built-in schemes.
  IntegratorRegistry();
  /// Adds or replaces the scheme @p name by a stateless function (wrapped in an Integrator).
  /// @throws ido::InvalidInput for an empty name or function.
  void add(const std::string& name, IntegratorFn fn);
  /// Adds or replaces the scheme @p name by a factory of Integrator objects (a scheme with
  /// options and state). A world that already made an instance of a replaced scheme makes a
  /// new one before its next step with it. @throws ido::InvalidInput for an empty name or
  /// factory.
  void add(const std::string& name, IntegratorFactory factory);
  [[nodiscard]] bool contains(const std::string& name) const;
  /// A new instance of the scheme @p name. @throws ido::InvalidInput naming the unknown
  /// scheme and listing the known ones, or if the factory returns nothing.
  [[nodiscard]] std::unique_ptr<Integrator> create(const std::string& name) const;
  /// A number that changes whenever @p name is (re)registered (0 if unknown).
  [[nodiscard]] std::uint64_t revision(const std::string& name) const;
  /// Names in alphabetical order.
  [[nodiscard]] std::vector<std::string> names() const;

 private:
  struct Entry {
    IntegratorFactory factory;
    std::uint64_t revision = 0;
  };
  void put(const std::string& name, IntegratorFactory factory);
  std::map<std::string, Entry> m_entries;
  std::uint64_t m_next_revision = 1;
};

/// Built-in explicit schemes as free functions (each uses only the world's current state, so
/// the scheme can change between steps with nothing lost; a user scheme may call them).
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
/// One step of the world's own implicit Euler instance (World::scheme("implicit_euler"), see
/// ImplicitEuler in implicit_euler.h), whatever scheme is selected: its options and warm
/// start are those of that instance. @throws ido::InvalidInput if the world's
/// "implicit_euler" is not an ImplicitEuler, or as ImplicitEuler::step.
void implicit_euler(World& world, double dt_s);
}  // namespace integrators

}  // namespace ido::sim

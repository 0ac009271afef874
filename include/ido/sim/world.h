// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/external_forces.h"
#include "ido/sim/force_model.h"
#include "ido/sim/implicit_euler.h"
#include "ido/sim/integrator.h"
#include "ido/sim/particles.h"

namespace ido::sim {

/// What the last step did.
struct StepStats {
  int cg_iterations = 0;          ///< implicit schemes only
  double cg_relative_residual = 0.0;
  int force_evaluations = 0;
};

/// A simulated world: particles, force models, external forces and its integrators (one
/// instance per scheme used, and the one selected).
/// The caller owns the loop: step() performs exactly one step (the paper's IdoLib design).
/// Worlds share nothing, so separate worlds may run in separate threads.
class World {
 public:
  World();
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  [[nodiscard]] Particles& particles() noexcept { return m_particles; }
  [[nodiscard]] const Particles& particles() const noexcept { return m_particles; }

  /// Adds one particle per mesh vertex with lumped masses (each tetrahedron gives a quarter
  /// of its mass, density × volume, to each vertex) and returns the index of the first.
  /// @p density_kg_m3 > 0. @throws ido::InvalidInput for an empty mesh, bad indices or an
  /// inverted / degenerate tetrahedron (naming it), or a vertex no tetrahedron uses; the world
  /// is unchanged then.
  std::int32_t add_tet_body(const geometry::TetMesh& mesh, double density_kg_m3);

  /// Adds a force model (the world owns it) and returns a reference to it.
  ForceModel& add_model(std::unique_ptr<ForceModel> model);
  template <class Model, class... Args>
  Model& emplace_model(Args&&... args) {
    return static_cast<Model&>(add_model(std::make_unique<Model>(std::forward<Args>(args)...)));
  }
  [[nodiscard]] std::span<const std::unique_ptr<ForceModel>> models() const noexcept {
    return m_models;
  }

  [[nodiscard]] ExternalForces& external() noexcept { return m_external; }
  [[nodiscard]] const ExternalForces& external() const noexcept { return m_external; }

  /// The world's integrators; register new ones here.
  [[nodiscard]] IntegratorRegistry& integrators() noexcept { return m_registry; }
  [[nodiscard]] const IntegratorRegistry& integrators() const noexcept { return m_registry; }
  /// Selects the integrator used by the next step() (making the world's instance of it if it
  /// has none yet). @throws ido::InvalidInput if unknown.
  void set_integrator(const std::string& name);
  [[nodiscard]] const std::string& integrator() const noexcept { return m_integrator; }

  /// The world's instance of scheme @p name, made on first use and kept for the world's life
  /// (selected or not), so its options and state survive switching away and back. A scheme
  /// re-registered since is made anew. @throws ido::InvalidInput if unknown.
  [[nodiscard]] Integrator& scheme(const std::string& name);
  /// scheme(@p name) as a @p Scheme, to reach its options. @throws ido::InvalidInput if the
  /// scheme registered under @p name is of another type.
  template <class Scheme>
  [[nodiscard]] Scheme& scheme_as(const std::string& name) {
    auto* s = dynamic_cast<Scheme*>(&scheme(name));
    if (!s) throw_scheme_type(name);
    return *s;
  }
  /// The options of the world's implicit Euler instance: scheme_as<ImplicitEuler>(
  /// "implicit_euler").options(). @throws ido::InvalidInput if "implicit_euler" was replaced
  /// by a scheme of another type.
  [[nodiscard]] ImplicitEulerOptions& implicit_options() {
    return scheme_as<ImplicitEuler>("implicit_euler").options();
  }

  /// Runs force assembly with oneTBB (default true). Results do not depend on it.
  void set_threaded(bool threaded) noexcept { m_threaded = threaded; }
  [[nodiscard]] bool threaded() const noexcept { return m_threaded; }

  /// Advances by @p dt_s seconds with the current integrator, then applies plane contacts.
  /// @throws ido::InvalidInput if dt_s is not positive and finite.
  void step(double dt_s);
  [[nodiscard]] double time_s() const noexcept { return m_time_s; }
  [[nodiscard]] std::int64_t step_count() const noexcept { return m_steps; }
  [[nodiscard]] const StepStats& last_step() const noexcept { return m_stats; }

  /// Sets particles().forces() to the total force (N) at the current state: models,
  /// gravity, Rayleigh damping, point loads. Fixed particles get zero force.
  void compute_forces();
  /// Accelerations (mm/s²) from the current forces: a = f / (m · kKgMmPerS2ToNewton), zero
  /// for fixed particles. Call compute_forces() first.
  [[nodiscard]] std::vector<Vec3> accelerations() const;

  /// Scheme support: the stats of the step being taken (integrators write into it).
  [[nodiscard]] StepStats& step_stats() noexcept { return m_stats; }
  /// Scheme support: a number that changes whenever a force model is added, so a scheme that
  /// caches something built from the models (a sparsity pattern) knows to rebuild it.
  [[nodiscard]] std::uint64_t model_revision() const noexcept { return m_model_revision; }

 private:
  [[noreturn]] static void throw_scheme_type(const std::string& name);

  Particles m_particles;
  std::vector<std::unique_ptr<ForceModel>> m_models;
  ExternalForces m_external;
  /// An instance of a scheme and the registry revision it was made from.
  struct SchemeSlot {
    std::unique_ptr<Integrator> instance;
    std::uint64_t revision = 0;
  };
  IntegratorRegistry m_registry;
  std::string m_integrator = "symplectic_euler";
  std::map<std::string, SchemeSlot> m_schemes;
  std::uint64_t m_model_revision = 0;
  StepStats m_stats;
  double m_time_s = 0.0;
  std::int64_t m_steps = 0;
  bool m_threaded = true;
};

/// Options of solve_static().
struct StaticSolveOptions {
  int max_newton_iterations = 20;
  double force_tolerance_n = 1e-9;   ///< stop when the largest free-particle force is below
};

/// Result of solve_static().
struct StaticSolveResult {
  int newton_iterations = 0;
  double max_residual_force_n = 0.0;
  bool converged = false;
};

/// Static equilibrium f(x) = 0 by Newton's method with the models' stiffness, each linear
/// system solved by sparse LDLᵀ (Eigen SimplicialLDLT). Velocities are set to zero.
/// Velocity-dependent forces are ignored; models without stiffness make it fail to converge.
/// @throws ido::InvalidInput if the stiffness is singular (e.g. nothing fixed).
StaticSolveResult solve_static(World& world, const StaticSolveOptions& options = {});

}  // namespace ido::sim

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/sim/external_forces.h"
#include "ido/sim/force_model.h"
#include "ido/sim/integrator.h"
#include "ido/sim/particles.h"

namespace ido::sim {

/// Preconditioner of the implicit Euler conjugate-gradient solve.
enum class CgPreconditioner {
  /// Inverse of the system matrix's diagonal (Jacobi).
  Jacobi,
  /// Symmetric block Gauss–Seidel / SSOR: M = (D̃ + L) D̃⁻¹ (D̃ + Lᵀ) with D̃ = D / ω, D the
  /// 3×3 diagonal blocks and L the strictly lower block triangle (Saad, "Iterative Methods
  /// for Sparse Linear Systems", 2nd ed. 2003, §10.2), ω = ImplicitEulerOptions::
  /// sgs_relaxation. A quarter to a third of Jacobi's iterations on FEM beams. Applied with
  /// Eisenstat's trick, so an iteration costs one pass over the matrix, like Jacobi's;
  /// sequential (deterministic).
  SymmetricGaussSeidel,
};

/// Longest warm-start history of the implicit Euler solve (ImplicitEulerOptions).
inline constexpr int kMaxWarmStartHistory = 16;

/// Settings of the implicit Euler scheme's conjugate-gradient solve.
struct ImplicitEulerOptions {
  double cg_tolerance = 1e-6;     ///< stop when ‖r‖ ≤ tolerance · ‖b‖
  int cg_max_iterations = 500;    ///< cap on CG iterations per step
  bool warm_start = true;         ///< start CG from the previous step's Δv
  /// With warm_start: start instead from the best approximation of Δv (in the A-norm, a
  /// Galerkin projection) in the span of the last warm_start_history steps' Δv — which
  /// contains the linear extrapolation 2 Δvₙ₋₁ − Δvₙ₋₂. Costs one product with the system
  /// matrix per stored step; 46 % fewer CG iterations than the extrapolation on the
  /// benchmark beam with 5 steps.
  bool warm_start_extrapolation = true;
  /// Number of previous steps' Δv the projected warm start uses, 1 to
  /// kMaxWarmStartHistory (implicit_euler throws ido::InvalidInput otherwise). 2 spans the
  /// linear extrapolation; on the 7350-tet benchmark beam 2 → 60, 3 → 51, 4 → 40, 5 → 36,
  /// 8 → 30 CG iterations per step.
  int warm_start_history = 5;
  CgPreconditioner preconditioner = CgPreconditioner::SymmetricGaussSeidel;
  /// Relaxation ω of the Gauss–Seidel preconditioner: symmetric SOR (Saad 2003, §10.2),
  /// D replaced by D / ω; 1 is plain symmetric Gauss–Seidel. 1.3 takes 10–30 % fewer CG
  /// iterations than 1 on the benchmark beams (1.3–1.4 best there, worse again from 1.5).
  /// Must be in (0, 2): implicit_euler throws ido::InvalidInput otherwise.
  double sgs_relaxation = 1.3;
};

/// What the last step did.
struct StepStats {
  int cg_iterations = 0;          ///< implicit schemes only
  double cg_relative_residual = 0.0;
  int force_evaluations = 0;
};

/// A simulated world: particles, force models, external forces and the current integrator.
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
  /// inverted / degenerate tetrahedron (naming it), or a vertex no tetrahedron uses.
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
  /// Selects the integrator used by the next step(). @throws ido::InvalidInput if unknown.
  void set_integrator(const std::string& name);
  [[nodiscard]] const std::string& integrator() const noexcept { return m_integrator; }

  [[nodiscard]] ImplicitEulerOptions& implicit_options() noexcept { return m_implicit; }

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

  /// Cached implicit-solver state (sparsity pattern, warm start); opaque.
  struct ImplicitCache;
  [[nodiscard]] ImplicitCache& implicit_cache();

 private:
  Particles m_particles;
  std::vector<std::unique_ptr<ForceModel>> m_models;
  ExternalForces m_external;
  IntegratorRegistry m_registry;
  std::string m_integrator = "symplectic_euler";
  ImplicitEulerOptions m_implicit;
  std::unique_ptr<ImplicitCache> m_cache;
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

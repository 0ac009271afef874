// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>
#include <string_view>

#include "ido/sim/integrator.h"

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
  /// kMaxWarmStartHistory (step() throws ido::InvalidInput otherwise). 2 spans the
  /// linear extrapolation; on the 7350-tet benchmark beam 2 → 60, 3 → 51, 4 → 40, 5 → 36,
  /// 8 → 30 CG iterations per step.
  int warm_start_history = 5;
  CgPreconditioner preconditioner = CgPreconditioner::SymmetricGaussSeidel;
  /// Relaxation ω of the Gauss–Seidel preconditioner: symmetric SOR (Saad 2003, §10.2),
  /// D replaced by D / ω; 1 is plain symmetric Gauss–Seidel. 1.3 takes 10–30 % fewer CG
  /// iterations than 1 on the benchmark beams (1.3–1.4 best there, worse again from 1.5).
  /// Must be in (0, 2): step() throws ido::InvalidInput otherwise.
  double sgs_relaxation = 1.3;
};

/// Backward Euler linearised once per step (Baraff & Witkin, "Large Steps in Cloth
/// Simulation", SIGGRAPH 1998): (M + dt C + dt² K) Δv = dt (f − dt K v), C the Rayleigh
/// damping α M + β K, solved with preconditioned conjugate gradients (symmetric block SOR by
/// default, or Jacobi) warm-started from the previous steps' Δv. K is assembled once per step
/// into a block-sparse matrix (upper block triangle only: the models' stiffness must be
/// symmetric, with a symmetric pattern) whose pattern is built once per set of models,
/// particle count and fixed set. Models without stiffness contribute their forces only.
///
/// The instance owns its options, the sparsity pattern, the warm-start history and the CG
/// work vectors; the history is used only over consecutive steps of this instance (another
/// scheme may have run between).
class ImplicitEuler final : public Integrator {
 public:
  explicit ImplicitEuler(const ImplicitEulerOptions& options = {});
  ~ImplicitEuler() override;

  /// @throws ido::InvalidInput for a relaxation outside (0, 2), a warm-start history
  /// outside 1..kMaxWarmStartHistory, or a force model referring to a missing particle.
  void step(World& world, double dt_s) override;
  [[nodiscard]] std::string_view name() const override { return "implicit_euler"; }

  /// The solve's settings; may change between steps.
  [[nodiscard]] ImplicitEulerOptions& options() noexcept { return m_options; }
  [[nodiscard]] const ImplicitEulerOptions& options() const noexcept { return m_options; }

 private:
  struct Solver;   // pattern, assembled matrix, warm start, work vectors (implicit_euler.cpp)
  ImplicitEulerOptions m_options;
  std::unique_ptr<Solver> m_solver;
};

}  // namespace ido::sim

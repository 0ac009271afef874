// SPDX-License-Identifier: Apache-2.0
// Private: the assembled block-sparse stiffness used by implicit Euler and the solver's work
// vectors. The system is symmetric, so only its upper block triangle is stored (BSR, 3×3
// blocks, rows in solver order, the diagonal block first in each row). Solver order: the free
// particles only (fixed particles do not move; their rows and columns are dropped). The
// pattern is built once per (model set, particle count, fixed set); each step only refills
// the values, every model adding its blocks straight into their slots in a fixed order
// (deterministic whether threaded or not).
#pragma once

#include <cstdint>
#include <vector>

#include "ido/sim/world.h"

namespace ido::sim {

struct World::ImplicitCache {
  bool valid = false;
  std::size_t particle_count = 0;
  std::vector<std::uint8_t> fixed;           // fixed flags the pattern was built for
  std::vector<std::int32_t> particle_of;     // solver index → particle
  std::vector<std::int32_t> row_offset;      // upper BSR rows, solver order
  std::vector<std::int32_t> col;             // column (solver index) per slot, sorted per row
  std::vector<std::vector<std::int32_t>> model_slots;   // per model: slot of each pattern
                                                        // block, −1 for lower or fixed ones
  std::vector<Mat3> values;                  // K per slot (N/mm), then A = M' + ak K in place
  std::vector<Mat3> dinv;                    // per row: inverse of the preconditioner's
                                             // diagonal block
  std::vector<std::int32_t> fallback_rows;   // rows whose diagonal block is not SPD
  std::vector<Mat3> fallback_excess;         // their A_ii − ω D̃_i
  std::vector<std::vector<Vec3>> history;    // previous steps' Δv per particle (mm/s),
                                             // newest first, ImplicitEulerOptions::
                                             // warm_start_history of them
  int warm_steps = 0;                        // consecutive implicit steps stored
  std::vector<std::vector<Vec3>> basis, abasis;   // projected warm start: orthonormal basis
                                                  // of the history and A·basis (solver order)
  std::int64_t warm_step = -2;               // World::step_count() at the last solve
  std::vector<Vec3> b, x, r, dir, q, s, t;  // CG work vectors (solver order)
  // SOR-preconditioned CG (sor_kernels.h layout): blocks row-major, vectors 4 doubles a row.
  std::vector<double> sor_blocks, sor_dinv;
  std::vector<double> x4, rho4, sigma4, p4, s4, g4, t4, q4;

  void invalidate() { valid = false; }
  /// Builds the pattern if needed.
  void ensure(const World& world);
  /// Refills values with K at the current positions.
  void assemble(const World& world);
};

}  // namespace ido::sim

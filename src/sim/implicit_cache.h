// SPDX-License-Identifier: Apache-2.0
// Private: the assembled block-sparse (BSR, 3×3 blocks) stiffness used by implicit Euler and
// the solver's work vectors. The pattern — free particles only: blocks on a fixed particle's
// row or column are dropped, since fixed particles do not move — is built once per (model
// set, particle count, fixed set); each step only refills the values, every model adding its
// blocks straight into their slots in a fixed order (deterministic whether threaded or not).
#pragma once

#include <cstdint>
#include <vector>

#include "ido/sim/world.h"

namespace ido::sim {

struct World::ImplicitCache {
  bool valid = false;
  std::size_t particle_count = 0;
  std::vector<std::uint8_t> fixed;           // fixed flags the pattern was built for
  std::vector<std::int32_t> row_offset;      // BSR rows = particles (fixed rows are empty)
  std::vector<std::int32_t> col;             // column particle of each slot, sorted per row
  std::vector<std::int32_t> diag_slot;       // slot of (i, i), −1 for a fixed particle
  std::vector<std::vector<std::int32_t>> model_slots;   // per model: slot of each pattern block
  std::vector<Mat3> values;                  // K per slot, N/mm
  std::vector<Mat3> precond;                 // per particle: inverse diagonal block of A
  std::vector<Vec3> warm_dv;                 // previous Δv, mm/s
  std::vector<Vec3> b, r, z, d, q, dv, kv;   // CG work vectors

  void invalidate() { valid = false; }
  /// Builds the pattern if needed.
  void ensure(const World& world);
  /// Refills values with K at the current positions.
  void assemble(const World& world);
};

}  // namespace ido::sim

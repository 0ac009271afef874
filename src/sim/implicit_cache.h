// SPDX-License-Identifier: Apache-2.0
// Private: the assembled block-sparse stiffness used by implicit Euler. The pattern is
// built once per (model set, particle count); values are refilled each step by summing
// every model block into its slot in a fixed order (deterministic in parallel).
#pragma once

#include <cstdint>
#include <vector>

#include "ido/sim/world.h"

namespace ido::sim {

struct World::ImplicitCache {
  bool valid = false;
  std::size_t particle_count = 0;
  std::vector<std::int32_t> row_offset;     // BSR rows = particles
  std::vector<std::int32_t> col;            // column particle of each slot
  std::vector<std::int32_t> diag_slot;      // slot of (i, i)
  std::vector<std::size_t> model_first;     // start of each model's blocks (all models)
  std::vector<Mat3> model_blocks;           // concatenated model blocks
  std::vector<std::int32_t> slot_offset;    // per slot: contributing blocks (CSR)
  std::vector<std::int32_t> slot_sources;
  std::vector<Mat3> values;                 // K per slot, N/mm
  std::vector<Vec3> warm_dv;                // previous Δv, mm/s

  void invalidate() { valid = false; }
  /// Builds the pattern if needed.
  void ensure(const World& world);
  /// Refills values with K at the current positions.
  void assemble(const World& world);
};

}  // namespace ido::sim

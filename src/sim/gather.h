// SPDX-License-Identifier: Apache-2.0
// Private helper: deterministic parallel accumulation. Elements write their per-corner
// contributions into their own slots; each particle then sums its slots in a fixed order.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/core/parallel.h"

namespace ido::sim::detail {

/// Builds a CSR (offsets, sources) listing, for every target t < n_targets, the slots s with
/// target_of_slot[s] == t in increasing order.
inline void build_gather(std::span<const std::int32_t> target_of_slot, std::size_t n_targets,
                         std::vector<std::int32_t>& offsets, std::vector<std::int32_t>& sources) {
  offsets.assign(n_targets + 1, 0);
  for (auto t : target_of_slot) ++offsets[static_cast<std::size_t>(t) + 1];
  for (std::size_t i = 0; i < n_targets; ++i) offsets[i + 1] += offsets[i];
  sources.resize(target_of_slot.size());
  std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
  for (std::size_t s = 0; s < target_of_slot.size(); ++s)
    sources[static_cast<std::size_t>(fill[static_cast<std::size_t>(target_of_slot[s])]++)] =
        static_cast<std::int32_t>(s);
}

/// out[t] += Σ slots of t, in parallel over targets (deterministic).
inline void gather_add(const std::vector<std::int32_t>& offsets,
                       const std::vector<std::int32_t>& sources, std::span<const Vec3> slots,
                       std::span<Vec3> out, bool threaded) {
  const std::size_t n = offsets.empty() ? 0 : offsets.size() - 1;
  parallel_for(
      n,
      [&](std::size_t t) {
        Vec3 sum = Vec3::Zero();
        for (auto k = offsets[t]; k < offsets[t + 1]; ++k)
          sum += slots[static_cast<std::size_t>(sources[static_cast<std::size_t>(k)])];
        out[t] += sum;
      },
      threaded, 1024);
}

/// Serial, order-fixed sum of per-item values.
inline double ordered_sum(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s;
}

}  // namespace ido::sim::detail

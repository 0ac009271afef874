// SPDX-License-Identifier: Apache-2.0
// Hand-written: Teschner et al. 2003 spatial hashing (the project's own collision broad phase).
#include "ido/geometry/spatial_hash.h"

#include <cmath>
#include <limits>
#include <string>

#include "ido/core/error.h"

namespace ido::geometry {

std::size_t SpatialHash::next_prime(std::size_t n) noexcept {
  if (n <= 2) return 2;
  for (std::size_t c = n | 1U;; c += 2) {
    bool prime = true;
    for (std::size_t d = 3; d * d <= c; d += 2) {
      if (c % d == 0) {
        prime = false;
        break;
      }
    }
    if (prime) return c;
  }
}

SpatialHash::SpatialHash(std::span<const Aabb> boxes, double cell_size_mm) {
  if (!(cell_size_mm > 0.0) || !std::isfinite(cell_size_mm)) {
    throw InvalidInput("spatial hash: cell size must be positive and finite");
  }
  m_cell = cell_size_mm;
  m_inv_cell = 1.0 / cell_size_mm;
  std::size_t entries = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const Aabb& b = boxes[i];
    if (!b.min.allFinite() || !b.max.allFinite()) {
      throw InvalidInput("spatial hash: box " + std::to_string(i) + " is not finite");
    }
    std::size_t cells = 1;
    for (int a = 0; a < 3; ++a) {
      cells *= static_cast<std::size_t>(cell_coordinate(b.max[a]) - cell_coordinate(b.min[a]) + 1);
    }
    entries += cells;
  }
  if (entries > std::numeric_limits<std::uint32_t>::max() / 2) {
    throw InvalidInput("spatial hash: cell size too small for the boxes (too many cell entries)");
  }
  const std::size_t n = next_prime(std::max<std::size_t>(2 * entries, 2));
  m_offsets.assign(n + 1, 0);
  auto for_cells = [&](const Aabb& b, auto&& f) {
    for (std::int64_t i = cell_coordinate(b.min.x()); i <= cell_coordinate(b.max.x()); ++i)
      for (std::int64_t j = cell_coordinate(b.min.y()); j <= cell_coordinate(b.max.y()); ++j)
        for (std::int64_t k = cell_coordinate(b.min.z()); k <= cell_coordinate(b.max.z()); ++k) {
          f(static_cast<std::size_t>(hash(i, j, k) % n));
        }
  };
  for (const Aabb& b : boxes) for_cells(b, [&](std::size_t bk) { ++m_offsets[bk + 1]; });
  for (std::size_t b = 0; b < n; ++b) m_offsets[b + 1] += m_offsets[b];
  m_items.assign(entries, -1);
  std::vector<std::uint32_t> fill(m_offsets.begin(), m_offsets.end() - 1);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    for_cells(boxes[i], [&](std::size_t bk) {
      // The same bucket may be hit twice by one item (two cells colliding); keep one entry.
      const std::uint32_t start = m_offsets[bk];
      if (fill[bk] > start && m_items[fill[bk] - 1] == static_cast<std::int32_t>(i)) return;
      m_items[fill[bk]++] = static_cast<std::int32_t>(i);
    });
  }
  // Compact away the slots left by skipped duplicates.
  std::size_t w = 0;
  std::vector<std::uint32_t> offsets(n + 1, 0);
  for (std::size_t b = 0; b < n; ++b) {
    offsets[b] = static_cast<std::uint32_t>(w);
    for (std::uint32_t e = m_offsets[b]; e < fill[b]; ++e) m_items[w++] = m_items[e];
  }
  offsets[n] = static_cast<std::uint32_t>(w);
  m_items.resize(w);
  m_items.shrink_to_fit();
  m_offsets = std::move(offsets);
}

}  // namespace ido::geometry

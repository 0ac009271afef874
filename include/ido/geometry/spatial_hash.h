// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/aabb.h"

namespace ido::geometry {

/// Static spatial hash of boxes after Teschner et al., "Optimized Spatial Hashing for
/// Collision Detection of Deformable Objects", VMV 2003: space is cut into cubic cells of
/// side cell_size_mm; integer cell coordinates (i, j, k) map to bucket
/// ((i·73856093) xor (j·19349663) xor (k·83492791)) mod n, with n a prime. Each item is
/// entered in every cell its box overlaps. Buckets are stored compactly (CSR), so a query
/// allocates nothing. Distinct cells may share a bucket: queries return candidates that
/// the caller must test exactly.
class SpatialHash {
 public:
  SpatialHash() = default;
  /// Builds the hash of @p boxes (item i = boxes[i]). @p cell_size_mm > 0; the table size
  /// is the smallest prime ≥ 2 × (number of cell entries).
  /// @throws ido::InvalidInput for a non-positive cell size or a non-finite box.
  SpatialHash(std::span<const Aabb> boxes, double cell_size_mm);

  /// Bucket index of the cell holding point @p p_mm.
  [[nodiscard]] std::size_t bucket_of(const Vec3& p_mm) const noexcept {
    return bucket(cell_coordinate(p_mm.x()), cell_coordinate(p_mm.y()), cell_coordinate(p_mm.z()));
  }
  /// Candidate items whose boxes may contain @p p_mm (possibly with false positives).
  [[nodiscard]] std::span<const std::int32_t> candidates(const Vec3& p_mm) const noexcept {
    if (m_offsets.empty()) return {};
    const std::size_t b = bucket_of(p_mm);
    return {m_items.data() + m_offsets[b], m_items.data() + m_offsets[b + 1]};
  }
  /// Calls f(item) for every item entered in a cell overlapping @p box; an item can be
  /// reported more than once. Allocates nothing.
  template <class F>
  void for_each_in_box(const Aabb& box, F&& f) const {
    if (m_offsets.empty()) return;
    const std::int64_t i0 = cell_coordinate(box.min.x()), i1 = cell_coordinate(box.max.x());
    const std::int64_t j0 = cell_coordinate(box.min.y()), j1 = cell_coordinate(box.max.y());
    const std::int64_t k0 = cell_coordinate(box.min.z()), k1 = cell_coordinate(box.max.z());
    for (std::int64_t i = i0; i <= i1; ++i)
      for (std::int64_t j = j0; j <= j1; ++j)
        for (std::int64_t k = k0; k <= k1; ++k) {
          const std::size_t b = bucket(i, j, k);
          for (std::size_t e = m_offsets[b]; e < m_offsets[b + 1]; ++e) f(m_items[e]);
        }
  }

  [[nodiscard]] double cell_size() const noexcept { return m_cell; }
  /// Number of buckets (a prime).
  [[nodiscard]] std::size_t table_size() const noexcept {
    return m_offsets.empty() ? 0 : m_offsets.size() - 1;
  }
  /// Memory held by the table (bytes).
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return m_offsets.capacity() * sizeof(std::uint32_t) + m_items.capacity() * sizeof(std::int32_t);
  }

  /// Teschner et al.'s hash of integer cell coordinates, before the modulo.
  [[nodiscard]] static std::uint64_t hash(std::int64_t i, std::int64_t j, std::int64_t k) noexcept {
    return (static_cast<std::uint64_t>(i) * 73856093ULL) ^ (static_cast<std::uint64_t>(j) * 19349663ULL) ^
           (static_cast<std::uint64_t>(k) * 83492791ULL);
  }
  /// Smallest prime ≥ n (n ≥ 2).
  [[nodiscard]] static std::size_t next_prime(std::size_t n) noexcept;

 private:
  [[nodiscard]] std::int64_t cell_coordinate(double x) const noexcept {
    return static_cast<std::int64_t>(std::floor(x * m_inv_cell));
  }
  [[nodiscard]] std::size_t bucket(std::int64_t i, std::int64_t j, std::int64_t k) const noexcept {
    return static_cast<std::size_t>(hash(i, j, k) % (m_offsets.size() - 1));
  }

  double m_cell = 1.0;
  double m_inv_cell = 1.0;
  std::vector<std::uint32_t> m_offsets;  // bucket b holds m_items[m_offsets[b] .. m_offsets[b+1])
  std::vector<std::int32_t> m_items;
};

}  // namespace ido::geometry

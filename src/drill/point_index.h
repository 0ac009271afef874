// SPDX-License-Identifier: Apache-2.0
// Private to the drill module: compact storage for welding points of the hierarchy by their
// exact keys (the boundary surface's assembly, the leaf mesh's walk). Flat, open-addressing
// tables instead of node-based maps: a node-based map entry costs about 70 bytes and an
// allocation, which at refinement depth 8 (a million surface vertices) was most of the time
// and a large part of the memory of writing the outputs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "ido/drill/boundary_surface.h"

namespace ido::drill::detail {

/// Returns the heap's free pages to the system (glibc; elsewhere nothing to do). For the
/// places that free large structures piece by piece while building others (the v_lists as
/// they are taken over or consumed): the freed pieces are spread over the heap and often too
/// small for what is built next, so without it what is built comes on top of them. ido's heap
/// policy keeps freed memory otherwise (ido/core/memory.h).
inline void return_free_pages() noexcept {
#if defined(__GLIBC__)
  ::malloc_trim(0);
#endif
}

/// Calls return_free_pages() once about @p every_bytes were freed (as reported by freed()).
class FreedPages {
 public:
  explicit FreedPages(std::size_t every_bytes = std::size_t(4) << 20) : m_every(every_bytes) {}
  void freed(std::size_t bytes) noexcept {
    m_freed += bytes;
    if (m_freed >= m_every) {
      return_free_pages();
      m_freed = 0;
    }
  }

 private:
  std::size_t m_every;
  std::size_t m_freed = 0;
};

/// Hash of a point key: splitmix64's finaliser over the packed (id, weight) pairs.
inline std::uint64_t hash_key(const PointKey& k) noexcept {
  auto mix = [](std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
  };
  std::uint64_t h = 0;
  for (std::size_t i = 0; i < 4; ++i)
    h = mix(h ^ ((static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.id[i])) << 32) |
                 static_cast<std::uint32_t>(k.weight[i])));
  return h;
}

/// A point key in 24 bytes (32 unpacked): the four ids and the first three weights, 12 bits
/// each (a weight is at most kBaryScale = 2^11); the fourth weight is kBaryScale less the
/// others, which is also right for keys of fewer than four points (unused weights are 0).
struct PackedKey {
  std::array<std::int32_t, 4> id{-1, -1, -1, -1};
  std::uint64_t weights = 0;

  static PackedKey pack(const PointKey& k) noexcept {
    PackedKey p;
    p.id = k.id;
    p.weights = static_cast<std::uint64_t>(k.weight[0]) | (static_cast<std::uint64_t>(k.weight[1]) << 12) |
                (static_cast<std::uint64_t>(k.weight[2]) << 24);
    return p;
  }
  [[nodiscard]] PointKey unpack() const noexcept {
    PointKey k;
    k.id = id;
    k.weight[0] = static_cast<std::int32_t>(weights & 0xFFF);
    k.weight[1] = static_cast<std::int32_t>((weights >> 12) & 0xFFF);
    k.weight[2] = static_cast<std::int32_t>((weights >> 24) & 0xFFF);
    k.weight[3] = kBaryScale - k.weight[0] - k.weight[1] - k.weight[2];
    return k;
  }
  friend bool operator==(const PackedKey&, const PackedKey&) = default;
};
static_assert(sizeof(PackedKey) == 24);
static_assert(kBaryScale < (1 << 12), "a packed weight has 12 bits");

/// An array grown in fixed blocks of 2^kShift elements: no doubling slack and no copy when it
/// grows (so a large array never exists twice), and blocks before a position can be freed
/// once they are consumed. T is trivially copyable.
template <class T, unsigned kShift = 12>
class BlockArray {
 public:
  static constexpr std::size_t kBlock = std::size_t(1) << kShift;

  [[nodiscard]] std::size_t size() const noexcept { return m_size; }
  void push_back(const T& v) {
    if ((m_size >> kShift) == m_blocks.size()) m_blocks.emplace_back(new T[kBlock]);
    m_blocks[m_size >> kShift][m_size & (kBlock - 1)] = v;
    ++m_size;
  }
  [[nodiscard]] T& operator[](std::size_t i) noexcept { return m_blocks[i >> kShift][i & (kBlock - 1)]; }
  [[nodiscard]] const T& operator[](std::size_t i) const noexcept { return m_blocks[i >> kShift][i & (kBlock - 1)]; }
  /// Frees the blocks that hold only elements before @p i (they must not be read again).
  void release_before(std::size_t i) noexcept {
    for (std::size_t b = 0; b < (i >> kShift) && b < m_blocks.size(); ++b) m_blocks[b].reset();
  }
  /// Frees everything.
  void clear() noexcept {
    std::vector<std::unique_ptr<T[]>>().swap(m_blocks);
    m_size = 0;
  }
  /// Bytes allocated (blocks still held and the block table).
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    std::size_t held = 0;
    for (const auto& b : m_blocks) held += b ? kBlock * sizeof(T) : 0U;
    return held + m_blocks.capacity() * sizeof(void*);
  }

 private:
  std::vector<std::unique_ptr<T[]>> m_blocks;
  std::size_t m_size = 0;
};

/// Numbers point keys in order of first insertion and finds them again: the keys in a
/// BlockArray (24 bytes each, so a number gives its key back) and an open-addressing table of
/// (hash tag, number) slots, 8 bytes each, at most 0.7 full. A look-up compares a key only
/// where the tag matches, so a miss rarely reads the key array.
class PointIndex {
 public:
  /// Sized for about @p expected keys without growing.
  explicit PointIndex(std::size_t expected = 0) { rehash(capacity_for(expected)); }

  [[nodiscard]] std::size_t size() const noexcept { return m_keys.size(); }
  /// The number of @p k, numbering it next if it is new.
  std::int32_t insert(const PointKey& k) {
    const std::uint64_t h = hash_key(k);
    const PackedKey p = PackedKey::pack(k);
    std::size_t s = h & m_mask;
    const auto tag = static_cast<std::uint32_t>(h >> 32);
    for (;; s = (s + 1) & m_mask) {
      const std::uint64_t slot = m_slots[s];
      if (slot == 0) break;
      if (static_cast<std::uint32_t>(slot >> 32) == tag) {
        const auto i = static_cast<std::uint32_t>(slot) - 1U;
        if (m_keys[i] == p) return static_cast<std::int32_t>(i);
      }
    }
    const auto i = static_cast<std::uint32_t>(m_keys.size());
    m_keys.push_back(p);
    m_slots[s] = (static_cast<std::uint64_t>(tag) << 32) | (i + 1U);
    if (10 * m_keys.size() > 7 * (m_mask + 1)) rehash(2 * (m_mask + 1));
    return static_cast<std::int32_t>(i);
  }
  /// The number of @p k, or −1.
  [[nodiscard]] std::int32_t find(const PointKey& k) const noexcept {
    if (m_slots.empty()) return -1;
    const std::uint64_t h = hash_key(k);
    const auto tag = static_cast<std::uint32_t>(h >> 32);
    PackedKey p;
    bool packed = false;
    for (std::size_t s = h & m_mask;; s = (s + 1) & m_mask) {
      const std::uint64_t slot = m_slots[s];
      if (slot == 0) return -1;
      if (static_cast<std::uint32_t>(slot >> 32) == tag) {
        if (!packed) {
          p = PackedKey::pack(k);
          packed = true;
        }
        const auto i = static_cast<std::uint32_t>(slot) - 1U;
        if (m_keys[i] == p) return static_cast<std::int32_t>(i);
      }
    }
  }
  /// The key numbered @p i.
  [[nodiscard]] PointKey key(std::size_t i) const noexcept { return m_keys[i].unpack(); }
  /// Frees the look-up table (find() and insert() are not called again); the keys stay.
  void release_table() noexcept {
    std::vector<std::uint64_t>().swap(m_slots);
    m_mask = 0;
  }
  /// Frees everything.
  void clear() noexcept {
    release_table();
    m_keys.clear();
  }
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return m_keys.memory_bytes() + m_slots.capacity() * sizeof(std::uint64_t);
  }

 private:
  static std::size_t capacity_for(std::size_t n) noexcept {
    std::size_t c = 64;
    while (7 * c < 10 * n) c *= 2;
    return c;
  }
  void rehash(std::size_t capacity) {
    std::vector<std::uint64_t> slots(capacity, 0);
    const std::size_t mask = capacity - 1;
    for (const std::uint64_t slot : m_slots) {
      if (slot == 0) continue;
      // The slot's position comes from the low bits of the hash, which the slot does not
      // keep: hash the key again.
      const std::uint64_t h = hash_key(m_keys[static_cast<std::uint32_t>(slot) - 1U].unpack());
      std::size_t s = h & mask;
      while (slots[s] != 0) s = (s + 1) & mask;
      slots[s] = slot;
    }
    m_slots = std::move(slots);
    m_mask = mask;
  }

  BlockArray<PackedKey> m_keys;
  std::vector<std::uint64_t> m_slots;  // 0: empty; else (tag << 32) | (number + 1)
  std::size_t m_mask = 0;
};

/// A map from point keys to numbers that is emptied often (a root's inner points): open
/// addressing with the keys in the slots, and a list of the slots used, so that emptying it
/// costs what was put in, not its capacity.
class PointMap {
 public:
  /// The number of @p k, or @p next (then stored for @p k) if it is not there.
  std::int32_t try_emplace(const PointKey& k, std::int32_t next) {
    if (2 * (m_used.size() + 1) > m_slots.size()) grow();
    std::size_t s = hash_key(k) & (m_slots.size() - 1);
    for (;; s = (s + 1) & (m_slots.size() - 1)) {
      Slot& slot = m_slots[s];
      if (slot.value < 0) {
        slot = {k, next};
        m_used.push_back(static_cast<std::uint32_t>(s));
        return next;
      }
      if (slot.key == k) return slot.value;
    }
  }
  /// The number of @p k, or −1.
  [[nodiscard]] std::int32_t find(const PointKey& k) const noexcept {
    if (m_slots.empty()) return -1;
    for (std::size_t s = hash_key(k) & (m_slots.size() - 1);; s = (s + 1) & (m_slots.size() - 1)) {
      const Slot& slot = m_slots[s];
      if (slot.value < 0) return -1;
      if (slot.key == k) return slot.value;
    }
  }
  [[nodiscard]] std::size_t size() const noexcept { return m_used.size(); }
  /// Empties the map, keeping its capacity.
  void clear() noexcept {
    for (const auto s : m_used) m_slots[s].value = -1;
    m_used.clear();
  }
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return m_slots.capacity() * sizeof(Slot) + m_used.capacity() * sizeof(std::uint32_t);
  }

 private:
  struct Slot {
    PointKey key;
    std::int32_t value = -1;  // −1: empty
  };
  void grow() {
    std::vector<Slot> old = std::move(m_slots);
    m_slots.assign(old.empty() ? 64 : 2 * old.size(), Slot{});
    m_used.clear();
    for (const auto& slot : old)
      if (slot.value >= 0) {
        std::size_t s = hash_key(slot.key) & (m_slots.size() - 1);
        while (m_slots[s].value >= 0) s = (s + 1) & (m_slots.size() - 1);
        m_slots[s] = slot;
        m_used.push_back(static_cast<std::uint32_t>(s));
      }
  }
  std::vector<Slot> m_slots;
  std::vector<std::uint32_t> m_used;
};

}  // namespace ido::drill::detail

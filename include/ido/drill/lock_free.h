// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>

namespace ido::drill {

/// Single-writer / single-reader triple buffer: the writer never waits, the reader always
/// gets the latest complete value. Wait-free, no allocation after construction. T must be
/// copyable. Hand-written (a standard construction).
template <class T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) { m_slot.fill(initial); }

  /// Writer: publishes @p value.
  void write(const T& value) noexcept {
    m_slot[m_back] = value;
    const std::uint8_t prev = m_middle.exchange(static_cast<std::uint8_t>(m_back | kDirty), std::memory_order_acq_rel);
    m_back = prev & kIndex;
  }
  /// Reader: the latest published value (the same as last time if nothing new).
  const T& read() noexcept {
    if (m_middle.load(std::memory_order_relaxed) & kDirty) {
      const std::uint8_t prev = m_middle.exchange(m_front, std::memory_order_acq_rel);
      m_front = prev & kIndex;
    }
    return m_slot[m_front];
  }
  /// Reader: true when a value newer than the last read() is waiting.
  [[nodiscard]] bool has_new() const noexcept { return (m_middle.load(std::memory_order_acquire) & kDirty) != 0; }

 private:
  static constexpr std::uint8_t kDirty = 4;
  static constexpr std::uint8_t kIndex = 3;
  std::array<T, 3> m_slot{};
  std::uint8_t m_back = 0;                 // writer's slot
  std::atomic<std::uint8_t> m_middle{1};   // shared slot index | dirty bit
  std::uint8_t m_front = 2;                // reader's slot
};

/// Bounded single-producer / single-consumer ring (lock-free; push and pop never block).
template <class T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "capacity must be a power of two");

 public:
  /// Producer: false (and @p value untouched) when full.
  bool push(T& value) noexcept {
    const std::size_t head = m_head.load(std::memory_order_relaxed);
    if (head - m_tail.load(std::memory_order_acquire) >= N) return false;
    m_items[head & (N - 1)] = std::move(value);
    m_head.store(head + 1, std::memory_order_release);
    return true;
  }
  /// Consumer: the oldest item, if any.
  std::optional<T> pop() noexcept {
    const std::size_t tail = m_tail.load(std::memory_order_relaxed);
    if (m_head.load(std::memory_order_acquire) == tail) return std::nullopt;
    std::optional<T> v(std::move(m_items[tail & (N - 1)]));
    m_tail.store(tail + 1, std::memory_order_release);
    return v;
  }

 private:
  std::array<T, N> m_items{};
  alignas(64) std::atomic<std::size_t> m_head{0};
  alignas(64) std::atomic<std::size_t> m_tail{0};
};

}  // namespace ido::drill

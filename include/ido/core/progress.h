// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <string_view>

namespace ido {

/// Progress reporting and cancellation for long operations. The library calls update()
/// now and then and throws ido::Cancelled at the next check once cancel() was called
/// (from any thread). Operations take a `Progress*` that may be null.
class Progress {
 public:
  /// Called with a fraction in [0, 1] and the current stage's name.
  using Callback = std::function<void(double fraction, std::string_view stage)>;

  Progress() = default;
  explicit Progress(Callback callback) : m_callback(std::move(callback)) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Reports progress and throws ido::Cancelled if cancellation was requested.
  void update(double fraction, std::string_view stage);
  /// Requests cancellation; thread-safe.
  void cancel() noexcept { m_cancelled.store(true, std::memory_order_relaxed); }
  [[nodiscard]] bool cancelled() const noexcept {
    return m_cancelled.load(std::memory_order_relaxed);
  }
  /// Throws ido::Cancelled if cancellation was requested.
  void check() const;

 private:
  Callback m_callback;
  std::atomic<bool> m_cancelled{false};
};

/// Null-safe helpers for the optional Progress* parameter of long operations.
inline void report(Progress* p, double fraction, std::string_view stage) {
  if (p) p->update(fraction, stage);
}
inline void check_cancel(const Progress* p) {
  if (p) p->check();
}

}  // namespace ido

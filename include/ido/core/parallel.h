// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace ido {

/// Calls body(begin, end) over disjoint sub-ranges covering [0, n), in parallel with oneTBB
/// when @p threaded is true, else serially in one call. Halved while longer than @p grain.
template <class Body>
void parallel_for_ranges(std::size_t n, Body&& body, bool threaded = true,
                         std::size_t grain = 256) {
  if (n == 0) return;
#if defined(__SANITIZE_THREAD__)
  // ThreadSanitizer cannot see the happens-before edges of oneTBB's scheduler (Debian's libtbb
  // is not instrumented): every task's write read after the loop, and the reuse of the task
  // objects' stack memory, were reported as races. Under TSan the data-parallel loops run
  // serially, so TSan checks the project's own threads (drilling threads, lock-free hand-offs,
  // concurrent worlds); the loops' threaded results are checked against serial ones by the
  // determinism tests instead.
  threaded = false;
#endif
  if (!threaded || n <= grain) {
    body(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

/// Calls body(i) for every i in [0, n), in parallel when @p threaded.
template <class Body>
void parallel_for(std::size_t n, Body&& body, bool threaded = true, std::size_t grain = 256) {
  parallel_for_ranges(
      n,
      [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) body(i);
      },
      threaded, grain);
}

}  // namespace ido

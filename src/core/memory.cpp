// SPDX-License-Identifier: Apache-2.0
// The process heap policy of ido/core/memory.h. Only glibc's documented mallopt parameters
// and the kernel's madvise are used; nothing of the allocator is replaced.
#include "ido/core/memory.h"

#include <atomic>
#include <cstdint>
#include <cstdlib>

#if defined(__linux__) && defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#define IDO_GLIBC_HEAP 1
#endif

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#undef IDO_GLIBC_HEAP
#endif
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#undef IDO_GLIBC_HEAP
#endif
#endif

namespace ido {

namespace {
// Set by use_huge_page_heap: a library's buffers follow the policy only in a program that chose it.
std::atomic<bool> g_advise{false};

#ifdef IDO_GLIBC_HEAP
// Advises the 2 MiB-aligned interior of [begin, end) for transparent huge pages; returns the
// bytes advised (0 when the interior is empty or madvise refuses).
std::size_t advise_interior(std::uintptr_t begin, std::uintptr_t end) {
  constexpr std::uintptr_t huge = std::uintptr_t(2) << 20;
  const std::uintptr_t lo = (begin + huge - 1) & ~(huge - 1);
  const std::uintptr_t hi = end & ~(huge - 1);
  if (hi <= lo || madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE) != 0) return 0;
  return hi - lo;
}
#endif
}  // namespace

HeapPolicy use_huge_page_heap(std::size_t reserve_bytes) {
  HeapPolicy out;
#ifdef IDO_GLIBC_HEAP
  // glibc refuses a mapping threshold above 32 MiB on 64-bit systems (half its arena heap size).
  if (mallopt(M_MMAP_THRESHOLD, 32 << 20) != 1) return out;
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  // The next extension of the main heap asks for reserve_bytes more than it needs: provoke it
  // with a small block, then advise the whole extension. Address space only: untouched pages
  // cost no memory.
  mallopt(M_TOP_PAD, static_cast<int>(reserve_bytes));
  const auto* before = static_cast<const char*>(sbrk(0));
  void* probe = std::malloc(std::size_t(1) << 20);
  const auto* after = static_cast<const char*>(sbrk(0));
  mallopt(M_TOP_PAD, 128 << 10);  // glibc's default again for later growth
  if (probe != nullptr && after > before)
    out.huge_bytes = advise_interior(reinterpret_cast<std::uintptr_t>(before), reinterpret_cast<std::uintptr_t>(after));
  std::free(probe);
  out.applied = true;
  g_advise.store(true, std::memory_order_relaxed);
#else
  (void)reserve_bytes;
#endif
  return out;
}

void advise_huge_pages(void* data, std::size_t bytes) noexcept {
#ifdef IDO_GLIBC_HEAP
  if (data == nullptr || bytes < (std::size_t(4) << 20) || !g_advise.load(std::memory_order_relaxed)) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  (void)advise_interior(begin, begin + bytes);
#else
  (void)data;
  (void)bytes;
#endif
}

}  // namespace ido

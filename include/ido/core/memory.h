// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstddef>

namespace ido {

/// What use_huge_page_heap did.
struct HeapPolicy {
  bool applied = false;           ///< false where unsupported (not glibc on Linux, sanitizers)
  std::size_t huge_bytes = 0;     ///< heap range advised for transparent huge pages
};

/// Makes the process heap cheap to fill with large buffers. Volumes, distance grids and
/// meshes of tens of megabytes are written once into fresh memory, and on a virtual machine
/// every 4 KiB page's first touch is a fault of about 10 µs (a new 21 MB volume: 60 ms).
/// This (1) serves allocations up to 32 MiB from the heap rather than fresh mappings, and
/// keeps freed heap memory for reuse instead of returning it; (2) grows the heap once by
/// @p reserve_bytes of address space (no memory is touched) and advises the kernel to back
/// it with transparent huge pages, so a first touch maps 2 MiB at once where the system
/// allows it (THP mode "madvise" or "always"). Meant for a program's main() before its
/// work starts (the `ido` CLI, benchmarks), not for a library. Safe to call more than once.
/// glibc on Linux only; a no-op under AddressSanitizer / ThreadSanitizer, whose
/// allocators replace glibc's.
HeapPolicy use_huge_page_heap(std::size_t reserve_bytes = std::size_t(512) << 20);

}  // namespace ido

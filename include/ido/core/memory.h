// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <cstddef>
#include <vector>

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

/// Advises the kernel to back a buffer that is about to be written for the first time with
/// transparent huge pages (its 2 MiB-aligned interior; buffers under 4 MiB are left alone).
/// For blocks above use_huge_page_heap's 32 MiB, which glibc maps afresh for each allocation
/// (a 512 × 512 × 300 float volume: 76 800 faults of 4 KiB, against 150 of 2 MiB). Does
/// nothing until the program has called use_huge_page_heap (a library's buffers follow the
/// program's choice), where transparent huge pages are unsupported, and under the
/// sanitizers; never fails.
void advise_huge_pages(void* data, std::size_t bytes) noexcept;

/// Reserves room for @p n elements in an empty @p v and advises that block
/// (advise_huge_pages) before anything is written to it: fill it next (`assign`, `resize`,
/// `insert`) without growing past @p n. For the large buffers written once: a volume's voxels,
/// a reader's decoded slices.
template <class T>
void reserve_advised(std::vector<T>& v, std::size_t n) {
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
}

}  // namespace ido

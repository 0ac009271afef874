// SPDX-License-Identifier: Apache-2.0
// ido::use_huge_page_heap changes this process's allocator settings, so it has its own test
// executable.
#include "ido/core/memory.h"

#include <sys/resource.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include <vector>

#include <gtest/gtest.h>

namespace ido {
namespace {

long minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

// Page faults taken while writing every byte of a fresh @p bytes block.
long faults_to_fill(std::size_t bytes, char value) {
  const long before = minor_faults();
  auto block = std::unique_ptr<char[]>(new char[bytes]);
  std::memset(block.get(), value, bytes);
  volatile char keep = block[bytes / 2];
  (void)keep;
  return minor_faults() - before;
}

// The kernel's transparent-huge-page mode line ("always [madvise] never"), empty if unknown.
std::string thp_mode() {
  std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
  return {std::istreambuf_iterator<char>(thp), std::istreambuf_iterator<char>()};
}

constexpr bool kGlibcLinux =
#if defined(__linux__) && defined(__GLIBC__)
    true;
#else
    false;
#endif

bool sanitized() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return true;
#else
  return false;
#endif
}

TEST(HugePageHeap, ReusesFreedBuffersAndMapsFreshOnesInHugePages) {
  const HeapPolicy p = use_huge_page_heap(std::size_t(256) << 20);
  if (sanitized()) {
    EXPECT_FALSE(p.applied);  // the sanitizers' allocators are left alone
    return;
  }
  if (!kGlibcLinux) GTEST_SKIP() << "glibc on Linux only";
  ASSERT_TRUE(p.applied);
  constexpr std::size_t bytes = std::size_t(21) << 20;  // a 512 × 512 × 20 float volume
  constexpr long pages = long(bytes / 4096);
  (void)faults_to_fill(bytes, 1);
  // Freed memory stays in the heap: filling a block of the same size again faults on
  // (almost) no page. Without the policy glibc maps such a block afresh and faults on all.
  EXPECT_LT(faults_to_fill(bytes, 2), pages / 20);
  if (p.huge_bytes == 0 || thp_mode().find("[never]") != std::string::npos) return;
  EXPECT_GE(p.huge_bytes, std::size_t(200) << 20);
  // A larger block (still below the 32 MiB mapping threshold) reuses the freed 21 MiB and
  // extends into fresh heap, which lies in the advised range: 2 MiB per fault where the
  // kernel has huge pages to give. With 4 KiB pages the fresh 9 MiB alone are 2 304 faults.
  constexpr std::size_t larger = std::size_t(30) << 20;
  EXPECT_LT(faults_to_fill(larger, 3), long(larger / 4096) / 4);
}

TEST(HugePageHeap, AdvisedLargeBlocksFaultPerHugePage) {
  if (sanitized() || !kGlibcLinux) GTEST_SKIP() << "glibc on Linux without sanitizers only";
  ASSERT_TRUE(use_huge_page_heap(std::size_t(64) << 20).applied);
  if (thp_mode().find("[never]") != std::string::npos) GTEST_SKIP() << "transparent huge pages are off";
  // Above the heap's 32 MiB glibc maps each block afresh: 16 384 faults of 4 KiB for 64 MiB.
  constexpr std::size_t bytes = std::size_t(64) << 20;
  auto block = std::unique_ptr<char[]>(new char[bytes]);
  const long before = minor_faults();
  advise_huge_pages(block.get(), bytes);
  std::memset(block.get(), 5, bytes);
  const long faults = minor_faults() - before;
  EXPECT_EQ(block[bytes - 1], 5);
  EXPECT_LT(faults, long(bytes / 4096) / 4);
  advise_huge_pages(nullptr, bytes);       // ignored
  advise_huge_pages(block.get(), 100);     // too small: ignored
}

// reserve_advised: the vector's own block, above the heap's 32 MiB, advised before it is
// filled (as Volume and the readers fill theirs): fewer than a quarter of its 4 KiB pages fault.
TEST(HugePageHeap, ReserveAdvisedVectorFaultsPerHugePage) {
  constexpr std::size_t n = std::size_t(16) << 20;  // 64 MiB of floats
  std::vector<float> v;
  reserve_advised(v, n);
  EXPECT_TRUE(v.empty());
  EXPECT_GE(v.capacity(), n);
  if (sanitized() || !kGlibcLinux) GTEST_SKIP() << "glibc on Linux without sanitizers only";
  ASSERT_TRUE(use_huge_page_heap(std::size_t(64) << 20).applied);
  if (thp_mode().find("[never]") != std::string::npos) GTEST_SKIP() << "transparent huge pages are off";
  std::vector<float> w;
  const long before = minor_faults();
  reserve_advised(w, n);
  w.assign(n, 2.0f);
  const long faults = minor_faults() - before;
  EXPECT_EQ(w[n - 1], 2.0f);
  EXPECT_LT(faults, long(n * sizeof(float) / 4096) / 4);
}

TEST(HugePageHeap, SecondCallIsHarmless) {
  (void)use_huge_page_heap(std::size_t(64) << 20);
  const HeapPolicy p = use_huge_page_heap(std::size_t(64) << 20);
  EXPECT_EQ(p.applied, !sanitized() && kGlibcLinux);
  auto block = std::unique_ptr<char[]>(new char[std::size_t(8) << 20]);
  std::memset(block.get(), 7, std::size_t(8) << 20);
  EXPECT_EQ(block[12345], 7);
}

}  // namespace
}  // namespace ido

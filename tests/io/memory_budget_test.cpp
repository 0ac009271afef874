// SPDX-License-Identifier: Apache-2.0
// The memory budget: declared sizes over it are refused before allocation, naming the file,
// the need and the limit; sizes parse and print in binary units.
#include "ido/io/memory_budget.h"

#include <fstream>

#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "support/test_support.h"

namespace ido::io {
namespace {

/// Sets the budget for one test and restores the default after it.
struct BudgetGuard {
  explicit BudgetGuard(std::uint64_t bytes) { set_memory_limit_bytes(bytes); }
  ~BudgetGuard() { set_memory_limit_bytes(0); }
};

TEST(MemoryBudget, DefaultIsAPositiveFractionOfMemory) {
  EXPECT_GT(default_memory_limit_bytes(), std::uint64_t(64) << 20);
  EXPECT_EQ(memory_limit_bytes(), default_memory_limit_bytes());
  const BudgetGuard g(12345);
  EXPECT_EQ(memory_limit_bytes(), 12345u);
}

TEST(MemoryBudget, SizesParseAndPrintInBinaryUnits) {
  EXPECT_EQ(parse_memory_size("12G", "--memory-limit"), std::uint64_t(12) << 30);
  EXPECT_EQ(parse_memory_size("512MiB", "x"), std::uint64_t(512) << 20);
  EXPECT_EQ(parse_memory_size("1.5k", "x"), 1536u);
  EXPECT_EQ(parse_memory_size("4096", "x"), 4096u);
  for (const char* bad : {"", "0", "-1G", "12X", "1e30T", "nan", "G"})
    EXPECT_THROW((void)parse_memory_size(bad, "--memory-limit"), InvalidInput) << bad;
  EXPECT_EQ(format_bytes(512), "512 B");
  EXPECT_EQ(format_bytes(std::uint64_t(12) << 30), "12 GiB");
  EXPECT_EQ(saturating_product({std::uint64_t(1) << 40, std::uint64_t(1) << 30}), UINT64_MAX);
  EXPECT_EQ(saturating_product({32767, 32767, 32767, 4}), 140724603846652ull);
}

TEST(MemoryBudget, MeshFileOverTheBudgetIsRefusedNamingNeedAndLimit) {
  const auto dir = test::scratch_dir("memory-budget-mesh");
  std::ofstream(dir / "t.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n" << std::string(3000, '#') << "\n";
  const BudgetGuard g(2048);
  try {
    (void)read_triangle_mesh(dir / "t.obj");
    FAIL() << "read past the budget";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("t.obj: the file's 3033 bytes need 2.96 KiB, over the memory limit of 2 KiB"),
              std::string::npos)
        << e.what();
  }
}

TEST(MemoryBudget, VolumeHeaderOverTheBudgetIsRefusedBeforeReading) {
  const auto dir = test::scratch_dir("memory-budget-volume");
  image::Volume<float> v(Index3{20, 10, 5}, Vec3(1, 1, 1));
  write_volume(dir / "v.nrrd", v);
  write_volume(dir / "v.nii.gz", v);
  {
    const BudgetGuard g(3000);  // 1000 float voxels need 4000 bytes
    for (const char* name : {"v.nrrd", "v.nii.gz"}) {
      try {
        (void)read_volume(dir / name);
        FAIL() << name << " read past the budget";
      } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("20×10×5 voxels need 3.91 KiB, over the memory limit of 2.93 KiB"),
                  std::string::npos)
            << e.what();
      }
    }
  }
  EXPECT_EQ(read_volume(dir / "v.nrrd").voxel_count(), 1000u);
}

}  // namespace
}  // namespace ido::io

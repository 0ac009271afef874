// SPDX-License-Identifier: Apache-2.0
// Whole-process peer of `ido drill` on the benchmark trace (issue 30): the trace of
// drill_trace.h as a path CSV for `ido drill`, and OpenVDB voxel drilling of the same block
// on the same trace as a process of its own, so that the two processes' peak memory (and
// time) can be compared from outside (/usr/bin/time -v; bench/results/drill.md).
//
//   bench_drill_vdb_process --trace PATH.csv    writes the trace: t,x,y,z (s, mm), 1 ms apart
//   bench_drill_vdb_process DEPTH               OpenVDB voxel drilling at the voxel edge of DEPTH
//
// The drilling is run_openvdb_trace's (drill_update_bench.cpp): per pose, the 1000 burr
// samples looked up in the grid (collision) and the voxels in each sub-step sphere switched
// off (removal), single-threaded. It makes no surface and writes nothing: the yardstick the
// issue names. It prints one line: the voxel edge, the grid's memUsage() after the trace, the
// voxels switched off and the process's peak RSS (getrusage).
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "ido/drill/tool.h"
#include "drill_trace.h"

#ifdef IDO_BENCH_OPENVDB
#include <tbb/global_control.h>
#endif

namespace {

using namespace ido;
using namespace ido::drill;
using namespace ido::drill::bench;

int write_trace(const char* path) {
  std::FILE* f = std::fopen(path, "w");
  if (f == nullptr) {
    std::fprintf(stderr, "%s: cannot be written\n", path);
    return 2;
  }
  std::fprintf(f, "t,x,y,z\n");
  for (int i = 0; i < kUpdates; ++i) {
    const Vec3 p = trace(i);
    std::fprintf(f, "%.17g,%.17g,%.17g,%.17g\n", i * 1e-3, p.x(), p.y(), p.z());
  }
  return std::fclose(f) == 0 ? 0 : 2;
}

#ifdef IDO_BENCH_OPENVDB
int drill_voxels(int depth) {
  openvdb::initialize();
  const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const double h = voxel_edge(depth);
  auto grid = make_block_grid(h);
  const Tool tool({.burr_radius_mm = kRadius, .sample_count = 1000});
  auto acc = grid->getAccessor();
  long inside = 0, removed = 0;
  Vec3 last = trace(0);
  for (int i = 0; i < kUpdates; ++i) {
    const Vec3 c = trace(i);
    inside += samples_inside(acc, tool, c, h);
    const int n = substep_count(last, c);
    for (int k = 1; k <= n; ++k)
      switch_off_sphere(acc, last + (c - last) * (double(k) / n), h,
                        [&](const openvdb::Coord&) { ++removed; });
    last = c;
  }
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  std::printf("depth %d voxel_mm %.6g memUsage_kB %.1f voxels_removed %ld samples_inside %ld peak_rss_MiB %.1f\n",
              depth, h, static_cast<double>(grid->memUsage()) / 1024.0, removed, inside,
              static_cast<double>(u.ru_maxrss) / 1024.0);
  return 0;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  const std::string a = argc > 1 ? argv[1] : "";
  if (a == "--trace" && argc == 3) return write_trace(argv[2]);
#ifdef IDO_BENCH_OPENVDB
  if (argc == 2 && !a.empty() && a.find_first_not_of("0123456789") == std::string::npos)
    return drill_voxels(std::atoi(argv[1]));
  std::fprintf(stderr, "usage: %s --trace PATH.csv | DEPTH\n", argv[0]);
#else
  std::fprintf(stderr, "usage: %s --trace PATH.csv (built without OpenVDB: no DEPTH)\n", argv[0]);
#endif
  return 2;
}

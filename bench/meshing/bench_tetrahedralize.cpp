// SPDX-License-Identifier: Apache-2.0
// Tetrahedral meshing of a sphere and a torus: ido's isosurface stuffing (uniform and
// graded lattice) against TetGen
// (the `tetgen` Debian program, run as a separate process on the same surfaces; its AGPL
// code is never linked). Speed in tetrahedra per second, then a quality table.
//
//   build/bench/bench/meshing/bench_tetrahedralize --benchmark_repetitions=3 \
//       --benchmark_report_aggregates_only=true [--quality_table]
//
// The distance field is sampled once outside the timed region (0.25 mm voxels); the
// stuffing lattice spacing is 0.8 mm. TetGen gets a closed triangulation of the same
// surface (icosphere / torus, edges 0.6–0.8 mm) and runs with -pq1.414a<V>Q, V being twice
// the mean volume of ido's tetrahedra on that shape, so both produce meshes of comparable
// size. Times are CPU seconds (process CPU for ido, summed over its threads; the child's
// user + system for TetGen, which includes its start-up and its file output).
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ido/core/atomic_file.h"
#include "ido/geometry/primitives.h"
#include "ido/geometry/tet_quality.h"
#include "ido/meshing/tetrahedralize.h"

namespace {

using namespace ido;

constexpr double kEdge = 0.8;

struct Shape {
  const char* name;
  image::Volume<float> field;
  geometry::TriangleMesh surface;
  double exact_volume;
};

image::Volume<float> sample(double half, double s, const std::function<double(const Vec3&)>& f) {
  const auto n = std::int64_t(std::ceil(2 * half / s)) + 1;
  image::Volume<float> v({n, n, n}, Vec3::Constant(s), Vec3::Constant(-half));
  for (std::int64_t k = 0; k < n; ++k)
    for (std::int64_t j = 0; j < n; ++j)
      for (std::int64_t i = 0; i < n; ++i)
        v(i, j, k) = float(f(v.index_to_world(Vec3(double(i), double(j), double(k)))));
  return v;
}

const std::vector<Shape>& shapes() {
  static const std::vector<Shape> all = [] {
    std::vector<Shape> s;
    s.push_back({"sphere_r10",
                 sample(11.5, 0.25, [](const Vec3& p) { return p.norm() - 10.0; }),
                 geometry::icosphere(Vec3::Zero(), 10.0, 4), 4.0 / 3.0 * kPi * 1000.0});
    s.push_back({"torus",
                 sample(13.5, 0.25,
                        [](const Vec3& p) {
                          return std::hypot(std::hypot(p.x(), p.y()) - 9.0, p.z()) - 3.5;
                        }),
                 geometry::torus_surface(Vec3::Zero(), 9.0, 3.5, 98, 28),
                 2 * kPi * kPi * 9.0 * 3.5 * 3.5});
    return s;
  }();
  return all;
}

void BM_Stuffing(benchmark::State& state) {
  const Shape& shape = shapes()[std::size_t(state.range(0))];
  const bool threaded = state.range(1) != 0;
  const bool graded = state.range(2) != 0;
  std::size_t tets = 0;
  for (auto _ : state) {
    const auto mesh = meshing::tetrahedralize(
        shape.field, {.edge_mm = kEdge, .graded = graded, .threaded = threaded});
    tets = mesh.tet_count();
    benchmark::DoNotOptimize(mesh.tets.data());
  }
  state.SetLabel(std::string(shape.name) + (graded ? " graded" : "") +
                 (threaded ? " threaded" : " serial"));
  state.counters["tets"] = double(tets);
  state.counters["tets_per_s"] =
      benchmark::Counter(double(tets), benchmark::Counter::kIsIterationInvariantRate);
}
// args: shape, threaded, graded
BENCHMARK(BM_Stuffing)->Args({0, 1, 0})->Args({0, 0, 0})->Args({1, 1, 0})->Args({1, 0, 0})
    ->Args({0, 1, 1})->Args({0, 0, 1})->Args({1, 1, 1})->Args({1, 0, 1})
    ->MeasureProcessCPUTime()->Unit(benchmark::kMillisecond);

// ---- TetGen as a separate program ---------------------------------------------------

std::filesystem::path work_dir() {
  static const auto dir = [] {
    auto d = std::filesystem::temp_directory_path() / "ido_bench_tetgen";
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

void write_off(const std::filesystem::path& path, const geometry::TriangleMesh& m) {
  write_file_atomically(path, [&](std::ostream& os) {
    os << "OFF\n" << m.vertices.size() << " " << m.triangles.size() << " 0\n";
    os.precision(17);
    for (const Vec3& v : m.vertices) os << v.x() << " " << v.y() << " " << v.z() << "\n";
    for (const Tri& t : m.triangles) os << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  }, false);
}

/// Reads TetGen's .node/.ele output (first attribute-free columns only).
geometry::TetMesh read_tetgen(const std::filesystem::path& stem) {
  geometry::TetMesh m;
  auto lines = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    std::vector<std::string> out;
    for (std::string l; std::getline(in, l);) {
      const auto hash = l.find('#');
      if (hash != std::string::npos) l.resize(hash);
      if (l.find_first_not_of(" \t\r") != std::string::npos) out.push_back(l);
    }
    return out;
  };
  const auto node = lines(stem.string() + ".node");
  const auto ele = lines(stem.string() + ".ele");
  if (node.empty() || ele.empty()) return m;
  std::istringstream nh(node[0]);
  std::size_t nn = 0;
  nh >> nn;
  int base = 0;
  for (std::size_t i = 1; i <= nn && i < node.size(); ++i) {
    std::istringstream s(node[i]);
    int id;
    double x, y, z;
    s >> id >> x >> y >> z;
    if (i == 1) base = id;
    m.vertices.emplace_back(x, y, z);
  }
  std::istringstream eh(ele[0]);
  std::size_t ne = 0;
  eh >> ne;
  for (std::size_t i = 1; i <= ne && i < ele.size(); ++i) {
    std::istringstream s(ele[i]);
    int id, a, b, c, d;
    s >> id >> a >> b >> c >> d;
    m.tets.push_back({a - base, b - base, c - base, d - base});
  }
  return m;
}

double mean_tet_volume(const geometry::TetMesh& m) {
  double v = 0;
  for (const Tet& t : m.tets)
    v += std::abs(geometry::tet_signed_volume(m.vertices[std::size_t(t[0])], m.vertices[std::size_t(t[1])],
                                              m.vertices[std::size_t(t[2])], m.vertices[std::size_t(t[3])]));
  return m.tets.empty() ? 0 : v / double(m.tets.size());
}

double children_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_CHILDREN, &u);
  return double(u.ru_utime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec) +
         double(u.ru_stime.tv_sec) + 1e-6 * double(u.ru_stime.tv_usec);
}

/// Runs tetgen on shape i; returns the CPU seconds (user + system) it took, or a negative
/// value on failure. CPU time, not wall time, because the benchmark machine is shared.
/// max_volume <= 0: no volume bound (-pq1.414 alone, TetGen's own grading from the surface).
double run_tetgen(std::size_t i, double max_volume) {
  const Shape& shape = shapes()[i];
  const auto off = work_dir() / (std::string(shape.name) + ".off");
  if (!std::filesystem::exists(off)) write_off(off, shape.surface);
  char cmd[1024];
  if (max_volume > 0)
    std::snprintf(cmd, sizeof cmd, "tetgen -pq1.414a%.6fQ '%s' > /dev/null 2>&1", max_volume,
                  off.c_str());
  else
    std::snprintf(cmd, sizeof cmd, "tetgen -pq1.414Q '%s' > /dev/null 2>&1", off.c_str());
  const double t0 = children_cpu_s();
  const int rc = std::system(cmd);
  const double t1 = children_cpu_s();
  if (rc != 0) return -1;
  return t1 - t0;
}

double stuffing_mean_volume(std::size_t i) {
  static std::vector<double> cache(shapes().size(), 0.0);
  if (cache[i] == 0)
    cache[i] = mean_tet_volume(meshing::tetrahedralize(shapes()[i].field, {.edge_mm = kEdge}));
  return cache[i];
}

/// TetGen's -a bounds the volume from above and its refinement then lands well below it;
/// twice ido's mean tetrahedron volume gives meshes of comparable size.
constexpr double kTetGenVolumeFactor = 2.0;

bool have_tetgen() { return std::system("command -v tetgen > /dev/null 2>&1") == 0; }

void BM_TetGenProcess(benchmark::State& state) {
  const auto i = std::size_t(state.range(0));
  if (!have_tetgen()) {
    state.SkipWithError("tetgen not installed (scripts/install-deps.sh --bench)");
    return;
  }
  const bool unbounded = state.range(1) != 0;  // graded: no -a bound
  const double v = unbounded ? 0.0 : kTetGenVolumeFactor * stuffing_mean_volume(i);
  for (auto _ : state) {
    const double s = run_tetgen(i, v);
    if (s < 0) {
      state.SkipWithError("tetgen failed");
      return;
    }
    state.SetIterationTime(s);
  }
  const auto off = work_dir() / (std::string(shapes()[i].name) + ".off");
  const auto mesh = read_tetgen(work_dir() / (std::string(shapes()[i].name) + ".1"));
  (void)off;
  state.SetLabel(std::string(shapes()[i].name) +
                 (unbounded ? " tetgen -pq1.414" : " tetgen -pq1.414a" + std::to_string(v)));
  state.counters["tets"] = double(mesh.tet_count());
  state.counters["tets_per_s"] =
      benchmark::Counter(double(mesh.tet_count()), benchmark::Counter::kIsIterationInvariantRate);
}
// args: shape, unbounded volume (TetGen's graded mesh, compared with graded stuffing)
BENCHMARK(BM_TetGenProcess)->Args({0, 0})->Args({1, 0})->Args({0, 1})->Args({1, 1})->UseManualTime()->Unit(benchmark::kMillisecond);

// ---- quality table ------------------------------------------------------------------

void print_quality_row(const char* shape, const char* method, const geometry::TetMesh& m,
                       double exact_volume) {
  double dmin = 180, dmax = 0, qmin = 1, qsum = 0, vol = 0;
  std::size_t below20 = 0;
  for (const Tet& t : m.tets) {
    const Vec3& a = m.vertices[std::size_t(t[0])];
    const Vec3& b = m.vertices[std::size_t(t[1])];
    const Vec3& c = m.vertices[std::size_t(t[2])];
    const Vec3& d = m.vertices[std::size_t(t[3])];
    const auto ang = geometry::dihedral_angles_deg(a, b, c, d);
    double tmin = 180;
    for (double x : ang) {
      dmin = std::min(dmin, x);
      dmax = std::max(dmax, x);
      tmin = std::min(tmin, x);
    }
    below20 += tmin < 20.0;
    const double q = std::abs(geometry::mean_ratio(a, b, c, d));
    qmin = std::min(qmin, q);
    qsum += q;
    vol += std::abs(geometry::tet_signed_volume(a, b, c, d));
  }
  const double n = double(std::max<std::size_t>(m.tet_count(), 1));
  std::printf("| %s | %s | %zu | %zu | %.2f | %.2f | %.3f | %.3f | %.2f %% | %+.3f %% |\n", shape,
              method, m.vertex_count(), m.tet_count(), dmin, dmax, qmin, qsum / n,
              100.0 * double(below20) / n, 100.0 * (vol - exact_volume) / exact_volume);
}

}  // namespace

int main(int argc, char** argv) {
  // --quality_table: print the quality table after the timings (it runs tetgen once more).
  bool table = false;
  int kept = 1;
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "--quality_table") table = true;
    else argv[kept++] = argv[a];
  }
  argc = kept;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (!table) return 0;

  std::printf("\n| shape | method | vertices | tets | min dihedral ° | max dihedral ° | min mean ratio "
              "| mean mean ratio | tets with an angle < 20° | volume error |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t i = 0; i < shapes().size(); ++i) {
    const Shape& s = shapes()[i];
    print_quality_row(s.name, "ido stuffing h=0.8",
                      meshing::tetrahedralize(s.field, {.edge_mm = kEdge}), s.exact_volume);
    if (have_tetgen() && run_tetgen(i, kTetGenVolumeFactor * stuffing_mean_volume(i)) >= 0)
      print_quality_row(s.name, "tetgen -pq1.414a(2V)",
                        read_tetgen(work_dir() / (std::string(s.name) + ".1")), s.exact_volume);
    print_quality_row(s.name, "ido graded stuffing h=0.8",
                      meshing::tetrahedralize(s.field, {.edge_mm = kEdge, .graded = true}),
                      s.exact_volume);
    if (have_tetgen() && run_tetgen(i, 0.0) >= 0)
      print_quality_row(s.name, "tetgen -pq1.414 (graded)",
                        read_tetgen(work_dir() / (std::string(s.name) + ".1")), s.exact_volume);
  }
  return 0;
}

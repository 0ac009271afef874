// SPDX-License-Identifier: Apache-2.0
#include "ido/io/file_info.h"

#include <algorithm>
#include <cmath>
#include <system_error>

#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "parsers.h"
#include "text_parser.h"

namespace ido::io {

FileKind file_kind(const std::filesystem::path& path) {
  if (is_triangle_mesh_path(path)) return FileKind::TriangleMesh;
  if (detail::lower_extension(path.filename().string()) == ".msh") {
    // Gmsh files hold either kind: tetrahedra win; a file with triangles only is a surface.
    const std::string bytes = detail::read_file_bytes(path);
    const std::string name = path.string();
    if (detail::parse_gmsh_tets(bytes, name).tet_count() > 0) return FileKind::TetMesh;
    if (!detail::parse_gmsh_triangles(bytes, name).triangles.empty()) return FileKind::TriangleMesh;
    return FileKind::TetMesh;
  }
  if (is_tet_mesh_path(path)) return FileKind::TetMesh;
  if (looks_like_volume(path)) return FileKind::Volume;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError(path.string(), "no such file or folder");
  throw IoError(path.string(), "unknown file type (expected a volume, a DICOM folder or a mesh extension)");
}

VolumeStatistics volume_statistics(const image::Volume<float>& volume) {
  if (volume.empty()) throw InvalidInput("volume_statistics: the volume is empty");
  const auto& d = volume.data();
  VolumeStatistics s;
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  s.min = *lo;
  s.max = *hi;
  // Two passes (mean, then squared deviations) for accuracy.
  double sum = 0.0;
  for (float v : d) sum += v;
  s.mean = sum / double(d.size());
  double sq = 0.0;
  for (float v : d) sq += (v - s.mean) * (v - s.mean);
  s.stddev = std::sqrt(sq / double(d.size()));
  std::vector<float> sorted(d);
  for (double p : {1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0}) {
    // Nearest rank: the smallest value with at least p % of the voxels at or below it.
    auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * double(sorted.size())));
    rank = std::clamp<std::size_t>(rank, 1, sorted.size()) - 1;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank), sorted.end());
    s.percentiles.emplace_back(p, sorted[rank]);
  }
  return s;
}

std::array<Vec3, 2> point_bounds(const std::vector<Vec3>& points) {
  if (points.empty()) return {Vec3::Zero(), Vec3::Zero()};
  Vec3 lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return {lo, hi};
}

}  // namespace ido::io

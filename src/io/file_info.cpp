// SPDX-License-Identifier: Apache-2.0
#include "ido/io/file_info.h"

#include <algorithm>
#include <cmath>
#include <system_error>

#include "ido/core/error.h"
#include "ido/core/statistics.h"
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
  const std::vector<double> ps{1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0};
  std::vector<double> qs;
  for (double p : ps) qs.push_back(p / 100.0);
  const std::vector<double> v = percentiles(std::vector<float>(d), qs);
  for (std::size_t i = 0; i < ps.size(); ++i) s.percentiles.emplace_back(ps[i], v[i]);
  return s;
}

}  // namespace ido::io

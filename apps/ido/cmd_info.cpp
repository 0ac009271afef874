// SPDX-License-Identifier: Apache-2.0
// `ido info FILE [--json]`: what a volume or mesh file holds. Presentation only: reading,
// statistics and mesh checks come from the library.
#include <iostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "command.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "ido/io/file_info.h"
#include "ido/io/mesh_io.h"
#include "ido/io/report_json.h"
#include "ido/io/volume_io.h"

namespace ido::cli {
namespace {

// Insertion order, which is reading order: what the file is, its size and geometry, then
// statistics and checks (nlohmann::json would sort the keys: p25 before p5).
using json = nlohmann::ordered_json;

struct InfoOptions {
  std::string input;
  bool json = false;
};

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

json fields_json(const geometry::FieldMap& fields) {
  json out = json::object();
  for (const auto& [name, f] : fields) out[name] = {{"components", f.components}, {"count", f.count()}};
  return out;
}

json volume_json(const std::string& path) {
  io::VolumeFileInfo info;
  const auto vol = io::read_volume(path, &info);
  const auto stats = io::volume_statistics(vol);
  json dir = json::array();
  for (int r = 0; r < 3; ++r) dir.push_back(json::array({vol.direction()(r, 0), vol.direction()(r, 1), vol.direction()(r, 2)}));
  json pct = json::object();
  for (const auto& [p, v] : stats.percentiles) pct[fmt::format("p{:g}", p)] = v;
  json j = {{"file", path},
            {"kind", "volume"},
            {"format", info.format},
            {"pixel_type", info.pixel_type},
            {"size", json::array({vol.size(0), vol.size(1), vol.size(2)})},
            {"spacing_mm", vec(vol.spacing())},
            {"origin_mm", vec(vol.origin())},
            {"direction", dir},
            {"voxels", vol.voxel_count()},
            {"min", stats.min},
            {"max", stats.max},
            {"mean", stats.mean},
            {"stddev", stats.stddev},
            {"percentiles", pct}};
  if (!info.series_uid.empty()) j["series_uid"] = info.series_uid;
  return j;
}

json triangle_json(const std::string& path) {
  const auto mesh = io::read_triangle_mesh(path);
  const auto r = geometry::check_mesh(mesh);
  const geometry::Aabb b = geometry::Aabb::of(mesh.vertices);
  json j = {{"file", path},
            {"kind", "triangle_mesh"},
            {"vertices", mesh.vertices.size()},
            {"triangles", mesh.triangles.size()},
            {"bounds_min_mm", b.empty() ? json(nullptr) : vec(b.min)},
            {"bounds_max_mm", b.empty() ? json(nullptr) : vec(b.max)},
            {"point_fields", fields_json(mesh.point_fields)},
            {"cell_fields", fields_json(mesh.cell_fields)}};
  j["checks"] = io::to_json(r);
  return j;
}

json tet_json(const std::string& path) {
  const auto mesh = io::read_tet_mesh(path);
  const auto r = geometry::check_tet_mesh(mesh);
  const geometry::Aabb b = geometry::Aabb::of(mesh.vertices);
  json j = {{"file", path},
            {"kind", "tet_mesh"},
            {"vertices", mesh.vertices.size()},
            {"tets", mesh.tets.size()},
            {"bounds_min_mm", b.empty() ? json(nullptr) : vec(b.min)},
            {"bounds_max_mm", b.empty() ? json(nullptr) : vec(b.max)},
            {"point_fields", fields_json(mesh.point_fields)},
            {"cell_fields", fields_json(mesh.cell_fields)}};
  j["checks"] = io::to_json(r);
  return j;
}

std::string text_value(const json& v) {
  if (v.is_array()) {
    std::string s;
    for (const auto& e : v) s += (s.empty() ? "" : " × ") + text_value(e);
    return s;
  }
  if (v.is_number_float()) return fmt::format("{:.6g}", v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

/// Human-readable listing: one "key: value" line per entry, nested objects indented.
void print_text(const json& j, int indent) {
  for (const auto& [k, v] : j.items()) {
    if (v.is_object()) {
      if (v.empty()) continue;
      std::cout << std::string(std::size_t(indent), ' ') << k << ":\n";
      print_text(v, indent + 2);
    } else if (k == "direction") {
      std::cout << std::string(std::size_t(indent), ' ') << k << ":";
      for (const auto& row : v) std::cout << " [" << fmt::format("{:.6g} {:.6g} {:.6g}", row[0].get<double>(), row[1].get<double>(), row[2].get<double>()) << "]";
      std::cout << "\n";
    } else {
      std::cout << std::string(std::size_t(indent), ' ') << k << ": " << text_value(v) << "\n";
    }
  }
}

void run(const InfoOptions& o) {
  json j;
  switch (io::file_kind(o.input)) {
    case io::FileKind::Volume: j = volume_json(o.input); break;
    case io::FileKind::TriangleMesh: j = triangle_json(o.input); break;
    case io::FileKind::TetMesh: j = tet_json(o.input); break;
  }
  if (o.json) std::cout << j.dump(2) << "\n";
  else print_text(j, 0);
}

void setup(CLI::App& app, const GlobalOptions& /*g*/) {
  auto* sub = app.add_subcommand("info", "Describe a volume (NIfTI, NRRD, MetaImage, DICOM folder) or mesh file");
  auto opts = std::make_shared<InfoOptions>();
  sub->add_option("FILE", opts->input, "Volume file, DICOM folder or mesh file")->required();
  sub->add_flag("--json", opts->json, "Print JSON instead of text");
  sub->callback([opts] { run(*opts); });
}

const bool kRegistered = register_command({"info", 10, setup});

}  // namespace
}  // namespace ido::cli

// SPDX-License-Identifier: Apache-2.0
#include "ido/io/scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "ido/core/statistics.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/tet_quality.h"
#include "ido/io/mesh_io.h"
#include "ido/io/pvd.h"
#include "ido/io/report_json.h"
#include "ido/sim/diagnostics.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/fem_linear.h"
#include "ido/sim/fem_neo_hookean.h"
#include "ido/sim/generators.h"
#include "ido/sim/mass_spring.h"
#include "ido/sim/mls.h"
#include "ido/sim/shape_matching.h"
#include "ido/sim/units.h"
#include "parsers.h"

namespace ido::io {

namespace {

using json = nlohmann::json;

/// Reads typed values out of the scene, failing with the file name and JSON pointer.
class Reader {
 public:
  explicit Reader(std::string source) : m_source(std::move(source)) {}

  [[noreturn]] void fail(const std::string& ptr, const std::string& problem) const {
    throw InvalidInput(m_source + ": " + (ptr.empty() ? "/" : ptr) + ": " + problem);
  }

  const json& object(const json& j, const std::string& ptr,
                     std::initializer_list<const char*> allowed) const {
    if (!j.is_object()) fail(ptr, "must be an object");
    for (const auto& [k, v] : j.items()) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || k == a;
      if (!ok) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(ptr + "/" + k, "unknown field (expected one of: " + list + ")");
      }
    }
    return j;
  }

  static bool has(const json& obj, const char* key) { return obj.contains(key); }

  double number(const json& obj, const std::string& ptr, const char* key,
                std::optional<double> fallback = std::nullopt) const {
    const std::string p = ptr + "/" + key;
    if (!obj.contains(key)) {
      if (fallback) return *fallback;
      fail(p, "missing (a number is required)");
    }
    const auto& v = obj.at(key);
    if (!v.is_number()) fail(p, "must be a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(p, "must be finite");
    return d;
  }

  double positive(const json& obj, const std::string& ptr, const char* key,
                  std::optional<double> fallback = std::nullopt) const {
    const double d = number(obj, ptr, key, fallback);
    if (!(d > 0.0)) fail(ptr + "/" + key, fmt::format("must be > 0, got {}", d));
    return d;
  }

  double non_negative(const json& obj, const std::string& ptr, const char* key, double fallback) const {
    const double d = number(obj, ptr, key, fallback);
    if (!(d >= 0.0)) fail(ptr + "/" + key, fmt::format("must be >= 0, got {}", d));
    return d;
  }

  std::int64_t integer(const json& obj, const std::string& ptr, const char* key,
                       std::optional<std::int64_t> fallback, std::int64_t min) const {
    const std::string p = ptr + "/" + key;
    if (!obj.contains(key)) {
      if (fallback) return *fallback;
      fail(p, "missing (an integer is required)");
    }
    const auto& v = obj.at(key);
    if (!v.is_number_integer()) fail(p, "must be an integer");
    const auto i = v.get<std::int64_t>();
    if (i < min) fail(p, fmt::format("must be >= {}, got {}", min, i));
    return i;
  }

  bool boolean(const json& obj, const std::string& ptr, const char* key, bool fallback) const {
    if (!obj.contains(key)) return fallback;
    if (!obj.at(key).is_boolean()) fail(ptr + "/" + key, "must be true or false");
    return obj.at(key).get<bool>();
  }

  std::string string(const json& obj, const std::string& ptr, const char* key,
                     std::optional<std::string> fallback = std::nullopt) const {
    const std::string p = ptr + "/" + key;
    if (!obj.contains(key)) {
      if (fallback) return *fallback;
      fail(p, "missing (a string is required)");
    }
    if (!obj.at(key).is_string()) fail(p, "must be a string");
    return obj.at(key).get<std::string>();
  }

  Vec3 vec3(const json& obj, const std::string& ptr, const char* key,
            std::optional<Vec3> fallback = std::nullopt) const {
    const std::string p = ptr + "/" + key;
    if (!obj.contains(key)) {
      if (fallback) return *fallback;
      fail(p, "missing (an array of 3 numbers is required)");
    }
    const auto& v = obj.at(key);
    if (!v.is_array() || v.size() != 3) fail(p, "must be an array of 3 numbers");
    Vec3 out;
    for (int i = 0; i < 3; ++i) {
      if (!v[static_cast<std::size_t>(i)].is_number()) fail(p + "/" + std::to_string(i), "must be a number");
      out[i] = v[static_cast<std::size_t>(i)].get<double>();
      if (!std::isfinite(out[i])) fail(p + "/" + std::to_string(i), "must be finite");
    }
    return out;
  }

  Vec3i vec3i(const json& obj, const std::string& ptr, const char* key) const {
    const std::string p = ptr + "/" + key;
    if (!obj.contains(key)) fail(p, "missing (an array of 3 integers is required)");
    const auto& v = obj.at(key);
    if (!v.is_array() || v.size() != 3) fail(p, "must be an array of 3 integers");
    Vec3i out;
    for (int i = 0; i < 3; ++i) {
      const auto& e = v[static_cast<std::size_t>(i)];
      if (!e.is_number_integer() || e.get<std::int64_t>() < 1 || e.get<std::int64_t>() > 10000)
        fail(p + "/" + std::to_string(i), "must be an integer in 1..10000");
      out[i] = static_cast<int>(e.get<std::int64_t>());
    }
    return out;
  }

  const json& array(const json& obj, const std::string& ptr, const char* key) const {
    static const json kEmpty = json::array();
    if (!obj.contains(key)) return kEmpty;
    if (!obj.at(key).is_array()) fail(ptr + "/" + key, "must be an array");
    return obj.at(key);
  }

 private:
  std::string m_source;
};

constexpr std::int64_t kMaxGeneratedCells = 500'000;
constexpr std::size_t kNoModel = static_cast<std::size_t>(-1);

geometry::TetMesh read_body_mesh(const Reader& r, const json& j, const std::string& ptr,
                                 const std::filesystem::path& base_dir) {
  if (!j.is_object()) r.fail(ptr, "must be an object");
  if (j.contains("file")) {
    r.object(j, ptr, {"file"});
    std::filesystem::path file = r.string(j, ptr, "file");
    if (file.is_relative()) file = base_dir / file;
    try {
      return read_tet_mesh(file);
    } catch (const IoError&) {
      throw;
    } catch (const InvalidInput& e) {
      r.fail(ptr + "/file", e.what());
    }
  }
  const std::string gen = r.string(j, ptr, "generator");
  if (gen == "beam") {
    r.object(j, ptr, {"generator", "size_mm", "cells", "origin_mm", "split"});
    const Vec3 size = r.vec3(j, ptr, "size_mm");
    if (!(size.minCoeff() > 0.0)) r.fail(ptr + "/size_mm", "every size must be > 0");
    const Vec3i cells = r.vec3i(j, ptr, "cells");
    if (static_cast<std::int64_t>(cells.x()) * cells.y() * cells.z() > kMaxGeneratedCells)
      r.fail(ptr + "/cells", "too many cells");
    const std::string split = r.string(j, ptr, "split", "six");
    if (split != "six" && split != "five") r.fail(ptr + "/split", "must be \"six\" or \"five\"");
    return sim::make_beam(size, cells, r.vec3(j, ptr, "origin_mm", Vec3::Zero()),
                          split == "six" ? sim::HexSplit::Six : sim::HexSplit::Five);
  }
  if (gen == "cube") {
    r.object(j, ptr, {"generator", "edge_mm", "cells", "centre_mm"});
    const double edge = r.positive(j, ptr, "edge_mm");
    const auto cells = r.integer(j, ptr, "cells", std::nullopt, 1);
    if (cells > 120) r.fail(ptr + "/cells", "must be <= 120");
    return sim::make_cube(edge, static_cast<int>(cells), r.vec3(j, ptr, "centre_mm", Vec3::Zero()));
  }
  if (gen == "sphere") {
    r.object(j, ptr, {"generator", "radius_mm", "cells_per_radius", "centre_mm"});
    const double radius = r.positive(j, ptr, "radius_mm");
    const auto cells = r.integer(j, ptr, "cells_per_radius", std::nullopt, 1);
    if (cells > 60) r.fail(ptr + "/cells_per_radius", "must be <= 60");
    return sim::make_sphere(radius, static_cast<int>(cells), r.vec3(j, ptr, "centre_mm", Vec3::Zero()));
  }
  r.fail(ptr + "/generator", "unknown generator '" + gen + "' (known: beam, cube, sphere)");
}

geometry::Aabb read_box(const Reader& r, const json& j, const std::string& ptr) {
  const geometry::Aabb b{r.vec3(j, ptr, "box_min_mm"), r.vec3(j, ptr, "box_max_mm")};
  if (!(b.min.array() <= b.max.array()).all()) r.fail(ptr + "/box_max_mm", "must be >= box_min_mm in every axis");
  return b;
}

double mean_edge_length(const geometry::TetMesh& mesh) {
  double s = 0.0;
  std::size_t n = 0;
  for (const auto& t : mesh.tets)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        s += (mesh.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(a)])] -
              mesh.vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(b)])]).norm();
        ++n;
      }
  return n ? s / static_cast<double>(n) : 1.0;
}

/// Boundary triangles of a tetrahedral mesh (faces used by one tetrahedron), outward.
std::vector<Tri> boundary_faces(const geometry::TetMesh& mesh) {
  std::map<std::array<std::int32_t, 3>, std::pair<int, Tri>> faces;
  for (const auto& t : mesh.tets) {
    const Tri f[4] = {{t[1], t[2], t[3]}, {t[0], t[3], t[2]}, {t[0], t[1], t[3]}, {t[0], t[2], t[1]}};
    for (const auto& tri : f) {
      std::array<std::int32_t, 3> key = {tri[0], tri[1], tri[2]};
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      ++e.first;
      e.second = tri;
    }
  }
  std::vector<Tri> out;
  for (const auto& [k, e] : faces)
    if (e.first == 1) out.push_back(e.second);
  return out;
}

void add_body(Scene& scene, const Reader& r, const json& jb, const std::string& ptr,
              const std::filesystem::path& base_dir) {
  r.object(jb, ptr, {"name", "mesh", "model", "material", "mass_spring", "shape_matching", "mls",
                     "fixed", "loads", "initial_velocity_mm_s"});
  auto& world = scene.world;
  SceneBody body;
  body.name = r.string(jb, ptr, "name", "body" + std::to_string(scene.bodies.size()));
  if (!jb.contains("mesh")) r.fail(ptr + "/mesh", "missing (an object with \"file\" or \"generator\")");
  body.rest_mesh = read_body_mesh(r, jb.at("mesh"), ptr + "/mesh", base_dir);
  const std::string model = r.string(jb, ptr, "model");

  if (!jb.contains("material")) r.fail(ptr + "/material", "missing");
  const auto& jm = r.object(jb.at("material"), ptr + "/material",
                            {"youngs_modulus_pa", "poisson_ratio", "density_kg_m3"});
  const std::string mp = ptr + "/material";
  sim::ElasticMaterial material;
  material.youngs_modulus_pa = r.positive(jm, mp, "youngs_modulus_pa");
  material.poisson_ratio = r.number(jm, mp, "poisson_ratio");
  if (!(material.poisson_ratio < 0.5)) r.fail(mp + "/poisson_ratio", "must be < 0.5");
  if (!(material.poisson_ratio > -1.0)) r.fail(mp + "/poisson_ratio", "must be > -1");
  const double density = r.positive(jm, mp, "density_kg_m3");

  try {
    body.first_particle = world.add_tet_body(body.rest_mesh, density);
  } catch (const InvalidInput& e) {
    r.fail(ptr + "/mesh", e.what());
  }
  const auto first = body.first_particle;
  std::vector<Tet> tets = body.rest_mesh.tets;
  for (auto& t : tets)
    for (auto& i : t) i += first;
  const auto& x = world.particles().positions();
  const std::size_t nv = body.rest_mesh.vertex_count();

  auto check_section = [&](const char* wanted) {
    for (const char* s : {"mass_spring", "shape_matching", "mls"})
      if (std::string(s) != wanted && jb.contains(s))
        r.fail(ptr + "/" + s, "only allowed with \"model\": \"" + std::string(s) + "\"");
  };
  if (model == "corotational_fem" || model == "linear_fem" || model == "neo_hookean_fem") {
    check_section("");
    if (model == "corotational_fem") world.emplace_model<sim::CorotationalFem>(tets, x, material);
    if (model == "linear_fem") world.emplace_model<sim::LinearFem>(tets, x, material);
    if (model == "neo_hookean_fem") world.emplace_model<sim::NeoHookeanFem>(tets, x, material);
    body.model_index = body.stress_model_index = world.models().size() - 1;
  } else {
    if (model == "mass_spring") {
      check_section("mass_spring");
      const json empty = json::object();
      const auto& js = r.object(jb.contains("mass_spring") ? jb.at("mass_spring") : empty,
                                ptr + "/mass_spring", {"stiffness_n_per_mm", "damping_n_s_per_mm"});
      const std::string sp = ptr + "/mass_spring";
      const double k = r.positive(js, sp, "stiffness_n_per_mm");
      const double c = r.non_negative(js, sp, "damping_n_s_per_mm", 0.0);
      world.emplace_model<sim::MassSpring>(sim::MassSpring::from_tet_edges(body.rest_mesh, first, k, c));
    } else if (model == "shape_matching") {
      check_section("shape_matching");
      const json empty = json::object();
      const auto& js = r.object(jb.contains("shape_matching") ? jb.at("shape_matching") : empty,
                                ptr + "/shape_matching", {"mode", "beta", "stiffness_per_s2", "cluster_size_mm"});
      const std::string sp = ptr + "/shape_matching";
      sim::ShapeMatchingOptions o;
      const std::string mode = r.string(js, sp, "mode", "linear");
      if (mode == "rigid") o.mode = sim::ShapeMatchingMode::Rigid;
      else if (mode == "linear") o.mode = sim::ShapeMatchingMode::Linear;
      else if (mode == "quadratic") o.mode = sim::ShapeMatchingMode::Quadratic;
      else r.fail(sp + "/mode", "must be \"rigid\", \"linear\" or \"quadratic\"");
      o.beta = r.number(js, sp, "beta", 0.5);
      if (!(o.beta >= 0.0 && o.beta <= 1.0)) r.fail(sp + "/beta", "must be in [0, 1]");
      o.stiffness_per_s2 = r.positive(js, sp, "stiffness_per_s2", 1e4);
      const double cell = r.positive(js, sp, "cluster_size_mm", 3.0 * mean_edge_length(body.rest_mesh));
      std::vector<Vec3> rest(x.begin() + first, x.begin() + first + static_cast<std::ptrdiff_t>(nv));
      auto clusters = sim::grid_clusters(rest, cell);
      for (auto& c : clusters)
        for (auto& i : c) i += first;
      try {
        world.emplace_model<sim::ShapeMatching>(world.particles(), std::move(clusters), o);
      } catch (const InvalidInput& e) {
        r.fail(sp, e.what());
      }
    } else if (model == "mls") {
      check_section("mls");
      const json empty = json::object();
      const auto& js = r.object(jb.contains("mls") ? jb.at("mls") : empty, ptr + "/mls",
                                {"support_radius_mm", "volume_stiffness_pa"});
      const std::string sp = ptr + "/mls";
      sim::MlsOptions o;
      o.material = material;
      o.support_radius_mm = r.positive(js, sp, "support_radius_mm", 2.0 * mean_edge_length(body.rest_mesh));
      o.volume_stiffness_pa = r.non_negative(js, sp, "volume_stiffness_pa", 0.0);
      std::vector<std::int32_t> ids(nv);
      for (std::size_t i = 0; i < nv; ++i) ids[i] = first + static_cast<std::int32_t>(i);
      try {
        world.emplace_model<sim::MlsElasticity>(world.particles(), std::move(ids), o);
      } catch (const InvalidInput& e) {
        r.fail(sp, e.what());
      }
    } else {
      r.fail(ptr + "/model", "unknown model '" + model +
                                 "' (known: corotational_fem, linear_fem, neo_hookean_fem, "
                                 "mass_spring, shape_matching, mls)");
    }
    body.model_index = world.models().size() - 1;
    // Strain / stress output for meshless and spring bodies: corotational linear elasticity
    // with the body's material, evaluated on the tetrahedra (diagnostic only, exerts no force).
    body.stress_model_index = kNoModel;
  }
  body.material = material;

  // Boundary conditions.
  const auto& fixed = r.array(jb, ptr, "fixed");
  for (std::size_t k = 0; k < fixed.size(); ++k) {
    const std::string fp = ptr + "/fixed/" + std::to_string(k);
    const auto& jf = fixed[k];
    std::size_t count = 0;
    if (jf.is_object() && jf.contains("label")) {
      r.object(jf, fp, {"label"});
      const std::string label = r.string(jf, fp, "label");
      const auto it = body.rest_mesh.point_fields.find(label);
      if (it == body.rest_mesh.point_fields.end() || it->second.count() != nv)
        r.fail(fp + "/label", "the mesh has no point field '" + label + "'");
      for (std::size_t i = 0; i < nv; ++i)
        if (it->second.values[i * static_cast<std::size_t>(it->second.components)] != 0.0) {
          world.particles().set_fixed(static_cast<std::size_t>(first) + i, true);
          ++count;
        }
    } else {
      r.object(jf, fp, {"box_min_mm", "box_max_mm"});
      const geometry::Aabb b = read_box(r, jf, fp);
      for (std::size_t i = 0; i < nv; ++i)
        if (b.contains(body.rest_mesh.vertices[i])) {
          world.particles().set_fixed(static_cast<std::size_t>(first) + i, true);
          ++count;
        }
    }
    if (count == 0) r.fail(fp, "selects no vertex");
  }
  const auto& loads = r.array(jb, ptr, "loads");
  for (std::size_t k = 0; k < loads.size(); ++k) {
    const std::string lp = ptr + "/loads/" + std::to_string(k);
    const auto& jl = loads[k];
    if (!jl.is_object()) r.fail(lp, "must be an object");
    const std::string type = r.string(jl, lp, "type");
    if (type == "point") {
      r.object(jl, lp, {"type", "box_min_mm", "box_max_mm", "force_n"});
      const geometry::Aabb b = read_box(r, jl, lp);
      const Vec3 f = r.vec3(jl, lp, "force_n");
      std::vector<std::int32_t> sel;
      for (std::size_t i = 0; i < nv; ++i)
        if (b.contains(body.rest_mesh.vertices[i])) sel.push_back(first + static_cast<std::int32_t>(i));
      if (sel.empty()) r.fail(lp, "selects no vertex");
      for (auto i : sel) world.external().point_loads.push_back({i, f / static_cast<double>(sel.size())});
    } else if (type == "surface") {
      r.object(jl, lp, {"type", "box_min_mm", "box_max_mm", "traction_pa"});
      const geometry::Aabb b = read_box(r, jl, lp);
      const Vec3 t = r.vec3(jl, lp, "traction_pa") * sim::kPascalToNPerMm2;   // N/mm²
      std::vector<Vec3> nodal(nv, Vec3::Zero());
      bool any = false;
      for (const auto& tri : boundary_faces(body.rest_mesh)) {
        const Vec3& a = body.rest_mesh.vertices[static_cast<std::size_t>(tri[0])];
        const Vec3& bb = body.rest_mesh.vertices[static_cast<std::size_t>(tri[1])];
        const Vec3& c = body.rest_mesh.vertices[static_cast<std::size_t>(tri[2])];
        if (!b.contains(a) || !b.contains(bb) || !b.contains(c)) continue;
        any = true;
        const double area = 0.5 * (bb - a).cross(c - a).norm();
        for (auto i : tri) nodal[static_cast<std::size_t>(i)] += t * area / 3.0;
      }
      if (!any) r.fail(lp, "selects no boundary face (all three vertices must be in the box)");
      for (std::size_t i = 0; i < nv; ++i)
        if (nodal[i].squaredNorm() > 0.0)
          world.external().point_loads.push_back({first + static_cast<std::int32_t>(i), nodal[i]});
    } else {
      r.fail(lp + "/type", "must be \"point\" or \"surface\"");
    }
  }
  const Vec3 v0 = r.vec3(jb, ptr, "initial_velocity_mm_s", Vec3::Zero());
  for (std::size_t i = 0; i < nv; ++i)
    if (!world.particles().fixed(static_cast<std::size_t>(first) + i))
      world.particles().velocities()[static_cast<std::size_t>(first) + i] = v0;
  scene.bodies.push_back(std::move(body));
}

}  // namespace

Scene parse_scene(std::string_view json_text, const std::string& source_name,
                  const std::filesystem::path& base_dir) {
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::parse_error& e) {
    // nlohmann's text is "[json.exception.parse_error.101] parse error at line 3, column 5:
    // syntax error while parsing object key - unexpected '}'; expected string literal": keep
    // the part after the position, and give the position as ido does ("scene.json:3: ...").
    std::string why = e.what();
    if (const auto pe = why.find("parse error"); pe != std::string::npos)
      if (const auto colon = why.find(": ", pe); colon != std::string::npos) why = why.substr(colon + 2);
    // Line and column of the byte where parsing stopped (e.byte is 1-based; 0 for empty input).
    const std::size_t stop = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, json_text.size());
    const auto line = 1 + std::count(json_text.begin(), json_text.begin() + static_cast<std::ptrdiff_t>(stop), '\n');
    const auto line_start = json_text.rfind('\n', stop == 0 ? 0 : stop - 1);
    const std::size_t column = line_start == std::string_view::npos || stop == 0 ? stop + 1 : stop - line_start;
    if (json_text.find_first_not_of(" \t\r\n") == std::string_view::npos)
      throw IoError(source_name, "file holds no JSON (empty)");
    throw IoError(source_name, fmt::format("column {}: not valid JSON: {}", column, why),
                  FileLocation{line, std::nullopt});
  } catch (const json::exception& e) {
    // A number out of range ("[json.exception.out_of_range.406] number overflow parsing
    // '1e4000'", found by fuzz_scene): nlohmann gives no position, so the line is that of the
    // first occurrence of the number.
    std::string why = e.what();
    if (const auto close = why.find("] "); why.rfind("[json.exception.", 0) == 0 && close != std::string::npos)
      why = why.substr(close + 2);
    std::optional<std::int64_t> line;
    if (const auto q0 = why.find('\''), q1 = why.rfind('\''); q0 != std::string::npos && q1 > q0 + 1)
      if (const auto at = json_text.find(why.substr(q0 + 1, q1 - q0 - 1)); at != std::string_view::npos)
        line = 1 + std::count(json_text.begin(), json_text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    throw IoError(source_name, "not valid JSON: " + why, FileLocation{line, std::nullopt});
  }
  const Reader r(source_name);
  r.object(root, "", {"dt_s", "steps", "output_every", "integrator", "implicit", "gravity_mm_s2",
                      "damping", "planes", "bodies", "description"});
  Scene scene;
  scene.source = source_name;
  scene.dt_s = r.positive(root, "", "dt_s");
  scene.steps = r.integer(root, "", "steps", std::nullopt, 1);
  if (scene.steps > 100'000'000) r.fail("/steps", "must be <= 100000000");
  scene.output_every = r.integer(root, "", "output_every", std::max<std::int64_t>(1, scene.steps / 50), 1);
  auto& world = scene.world;
  const std::string integrator = r.string(root, "", "integrator", "implicit_euler");
  try {
    world.set_integrator(integrator);
  } catch (const InvalidInput& e) {
    r.fail("/integrator", e.what());
  }
  if (root.contains("implicit")) {
    const auto& ji = r.object(root.at("implicit"), "/implicit",
                              {"cg_tolerance", "cg_max_iterations", "preconditioner", "sgs_relaxation",
                               "warm_start", "warm_start_extrapolation"});
    auto& solver = world.implicit_options();
    solver.cg_tolerance = r.positive(ji, "/implicit", "cg_tolerance", 1e-6);
    solver.cg_max_iterations = static_cast<int>(r.integer(ji, "/implicit", "cg_max_iterations", 500, 1));
    const std::string pre = r.string(ji, "/implicit", "preconditioner", "ssor");
    if (pre == "ssor") solver.preconditioner = sim::CgPreconditioner::SymmetricGaussSeidel;
    else if (pre == "jacobi") solver.preconditioner = sim::CgPreconditioner::Jacobi;
    else r.fail("/implicit/preconditioner", fmt::format("must be 'ssor' or 'jacobi', got '{}'", pre));
    solver.sgs_relaxation = r.positive(ji, "/implicit", "sgs_relaxation", solver.sgs_relaxation);
    if (solver.sgs_relaxation >= 2.0)
      r.fail("/implicit/sgs_relaxation", fmt::format("must be in (0, 2), got {}", solver.sgs_relaxation));
    solver.warm_start = r.boolean(ji, "/implicit", "warm_start", solver.warm_start);
    solver.warm_start_extrapolation = r.boolean(ji, "/implicit", "warm_start_extrapolation", solver.warm_start_extrapolation);
  }
  world.external().gravity_mm_s2 = r.vec3(root, "", "gravity_mm_s2", Vec3::Zero());
  if (root.contains("damping")) {
    const auto& jd = r.object(root.at("damping"), "/damping", {"rayleigh_mass_per_s", "rayleigh_stiffness_s"});
    world.external().damping.mass_per_s = r.non_negative(jd, "/damping", "rayleigh_mass_per_s", 0.0);
    world.external().damping.stiffness_s = r.non_negative(jd, "/damping", "rayleigh_stiffness_s", 0.0);
  }
  const auto& planes = r.array(root, "", "planes");
  for (std::size_t k = 0; k < planes.size(); ++k) {
    const std::string pp = "/planes/" + std::to_string(k);
    r.object(planes[k], pp, {"point_mm", "normal"});
    sim::PlaneContact plane{r.vec3(planes[k], pp, "point_mm"), r.vec3(planes[k], pp, "normal")};
    if (!(plane.normal.norm() > 0.0)) r.fail(pp + "/normal", "must be non-zero");
    world.external().planes.push_back(plane);
  }
  if (!root.contains("bodies")) r.fail("/bodies", "missing (an array of bodies is required)");
  const auto& bodies = r.array(root, "", "bodies");
  if (bodies.empty()) r.fail("/bodies", "must hold at least one body");
  for (std::size_t b = 0; b < bodies.size(); ++b)
    add_body(scene, r, bodies[b], "/bodies/" + std::to_string(b), base_dir);
  return scene;
}

Scene load_scene(const std::filesystem::path& path) {
  // The shared whole-file read: a folder, a device or an empty file is refused by name, and
  // the size is checked against the memory budget.
  std::string text;
  try {
    text = detail::read_file_bytes(path);
  } catch (const IoError& e) {
    if (std::filesystem::is_directory(path)) throw IoError(path.string(), "is a folder, not a scene file");
    throw;
  }
  return parse_scene(text, path.string(), path.parent_path());
}

// ---- running -----------------------------------------------------------------------------

sim::RunOptions run_options(const Scene& scene) {
  sim::RunOptions o;
  o.dt_s = scene.dt_s;
  o.steps = scene.steps;
  o.frame_every = scene.output_every;
  o.label = scene.source.empty() ? std::string("scene") : scene.source;
  constexpr double kFloorStrain = 1e-3;
  double floor_mj = 0.0;
  for (const auto& body : scene.bodies) {
    double volume_mm3 = 0.0;
    for (const auto& t : body.rest_mesh.tets)
      volume_mm3 += std::abs(geometry::tet_signed_volume(
          body.rest_mesh.vertices[static_cast<std::size_t>(t[0])], body.rest_mesh.vertices[static_cast<std::size_t>(t[1])],
          body.rest_mesh.vertices[static_cast<std::size_t>(t[2])], body.rest_mesh.vertices[static_cast<std::size_t>(t[3])]));
    floor_mj += 0.5 * body.material.youngs_modulus_pa * sim::kPascalToNPerMm2 * kFloorStrain * kFloorStrain * volume_mm3;
  }
  o.energy_floor_mj = floor_mj;
  return o;
}

json scene_report(const Scene& scene, const SceneRunResult& result) {
  const auto& world = scene.world;
  std::size_t tets = 0;
  for (const auto& body : scene.bodies) tets += body.rest_mesh.tets.size();
  json report_json;
  report_json["steps"] = scene.steps;
  report_json["dt_s"] = scene.dt_s;
  report_json["integrator"] = world.integrator();
  report_json["particles"] = world.particles().size();
  report_json["tetrahedra"] = tets;
  report_json["frames"] = result.frames;
  report_json["wall_time_s"] = result.wall_time_s;
  const std::vector<double> ms =
      result.step_ms.empty() ? std::vector<double>(4, 0.0) : percentiles(result.step_ms, {0.5, 0.9, 0.99, 1.0});
  report_json["ms_per_step"] = {{"p50", ms[0]}, {"p90", ms[1]}, {"p99", ms[2]}, {"max", ms[3]}};
  report_json["final_energy"] = to_json(result.final_energy);
  double cg_sum = 0.0;
  int cg_max = 0;
  for (int c : result.cg_iterations) {
    cg_sum += c;
    cg_max = std::max(cg_max, c);
  }
  report_json["cg_iterations"] = {
      {"mean", result.cg_iterations.empty() ? 0.0 : cg_sum / static_cast<double>(result.cg_iterations.size())},
      {"max", cg_max},
      {"total", cg_sum}};
  return report_json;
}

namespace {

geometry::Field tensor_field(const std::vector<Mat3>& m) {
  geometry::Field f;
  f.components = 9;
  f.values.reserve(9 * m.size());
  for (const auto& t : m)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f.values.push_back(t(r, c));
  return f;
}

/// The run's file outputs as an observer: a frame file per frame, then the .pvd index,
/// energy.csv and report.json at the end, all staged in one batch.
class SceneWriter final : public sim::RunObserver {
 public:
  SceneWriter(const Scene& scene, const std::filesystem::path& out_dir, FileBatch& batch,
              const SceneFrameListener& on_frame)
      : m_scene(scene), m_out_dir(out_dir), m_batch(batch), m_on_frame(on_frame) {
    const auto& world = scene.world;
    // Diagnostic element models (no force) for bodies whose model has no elements.
    m_stress_models.resize(scene.bodies.size());
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      const auto& body = scene.bodies[b];
      if (body.stress_model_index < world.models().size()) continue;
      std::vector<Tet> tets = body.rest_mesh.tets;
      for (auto& t : tets)
        for (auto& i : t) i += body.first_particle;
      std::vector<Vec3> rest(world.particles().size(), Vec3::Zero());
      for (std::size_t i = 0; i < body.rest_mesh.vertex_count(); ++i)
        rest[static_cast<std::size_t>(body.first_particle) + i] = body.rest_mesh.vertices[i];
      m_stress_models[b] = std::make_unique<sim::CorotationalFem>(tets, rest, body.material);
    }
    // Combined rest mesh of all bodies.
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      const auto& body = scene.bodies[b];
      for (const auto& v : body.rest_mesh.vertices) m_rest.vertices.push_back(v);
      for (auto t : body.rest_mesh.tets) {
        for (auto& i : t) i += body.first_particle;
        m_rest.tets.push_back(t);
        m_body_id.push_back(static_cast<double>(b));
      }
    }
  }

  void on_frame(const sim::World& world, std::int64_t index, std::int64_t /*step*/) override {
    const auto mesh = frame(world);
    const std::string name = fmt::format("frame_{:04d}.vtu", index);
    write_tet_mesh(m_batch.stage(m_out_dir / name), mesh);
    m_pvd.push_back({world.time_s(), name});
    if (m_on_frame) m_on_frame(index, mesh);
  }

  void on_finish(const sim::World& /*world*/, const sim::RunResult& result) override {
    write_pvd(m_batch.stage(m_out_dir / "simulation.pvd"), m_pvd);
    std::string csv = "time_s,kinetic_mj,elastic_mj,gravitational_mj,total_mj\n";
    for (std::size_t i = 0; i < result.time_s.size(); ++i)
      csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", result.time_s[i], result.kinetic_mj[i],
                         result.elastic_mj[i], result.gravitational_mj[i], result.total_mj[i]);
    write_file_atomically(m_batch.stage(m_out_dir / "energy.csv"), [&](std::ostream& os) { os << csv; }, false);

    const json report_json = scene_report(m_scene, result);
    write_file_atomically(m_batch.stage(m_out_dir / "report.json"),
                          [&](std::ostream& os) { os << report_json.dump(2) << "\n"; }, false);
  }

 private:
  /// The bodies at the world's current state with the frame's fields.
  [[nodiscard]] geometry::TetMesh frame(const sim::World& world) const {
    const auto& x = world.particles().positions();
    const auto& v = world.particles().velocities();
    const auto& rest = m_rest.vertices;
    geometry::TetMesh out;
    out.tets = m_rest.tets;
    out.vertices.assign(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(rest.size()));
    geometry::Field disp{3, {}}, vel{3, {}};
    for (std::size_t i = 0; i < rest.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        disp.values.push_back(x[i][c] - rest[i][c]);
        vel.values.push_back(v[i][c]);
      }
    out.point_fields["displacement_mm"] = std::move(disp);
    out.point_fields["velocity_mm_s"] = std::move(vel);
    std::vector<Mat3> strain, stress;
    std::vector<double> vm;
    for (std::size_t b = 0; b < m_scene.bodies.size(); ++b) {
      const auto& body = m_scene.bodies[b];
      const sim::ForceModel& m = body.stress_model_index < world.models().size()
                                     ? *world.models()[body.stress_model_index]
                                     : *m_stress_models[b];
      const auto f = m.element_fields(world.particles());
      if (!f) continue;
      strain.insert(strain.end(), f->green_strain.begin(), f->green_strain.end());
      stress.insert(stress.end(), f->cauchy_stress_pa.begin(), f->cauchy_stress_pa.end());
      vm.insert(vm.end(), f->von_mises_pa.begin(), f->von_mises_pa.end());
    }
    out.cell_fields["green_strain"] = tensor_field(strain);
    out.cell_fields["cauchy_stress_pa"] = tensor_field(stress);
    out.cell_fields["von_mises_pa"] = geometry::Field{1, vm};
    out.cell_fields["body"] = geometry::Field{1, m_body_id};
    return out;
  }

  const Scene& m_scene;
  std::filesystem::path m_out_dir;
  FileBatch& m_batch;
  const SceneFrameListener& m_on_frame;
  std::vector<std::unique_ptr<sim::CorotationalFem>> m_stress_models;
  geometry::TetMesh m_rest;            ///< all bodies at rest, particle-indexed tetrahedra
  std::vector<double> m_body_id;       ///< body of each tetrahedron
  std::vector<PvdEntry> m_pvd;
};

/// Folders that create_directories(@p dir) would make, outermost first.
std::vector<std::filesystem::path> missing_folders(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> missing;
  std::error_code ec;
  for (auto d = std::filesystem::absolute(dir, ec).lexically_normal(); !d.empty() && !std::filesystem::exists(d, ec);
       d = d.parent_path()) {
    missing.insert(missing.begin(), d);
    if (d == d.parent_path()) break;
  }
  return missing;
}

}  // namespace

SceneRunResult run_scene(Scene& scene, const std::filesystem::path& out_dir, Progress* progress, FileBatch* outputs,
                         std::span<sim::RunObserver* const> observers, const SceneFrameListener& on_frame) {
  const auto created = missing_folders(out_dir);
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw IoError(out_dir.string(), "cannot create the output folder: " + ec.message());
  FileBatch own_batch;
  FileBatch& batch = outputs ? *outputs : own_batch;
  try {
    SceneWriter writer(scene, out_dir, batch, on_frame);
    std::vector<sim::RunObserver*> all{&writer};
    all.insert(all.end(), observers.begin(), observers.end());
    auto result = sim::run(scene.world, run_options(scene), all, progress);
    if (!outputs) batch.commit();
    return result;
  } catch (...) {
    batch.discard();
    for (auto it = created.rbegin(); it != created.rend(); ++it) std::filesystem::remove(*it, ec);  // only if empty
    throw;
  }
}

}  // namespace ido::io

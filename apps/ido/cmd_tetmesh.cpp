// SPDX-License-Identifier: Apache-2.0
// `ido tetmesh INPUT -o MESH.{vtu,msh,node} [--edge MM] [--graded]`: fills a segmentation
// mask, a closed surface or a signed distance field with tetrahedra (meshing::tetrahedralize,
// isosurface stuffing), or writes one of the drilling issue's test shapes
// (`--shape cube|cube12|block:SX,SY,SZ[,CELL]`). Prints a quality summary; --report writes
// the same figures as JSON. Every check happens before the first file is written.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "command.h"
#include "ido/core/error.h"
#include "ido/drill/shapes.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "ido/io/memory_budget.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "ido/meshing/distance_field.h"
#include "ido/meshing/tetrahedralize.h"

namespace ido::cli {
namespace {

struct TetmeshOptions {
  std::string input;                 ///< mask, surface or field; empty with --shape
  std::string shape;                 ///< "cube", "cube12", "block:SX,SY,SZ[,CELL]" (mm)
  std::string output;
  std::string report;                ///< JSON report path, optional
  std::string input_kind = "auto";   ///< auto | mask | surface | field
  bool field = false;                ///< --field: same as --input-kind field
  std::optional<double> edge_mm;     ///< lattice spacing (mm); unset = automatic
  std::optional<int> label;          ///< label of a label map to mesh
  bool graded = false;
};

enum class InputKind { Mask, Surface, Field };

const char* kind_name(InputKind k) {
  switch (k) {
    case InputKind::Mask: return "mask";
    case InputKind::Surface: return "surface";
    case InputKind::Field: return "field";
  }
  return "?";
}

// A volume is a mask when it holds no negative value and either only integers (0/1 or a
// label map) or only values in [0, 1] (a probability map, thresholded at ½); a field when it
// has negative non-integer values (a signed distance, negative inside) or nothing positive.
// Integers of both signs (a CT in HU, an integer label map with negatives, an integer
// distance) cannot be told apart: the caller must say.
InputKind classify_volume(const std::string& path, const image::Volume<float>& v) {
  bool negative = false, positive = false, integers = true, unit = true;
  for (float x : v.data()) {
    if (!std::isfinite(x)) continue;
    negative |= x < 0;
    positive |= x > 0;
    integers &= x == std::round(x);
    unit &= x >= 0 && x <= 1;
  }
  if (!negative && (integers || unit)) return InputKind::Mask;
  if (negative && !integers) return InputKind::Field;
  if (negative && !positive) return InputKind::Field;
  throw InvalidInput(fmt::format(
      "{}: cannot tell whether this volume is a mask or a distance field ({}); give "
      "--input-kind mask|field",
      path, negative ? "integer values of both signs" : "non-negative values beyond 1"));
}

InputKind input_kind(const TetmeshOptions& o) {
  std::string kind = o.input_kind;
  if (o.field) {
    if (kind != "auto" && kind != "field")
      throw InvalidInput(fmt::format("--field contradicts --input-kind {}", kind));
    kind = "field";
  }
  const bool surface_ext = io::is_triangle_mesh_path(o.input);
  const bool volume_ext = !surface_ext && io::looks_like_volume(o.input);
  if (kind == "surface") {
    if (!surface_ext)
      throw InvalidInput(fmt::format("{}: a surface must be .stl, .obj, .ply or .vtp", o.input));
    return InputKind::Surface;
  }
  if (kind == "mask" || kind == "field") {
    if (!volume_ext)
      throw InvalidInput(fmt::format(
          "{}: a {} must be a volume (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd or a DICOM folder)",
          o.input, kind));
    return kind == "mask" ? InputKind::Mask : InputKind::Field;
  }
  if (kind != "auto")
    throw InvalidInput(fmt::format("--input-kind {}: expected mask, surface, field or auto", kind));
  if (surface_ext) return InputKind::Surface;
  if (volume_ext) return InputKind::Field;  // refined by classify_volume once read
  throw InvalidInput(fmt::format(
      "{}: unknown input type; expected a surface (.stl, .obj, .ply, .vtp) or a volume (.nii, "
      ".nii.gz, .nrrd, .nhdr, .mha, .mhd, DICOM folder)",
      o.input));
}

geometry::TetMesh mesh_mask(const TetmeshOptions& o, const image::Volume<float>& v,
                            const meshing::TetrahedralizeOptions& to, Progress* progress) {
  auto mask = v.like<std::uint8_t>();
  std::size_t set = 0;
  for (std::size_t i = 0; i < v.data().size(); ++i) {
    const float x = v.data()[i];
    const bool in = o.label ? std::isfinite(x) && std::lround(x) == *o.label && x == std::round(x)
                            : x > 0.5f;
    mask.data()[i] = in ? 1 : 0;
    set += in ? 1 : 0;
  }
  if (set == 0) {
    throw InvalidInput(o.label ? fmt::format("{}: no voxel has label {}", o.input, *o.label)
                               : fmt::format("{}: the mask is empty (no voxel > 0.5)", o.input));
  }
  return meshing::tetrahedralize(meshing::signed_distance_from_mask(mask), to, progress);
}

// Refuses an --edge whose lattice would not fit the memory budget (ido --memory-limit),
// before anything of it is allocated. Isosurface stuffing samples the input on a
// body-centred cubic lattice of spacing h over the input's box (its corners and cell centres:
// at least 2 · Π floor(extent / h) vertices, each with a double value and a sign byte), and a
// surface is first made a distance grid of h/2 voxels (4-byte floats, at least
// Π floor(extent / (h/2)) of them). Counted from the box alone (the mesher's margins only
// add), so an edge that fits is never refused.
void check_lattice_budget(const TetmeshOptions& o, const geometry::Aabb& box, bool surface) {
  if (!o.edge_mm) return;
  const double h = *o.edge_mm;
  const Vec3 extent = box.max - box.min;
  auto cells = [&](double step) {
    std::array<std::uint64_t, 3> n{};
    for (int a = 0; a < 3; ++a) {
      const double c = std::max(1.0, std::floor(extent[a] / step));
      n[static_cast<std::size_t>(a)] = c >= 1e18 ? std::uint64_t(1e18) : static_cast<std::uint64_t>(c);
    }
    return n;
  };
  const auto n = cells(h);
  const std::uint64_t vertices = io::saturating_product({2, n[0], n[1], n[2]});
  std::uint64_t bytes = io::saturating_product({vertices, sizeof(double) + sizeof(std::int8_t)});
  if (surface) {
    const auto g = cells(0.5 * h);
    const std::uint64_t grid = io::saturating_product({g[0], g[1], g[2], sizeof(float)});
    bytes = grid > UINT64_MAX - bytes ? UINT64_MAX : bytes + grid;
  }
  if (bytes > io::memory_limit_bytes())
    throw InvalidInput(fmt::format("--edge {:g}: the meshing lattice over {} ({:.3g} x {:.3g} x {:.3g} mm) has at "
                                   "least {:.3g} vertices and needs {}, over the memory limit of {} "
                                   "(ido --memory-limit)",
                                   h, o.input, extent.x(), extent.y(), extent.z(), static_cast<double>(vertices),
                                   io::format_bytes(bytes), io::format_bytes(io::memory_limit_bytes())));
}

// Runs the mesher, saying in the CLI's words (naming --edge, not the library's edge_mm) when
// it refuses the lattice spacing as too small: more lattice vertices than it accepts, though
// within the memory budget.
template <class Mesher>
geometry::TetMesh run_mesher(const TetmeshOptions& o, Mesher&& mesher) {
  try {
    return mesher();
  } catch (const meshing::EdgeTooSmall&) {
    if (!o.edge_mm) throw;
    throw InvalidInput(fmt::format("--edge {:g}: the lattice spacing is too small for {}: the meshing lattice "
                                   "would have more vertices than the mesher accepts; give a larger --edge",
                                   *o.edge_mm, o.input));
  }
}

// The mesh the options ask for: a test shape, or INPUT meshed by isosurface stuffing.
geometry::TetMesh mesh_from_options(const TetmeshOptions& o, Progress* progress) {
  if (!o.shape.empty() && !o.input.empty())
    throw InvalidInput(fmt::format("tetmesh: give either INPUT ({}) or --shape {}, not both",
                                   o.input, o.shape));
  if (o.shape.empty() && o.input.empty())
    throw InvalidInput("tetmesh: give INPUT (a mask, a closed surface or a distance field) or "
                       "--shape cube|cube12|block:SX,SY,SZ[,CELL]");
  if (o.edge_mm && !(std::isfinite(*o.edge_mm) && *o.edge_mm > 0))
    throw InvalidInput(fmt::format("--edge {}: the lattice spacing must be a positive length (mm)",
                                   *o.edge_mm));
  if (!o.shape.empty()) {
    if (o.edge_mm || o.graded || o.label || o.field || o.input_kind != "auto")
      throw InvalidInput("--shape takes none of --edge, --graded, --label, --field, --input-kind");
    return drill::make_shape(o.shape);
  }

  meshing::TetrahedralizeOptions to;
  to.edge_mm = o.edge_mm.value_or(0.0);
  to.graded = o.graded;
  InputKind kind = input_kind(o);
  geometry::TetMesh mesh;
  if (kind == InputKind::Surface) {
    if (o.label) throw InvalidInput("--label applies to a mask (label map), not to a surface");
    const auto surface = io::read_triangle_mesh(o.input);
    if (surface.triangles.empty())
      throw InvalidInput(fmt::format("{}: the surface has no triangles", o.input));
    const auto check = geometry::check_mesh(surface);
    if (check.boundary_edges > 0 || check.non_manifold_edges > 0) {
      throw InvalidInput(fmt::format(
          "{}: the surface is not closed ({} boundary edges, {} non-manifold edges)", o.input,
          check.boundary_edges, check.non_manifold_edges));
    }
    check_lattice_budget(o, geometry::Aabb::of(surface.vertices), true);
    mesh = run_mesher(o, [&] { return meshing::tetrahedralize_surface(surface, to, progress); });
  } else {
    const auto volume = io::read_volume(o.input);
    if (o.input_kind == "auto" && !o.field) kind = o.label ? InputKind::Mask : classify_volume(o.input, volume);
    if (kind == InputKind::Field && o.label)
      throw InvalidInput("--label applies to a mask (label map), not to a distance field");
    check_lattice_budget(o, volume.world_bounds(), false);
    if (kind == InputKind::Mask) {
      mesh = run_mesher(o, [&] { return mesh_mask(o, volume, to, progress); });
    } else {
      for (float x : volume.data()) {
        if (std::isnan(x)) throw InvalidInput(fmt::format("{}: the distance field holds NaN", o.input));
      }
      mesh = run_mesher(o, [&] { return meshing::tetrahedralize(volume, to, progress); });
    }
  }
  if (mesh.tets.empty()) {
    throw InvalidInput(fmt::format(
        "{} ({}): nothing to mesh — the region is empty or thinner than the lattice spacing; "
        "try a smaller --edge",
        o.input, kind_name(kind)));
  }
  return mesh;
}

nlohmann::json quality_json(const TetmeshOptions& o, const geometry::TetMesh& mesh) {
  const auto q = geometry::check_tet_mesh(mesh);
  nlohmann::json j;
  j["input"] = o.input.empty() ? o.shape : o.input;
  j["output"] = o.output;
  j["graded"] = o.graded;
  j["vertices"] = q.vertices;
  j["tets"] = q.tets;
  j["inverted"] = q.inverted;
  j["degenerate"] = q.degenerate;
  j["volume_mm3"] = q.volume_mm3;
  j["min_dihedral_deg"] = q.min_dihedral_deg;
  j["max_dihedral_deg"] = q.max_dihedral_deg;
  j["min_mean_ratio"] = q.min_mean_ratio;
  j["mean_mean_ratio"] = q.mean_mean_ratio;
  j["boundary_faces"] = q.boundary_faces;
  return j;
}

void run(const TetmeshOptions& o, const GlobalOptions& g) {
  if (!io::is_tet_mesh_path(o.output)) {
    throw InvalidInput(fmt::format("{}: the output must be .vtu, .msh or .node/.ele", o.output));
  }
  if (!o.report.empty() && std::filesystem::path(o.report).extension() != ".json")
    throw InvalidInput(fmt::format("{}: --report must be a .json file", o.report));
  const auto progress = make_progress(g.quiet);
  const auto mesh = mesh_from_options(o, progress.get());
  const auto j = quality_json(o, mesh);
  io::write_tet_mesh(o.output, mesh);
  if (!o.report.empty()) write_text_file(o.report, j.dump(2) + "\n");
  if (!g.quiet) {
    std::printf("%s: %zu tetrahedra, %zu vertices, dihedral angles %.2f°–%.2f°, volume %.6g mm³\n",
                o.output.c_str(), j["tets"].get<std::size_t>(), j["vertices"].get<std::size_t>(),
                j["min_dihedral_deg"].get<double>(), j["max_dihedral_deg"].get<double>(),
                j["volume_mm3"].get<double>());
  }
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand(
      "tetmesh", "Tetrahedral mesh of a mask, a closed surface or a distance field (or a test shape)");
  auto opts = std::make_shared<TetmeshOptions>();
  sub->add_option("INPUT", opts->input,
                  "Mask or label map volume, closed surface (.stl, .obj, .ply, .vtp) or signed "
                  "distance volume (mm, negative inside)");
  sub->add_option("--shape", opts->shape,
                  "Instead of INPUT: cube | cube12 (the paper's 12-tetrahedron cube) | "
                  "block:SX,SY,SZ[,CELL] in mm");
  sub->add_option("-o,--output", opts->output, "Output mesh (.vtu, .msh, .node)")->required();
  sub->add_option("--edge", opts->edge_mm,
                  "Lattice spacing h (mm); default: twice the voxel size (volumes) or the mean "
                  "edge length (surfaces)");
  sub->add_flag("--graded", opts->graded, "Octree-graded lattice: coarser tetrahedra inside");
  sub->add_option("--label", opts->label, "Mesh the voxels with this label (label map)");
  sub->add_option("--input-kind", opts->input_kind, "mask | surface | field | auto (default)");
  sub->add_flag("--field", opts->field, "INPUT is a signed distance field (= --input-kind field)");
  sub->add_option("--report", opts->report, "JSON report with the quality figures");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"tetmesh", 40, setup});

}  // namespace
}  // namespace ido::cli

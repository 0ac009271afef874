// SPDX-License-Identifier: Apache-2.0
// `ido render INPUT... -o PICTURE.png [--camera AZ,EL] [--field NAME] [--slice AXIS:INDEX]
//  [--size WxH] [--overlay MASK] [--clip PX,PY,PZ:NX,NY,NZ] [--window W,L] [--ortho]`:
// a headless picture of surfaces, tetrahedral meshes and CT slices. Presentation only: the
// drawing is ido::viz::Renderer.
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>
#include <memory>
#include <string>
#include <vector>

#include "command.h"
#include "snapshots.h"
#include "cli_util.h"
#include "ido/core/error.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"
#include "ido/viz/renderer.h"

namespace ido::cli {
namespace {

struct RenderOptions {
  std::vector<std::string> inputs;
  std::string output;
  std::string camera;
  std::string field;
  std::string slice;
  std::string size = "800x600";
  std::string overlay;
  std::string clip;
  std::string window;
  bool ortho = false;
  bool edges = false;
};

/// Parses "A,B" into two numbers; @throws ido::InvalidInput naming @p what.
std::array<double, 2> parse_pair(const std::string& text, const std::string& what) {
  std::array<double, 2> out{};
  std::size_t used = 0;
  try {
    const auto comma = text.find(',');
    if (comma == std::string::npos) throw InvalidInput("");
    out[0] = std::stod(text.substr(0, comma), &used);
    if (used != comma) throw InvalidInput("");
    const std::string rest = text.substr(comma + 1);
    out[1] = std::stod(rest, &used);
    if (used != rest.size() || !std::isfinite(out[0]) || !std::isfinite(out[1])) throw InvalidInput("");
  } catch (const std::exception&) {
    throw InvalidInput(what + " must be two numbers A,B, got '" + text + "'");
  }
  return out;
}

/// "AXIS:INDEX" with AXIS one of i/j/k, x/y/z or 0/1/2 (voxel index axes).
std::pair<int, std::int64_t> parse_slice(const std::string& text) {
  const auto colon = text.find(':');
  const std::string axis = colon == std::string::npos ? "" : text.substr(0, colon);
  int a = -1;
  if (axis == "i" || axis == "x" || axis == "0") a = 0;
  if (axis == "j" || axis == "y" || axis == "1") a = 1;
  if (axis == "k" || axis == "z" || axis == "2") a = 2;
  std::int64_t index = -1;
  try {
    std::size_t used = 0;
    const std::string rest = text.substr(colon + 1);
    index = std::stoll(rest, &used);
    if (used != rest.size()) index = -1;
  } catch (const std::exception&) {
    index = -1;
  }
  if (a < 0 || index < 0)
    throw InvalidInput("--slice must be AXIS:INDEX with AXIS one of i, j, k (or x, y, z) and a "
                       "voxel index >= 0, got '" + text + "'");
  return {a, index};
}

viz::ClipPlane parse_clip(const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos)
    throw InvalidInput("--clip must be PX,PY,PZ:NX,NY,NZ (a point and a normal in mm), got '" +
                       text + "'");
  viz::ClipPlane p;
  p.point = parse_vec3(text.substr(0, colon), "--clip point");
  p.normal = parse_vec3(text.substr(colon + 1), "--clip normal");
  if (!(p.normal.norm() > 0)) throw InvalidInput("--clip normal must not be zero");
  return p;
}

void run(const RenderOptions& o, const GlobalOptions& g) {
  const auto [w, h] = cli::parse_picture_size(o.size, "--size");
  viz::Renderer ren(w, h);
  std::optional<std::array<double, 2>> camera;
  if (!o.camera.empty()) camera = parse_pair(o.camera, "--camera (azimuth,elevation in degrees)");
  std::optional<std::pair<int, std::int64_t>> slice;
  if (!o.slice.empty()) slice = parse_slice(o.slice);
  viz::SliceOptions slice_options;
  if (!o.window.empty()) {
    const auto wl = parse_pair(o.window, "--window (width,level)");
    slice_options.window = wl[0];
    slice_options.level = wl[1];
  }
  const std::array<Vec3, 4> palette = {Vec3(0.85, 0.75, 0.6), Vec3(0.8, 0.3, 0.3),
                                       Vec3(0.3, 0.5, 0.85), Vec3(0.4, 0.7, 0.4)};
  int surfaces = 0, meshes = 0;
  std::optional<std::pair<int, std::int64_t>> drawn_slice;
  for (const std::string& input : o.inputs) {
    if (io::is_tet_mesh_path(input)) {
      const auto mesh = io::read_tet_mesh(input);
      viz::ClipPlane plane;
      if (!o.clip.empty()) {
        plane = parse_clip(o.clip);
      } else {  // keep everything: a plane beyond the mesh
        double max_x = mesh.vertices.empty() ? 0.0 : mesh.vertices.front().x();
        for (const Vec3& v : mesh.vertices) max_x = std::max(max_x, v.x());
        plane.normal = Vec3(1, 0, 0);
        plane.point = Vec3(max_x + 1.0, 0, 0);
      }
      viz::TetClipOptions clip_options;
      clip_options.edges = o.edges;
      ren.add_tet_mesh_clipped(mesh, plane, o.field, clip_options);
      ++meshes;
    } else if (io::is_triangle_mesh_path(input)) {
      ren.add_surface(io::read_triangle_mesh(input), palette[std::size_t(surfaces) % palette.size()]);
      ++surfaces;
    } else if (io::looks_like_volume(input)) {
      const auto volume = io::read_volume(input);
      const auto s = slice ? *slice : std::pair<int, std::int64_t>{2, volume.size(2) / 2};
      ren.add_slice(volume, s.first, s.second, slice_options);
      drawn_slice = s;
    } else {
      throw InvalidInput("render: cannot tell what '" + input +
                         "' is (expected a mesh .stl/.obj/.ply/.vtp/.vtu/.msh/.node or a volume "
                         ".nii/.nii.gz/.nrrd/.mha/.mhd or DICOM folder)");
    }
  }
  if (!o.overlay.empty()) {
    if (!drawn_slice) throw InvalidInput("--overlay needs a volume input to draw the slice of");
    const auto m = io::read_volume(o.overlay);
    auto mask = m.like<std::uint8_t>(0);
    for (std::size_t n = 0; n < m.data().size(); ++n) mask.data()[n] = m.data()[n] != 0.f;
    ren.add_contour(mask, drawn_slice->first, drawn_slice->second);
  }
  if (surfaces + meshes == 0 && drawn_slice && !camera) {
    ren.set_camera(ren.slice_camera());
  } else {
    const auto ae = camera.value_or(std::array<double, 2>{30.0, 20.0});
    ren.set_camera(ren.fit_camera(ae[0], ae[1],
                                  o.ortho ? viz::Projection::Orthographic : viz::Projection::Perspective));
  }
  ren.write_png(o.output);
  if (!g.quiet) std::printf("wrote %s (%dx%d)\n", o.output.c_str(), w, h);
}

void setup(CLI::App& app, const GlobalOptions& g) {
  auto* sub = app.add_subcommand("render", "Draw meshes and CT slices to a PNG (no display needed)");
  auto opts = std::make_shared<RenderOptions>();
  sub->add_option("INPUT", opts->inputs,
                  "Surfaces (.stl .obj .ply .vtp), tetrahedral meshes (.vtu .msh .node) or volumes")
      ->required();
  sub->add_option("-o,--output", opts->output, "Picture to write (.png)")->required();
  sub->add_option("--camera", opts->camera, "Azimuth,elevation in degrees (default 30,20)");
  sub->add_option("--field", opts->field, "Cell field colouring tetrahedral meshes");
  sub->add_option("--slice", opts->slice, "Volume slice AXIS:INDEX, AXIS in i,j,k (default k:middle)");
  sub->add_option("--size", opts->size, "Picture size WIDTHxHEIGHT in pixels (default 800x600)");
  sub->add_option("--overlay", opts->overlay, "Mask volume whose contour is drawn on the slice");
  sub->add_option("--clip", opts->clip, "Clip tetrahedral meshes: PX,PY,PZ:NX,NY,NZ (removes the normal's side)");
  sub->add_option("--window", opts->window, "Slice display window WIDTH,LEVEL (default: slice min..max)");
  sub->add_flag("--ortho", opts->ortho, "Orthographic instead of perspective camera");
  sub->add_flag("--edges", opts->edges, "Draw the tetrahedra's edges on clipped tetrahedral meshes");
  sub->callback([opts, &g] { run(*opts, g); });
}

const bool kRegistered = register_command({"render", 90, setup});

}  // namespace
}  // namespace ido::cli

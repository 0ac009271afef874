// SPDX-License-Identifier: Apache-2.0
// `ido convert IN OUT`: meshes between formats that can hold them, volumes between ITK
// formats (a DICOM folder to NIfTI included). Formats follow the extensions.
#include <fmt/format.h>

#include "command.h"
#include "ido/core/error.h"
#include "ido/io/file_info.h"
#include "ido/io/mesh_io.h"
#include "ido/io/volume_io.h"

namespace ido::cli {
namespace {

struct ConvertOptions {
  std::string input;
  std::string output;
  bool ascii = false;
  bool big_endian = false;
  bool gmsh2 = false;
};

void run(const ConvertOptions& o) {
  const io::MeshWriteOptions w{.ascii = o.ascii, .big_endian = o.big_endian, .gmsh_v2 = o.gmsh2};
  const auto in_kind = io::file_kind(o.input);
  if (in_kind == io::FileKind::Volume) {
    if (io::is_triangle_mesh_path(o.output) || io::is_tet_mesh_path(o.output) || !io::looks_like_volume(o.output))
      throw InvalidInput(fmt::format("{}: a volume can only be converted to .nii, .nii.gz, .nrrd or .mha", o.output));
    io::VolumeFileInfo info;
    const auto vol = io::read_volume(o.input, &info);
    io::write_volume_as_stored(o.output, vol, info);
    return;
  }
  if (in_kind == io::FileKind::TetMesh) {
    if (!io::is_tet_mesh_path(o.output))
      throw InvalidInput(fmt::format("{}: a tetrahedral mesh can only be written as .vtu, .msh or .node/.ele", o.output));
    io::write_tet_mesh(o.output, io::read_tet_mesh(o.input), w);
    return;
  }
  if (!io::is_triangle_mesh_path(o.output) && std::filesystem::path(o.output).extension() != ".msh")
    throw InvalidInput(fmt::format("{}: a triangle mesh can only be written as .stl, .obj, .ply, .vtp or .msh", o.output));
  io::write_triangle_mesh(o.output, io::read_triangle_mesh(o.input), w);
}

void setup(CLI::App& app, const GlobalOptions& /*g*/) {
  auto* sub = app.add_subcommand("convert", "Convert a mesh or volume between file formats (by extension)");
  auto opts = std::make_shared<ConvertOptions>();
  sub->add_option("IN", opts->input, "Input file or DICOM folder")->required();
  sub->add_option("OUT", opts->output, "Output file; its extension picks the format")->required();
  sub->add_flag("--ascii", opts->ascii, "STL/PLY/VTK XML: write ASCII instead of binary");
  sub->add_flag("--big-endian", opts->big_endian, "binary PLY: big endian");
  sub->add_flag("--gmsh2", opts->gmsh2, ".msh: write version 2.2 instead of 4.1");
  sub->callback([opts] { run(*opts); });
}

const bool kRegistered = register_command({"convert", 11, setup});

}  // namespace
}  // namespace ido::cli

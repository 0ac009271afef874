// SPDX-License-Identifier: Apache-2.0
// `ido tetmesh --shape cube|cube12|block:SX,SY,SZ[,CELL] -o MESH.{vtu,msh,node}`: test meshes
// for drilling and simulation. Meshing a segmentation mask, a closed surface or a distance
// field (meshing::tetrahedralize) will arrive as an INPUT positional handled in
// mesh_from_options(); until then --shape is required.
#include <fmt/format.h>

#include "command.h"
#include "ido/core/error.h"
#include "ido/drill/shapes.h"
#include "ido/io/mesh_io.h"

namespace ido::cli {
namespace {

struct TetmeshOptions {
  std::string shape;   ///< "cube", "cube12", "block:SX,SY,SZ[,CELL]" (mm)
  std::string output;
};

// The mesh the options ask for. The INPUT branch (mask / surface / field → meshing) belongs
// here, next to the --shape branch.
geometry::TetMesh mesh_from_options(const TetmeshOptions& o) {
  if (o.shape.empty()) throw InvalidInput("tetmesh: give --shape cube|cube12|block:SX,SY,SZ[,CELL]");
  return drill::make_shape(o.shape);
}

void run(const TetmeshOptions& o) {
  if (!io::is_tet_mesh_path(o.output)) {
    throw InvalidInput(fmt::format("{}: the output must be .vtu, .msh or .node/.ele", o.output));
  }
  io::write_tet_mesh(o.output, mesh_from_options(o));
}

void setup(CLI::App& app, const GlobalOptions& /*g*/) {
  auto* sub = app.add_subcommand("tetmesh", "Make a tetrahedral mesh (test shapes: cube, cube12, block)");
  auto opts = std::make_shared<TetmeshOptions>();
  sub->add_option("--shape", opts->shape, "cube | cube12 (the paper's 12-tetrahedron cube) | block:SX,SY,SZ[,CELL] in mm");
  sub->add_option("-o,--output", opts->output, "Output mesh (.vtu, .msh, .node)")->required();
  sub->callback([opts] { run(*opts); });
}

const bool kRegistered = register_command({"tetmesh", 40, setup});

}  // namespace
}  // namespace ido::cli

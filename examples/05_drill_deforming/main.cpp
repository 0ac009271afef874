// SPDX-License-Identifier: Apache-2.0
// Example 05: drill a soft block while a sim::World (corotational FEM, implicit Euler)
// stretches it; the drilled detail follows the deforming roots through its embedding.
//   example_05_drill_deforming [OUTDIR]   → OUTDIR/deformed.vtu, OUTDIR/surface.vtp
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "ido/drill/boundary_surface.h"
#include "ido/drill/embedding.h"
#include "ido/drill/erosion.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/io/mesh_io.h"
#include "ido/sim/fem_corotational.h"
#include "ido/sim/world.h"

int main(int argc, char** argv) {
  using namespace ido;
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  std::filesystem::create_directories(out);

  const double sx = 12, sy = 8, sz = 6, stretch = 0.03, burr_mm = 1.2;
  const auto mesh = drill::make_block({sx, sy, sz}, 2.0);
  drill::TetHierarchy block(mesh);
  drill::BoundarySurface surface(block);
  drill::Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 4000});

  // The same mesh as a simulated body: clamped bottom, top face pulled up.
  sim::World world;
  world.add_tet_body(mesh, 1000.0);
  world.emplace_model<sim::CorotationalFem>(mesh.tets, world.particles().positions(), sim::ElasticMaterial{1e5, 0.0});
  world.set_integrator("implicit_euler");
  world.external().damping.mass_per_s = 5.0;
  std::vector<std::size_t> top;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (mesh.vertices[i].z() < 1e-9) world.particles().set_fixed(i, true);
    if (mesh.vertices[i].z() > sz - 1e-9) {
      world.particles().set_fixed(i, true);
      top.push_back(i);
    }
  }

  for (int step = 0; step <= 60; ++step) {
    const double e = stretch * std::min(1.0, step / 30.0);
    for (const auto i : top) world.particles().positions()[i].z() = sz * (1.0 + e);
    world.step(0.01);
    block.set_vertex_positions(world.particles().positions());  // the drilled detail follows
    eroder.erode(block, Vec3(6.2, 3.9, sz + 1.0 - 0.05 * step), burr_mm, 1.0, 0.01);
    surface.update(block, eroder.changed_nodes());
    eroder.clear_changed_roots();
  }
  (void)eroder.finish(block);
  surface.update(block, eroder.changed_nodes());
  eroder.clear_changed_roots();

  const auto statics = sim::solve_static(world);
  block.set_vertex_positions(world.particles().positions());
  const double removed_deformed = block.total_volume() - block.material_volume();
  io::write_tet_mesh(out / "deformed.vtu", drill::full_leaf_mesh(block));
  io::write_triangle_mesh(out / "surface.vtp", drill::assemble_surface(surface.v_lists(), block.vertices()));
  block.set_vertex_positions(mesh.vertices);
  const double removed_rest = block.total_volume() - block.material_volume();
  std::printf("static equilibrium: %s after %d Newton steps\n", statics.converged ? "converged" : "NOT converged",
              statics.newton_iterations);
  std::printf("removed volume: %.4f mm3 deformed, %.4f mm3 at rest, ratio %.6f (det F = %.6f)\n", removed_deformed,
              removed_rest, removed_deformed / removed_rest, 1.0 + stretch);
  std::printf("wrote %s and %s\n", (out / "deformed.vtu").string().c_str(), (out / "surface.vtp").string().c_str());
  return statics.converged ? 0 : 1;
}

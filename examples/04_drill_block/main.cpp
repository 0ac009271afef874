// SPDX-License-Identifier: Apache-2.0
// Example 04: drill a groove into a bone block with a scripted burr trajectory, through the
// same three threads (haptic, collision/erosion, render) as an interactive session.
//   example_04_drill_block [OUTDIR]   → OUTDIR/drilled.vtu, OUTDIR/surface.vtp
#include <cstdio>
#include <filesystem>
#include <vector>

#include "ido/drill/boundary_surface.h"
#include "ido/drill/embedding.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/shapes.h"
#include "ido/drill/simulator.h"
#include "ido/io/mesh_io.h"

int main(int argc, char** argv) {
  using namespace ido;
  const std::filesystem::path out = argc > 1 ? argv[1] : ".";
  std::filesystem::create_directories(out);

  // A 20 × 20 × 10 mm block of 2.5 mm cubes, 6 tetrahedra each: the roots of the hierarchy.
  drill::TetHierarchy bone(drill::make_block({20, 20, 10}, 2.5));

  // Keyframes (s, mm): come down onto the top face, cut 1.5 mm deep along x, lift off.
  std::vector<double> t{0.0, 0.2, 0.8, 1.0};
  std::vector<drill::ToolPose> poses(4);
  poses[0].position_mm = Vec3(5, 10, 13);
  poses[1].position_mm = Vec3(5, 10, 10.5);
  poses[2].position_mm = Vec3(15, 10, 10.5);
  poses[3].position_mm = Vec3(15, 10, 13);
  drill::ScriptedTrajectory device(t, poses);

  drill::SimulatorOptions options;
  options.tool.burr_radius_mm = 2.0;
  options.erosion.max_depth = 5;                  // leaves down to 2.5·√3 / 32 ≈ 0.14 mm
  options.erosion.removal_rate_mm3_per_s = 0.0;   // cut whatever the burr covers
  const double before = bone.material_volume();
  drill::Simulator session(bone, device, options);
  session.run();

  const auto& st = session.stats();
  std::printf("removed %.2f mm3 of %.1f; %zu nodes at %.1f bytes each; %zu haptic ticks, %zu missed 1 ms deadlines\n",
              before - bone.material_volume(), before, bone.node_count(), bone.bytes_per_node(), st.haptic_ticks,
              st.missed_deadlines);
  io::write_tet_mesh(out / "drilled.vtu", drill::full_leaf_mesh(bone));
  io::write_triangle_mesh(out / "surface.vtp", drill::assemble_surface(session.render_v_lists(), bone.vertices()));
  return 0;
}

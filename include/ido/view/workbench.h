// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "ido/core/math.h"
#include "ido/segment/organ.h"
#include "ido/view/segment_output.h"

namespace ido::view {

/// What `ido view` opens and how it runs.
struct WorkbenchOptions {
  /// Files to open: at most one volume (the CT of the Segment workspace), triangle surfaces,
  /// tetrahedral meshes (their boundary is drawn) and simulation scenes (their bodies).
  std::vector<std::filesystem::path> files;
  std::filesystem::path script;       ///< replay this event script (EventScript), then close
  std::filesystem::path screenshots;  ///< folder for the script's screenshots (created if missing)
  std::filesystem::path record;       ///< write the session's input events here on exit
  std::int64_t max_frames = 0;        ///< close after this many frames; 0 = no limit
  int width_px = 1280;                ///< window size (a script's own size wins)
  int height_px = 800;
  segment::Organ organ = segment::Organ::Generic;  ///< the Segment workspace's first organ choice
  std::vector<Index3> seed_voxels;    ///< seeds placed at start (voxel indices of the CT)
  SegmentOutputs segment_outputs;     ///< where Save (ctrl+s) in the Segment workspace writes the segmentation
  std::filesystem::path tet_output;   ///< where Save (ctrl+s) in the Mesh workspace writes the tetrahedra (.vtu .msh .node)
  double tet_edge_mm = 0.0;           ///< the Mesh workspace's first lattice spacing (mm); 0 = the surface's mean edge
  double burr_radius_mm = 2.0;        ///< the Drill workspace's spherical burr (mm)
  double drill_max_s = 60.0;          ///< longest drilling session (s)
  std::filesystem::path drill_path;   ///< where a drilling session's path is written when it ends (CSV for `ido drill --path`)
  std::filesystem::path drill_report; ///< where its figures are written when it ends (JSON)
  /// Deform workspace: written on exit, the grabbed particle's positions over the run (JSON).
  std::filesystem::path deform_log;
  bool quiet = false;                 ///< no messages on stdout
};

/// Runs the interactive workbench (GLFW window, OpenGL 3.3 core, Dear ImGui) until the window
/// is closed, the script ends or max_frames pass. Segmentation runs on worker threads
/// (SegmentSession); the frame loop never waits for it. See docs/viewer.md.
/// @throws ido::InvalidInput for unreadable options or files (naming them); ido::IoError as the
/// readers; ido::Error when no window can be opened (no display) or a scripted wait times out.
void run_workbench(const WorkbenchOptions& options);

}  // namespace ido::view

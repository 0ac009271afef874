// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/aabb.h"
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
  /// Stop points placed at start (voxel indices of the CT): the balloon's front does not pass
  /// them (segment::LeakControlOptions::stop_points_mm).
  std::vector<Index3> stop_voxels;
  /// The Segment workspace's first region of interest (world mm; segment::BalloonChoices::roi_mm):
  /// outside it the balloon deflates. Unset: none (one can be drawn on the slices).
  std::optional<geometry::Aabb> roi_mm;
  /// The Segment workspace's first bound on the organ's local radius (mm;
  /// segment::BalloonChoices::max_radius_mm). Unset: none.
  std::optional<double> max_radius_mm;
  SegmentOutputs segment_outputs;     ///< where Save (ctrl+s) in the Segment workspace writes the segmentation
  std::filesystem::path tet_output;   ///< where Save (ctrl+s) in the Mesh workspace writes the tetrahedra (.vtu .msh .node)
  double tet_edge_mm = 0.0;           ///< the Mesh workspace's first lattice spacing (mm); 0 = the surface's mean edge
  double burr_radius_mm = 2.0;        ///< the Drill workspace's spherical burr (mm)
  /// The tool's shaft (mm; 0 = none, else below the burr radius), along the tool's axis from the
  /// burr centre for 30 mm (drill::ToolOptions), turned with the tool's orientation.
  double shaft_radius_mm = 0.0;
  double drill_max_s = 60.0;          ///< longest drilling session (s)
  std::filesystem::path drill_path;   ///< where a drilling session's path is written when it ends (CSV for `ido drill --path`)
  std::filesystem::path drill_report; ///< where its figures are written when it ends (JSON)
  /// A path CSV (`ido drill --path`'s format) the Drill workspace replays (`p`); checked at start.
  std::filesystem::path drill_replay;
  /// UDP port (127.0.0.1) on which the Drill workspace's device bridge listens (`u`); 0 = any free port.
  int drill_udp_port = 0;
  /// Deform workspace: written on exit, the grabbed particle's positions over the run (JSON).
  std::filesystem::path deform_log;
  /// Instead of opening a window: render one picture of what was opened (the views of the
  /// first workspace, without the panel: Segment with a volume, else Scene) off-screen, with no
  /// display (EGL, Mesa's surfaceless platform), write it here as PNG and return. Seeds given
  /// at start are grown first, so the picture shows the finished balloon.
  std::filesystem::path snapshot;
  bool quiet = false;                 ///< no messages on stdout
};

/// The workbench's workspaces.
enum class Workspace : std::uint8_t { Segment, Scene, Mesh, Drill, Deform };

/// "segment", "scene", "mesh", "drill" or "deform".
[[nodiscard]] const char* workspace_name(Workspace workspace) noexcept;

/// One frame of a workbench run.
struct FrameRecord {
  Workspace workspace = Workspace::Scene;  ///< the workspace shown
  float ms = 0.0f;             ///< wall time of the frame loop's iteration (ms): input, panel, drawing, swap
  bool script_waiting = false; ///< a script's wait held the frame (the loop then also sleeps 10 ms)
  /// The 3-D view was drawn anew; false when nothing it shows changed and its last picture was
  /// copied (Scene, Segment, Mesh). Drill and Deform draw every frame.
  bool view_drawn = true;
};

/// What a workbench run measured.
struct WorkbenchStats {
  std::vector<FrameRecord> frames;  ///< every frame, in order
};

/// Runs the interactive workbench (GLFW window, OpenGL 3.3 core, Dear ImGui) until the window
/// is closed, the script ends or max_frames pass. Segmentation runs on worker threads
/// (SegmentSession); the frame loop never waits for it. See docs/viewer.md.
/// @throws ido::InvalidInput for unreadable options or files (naming them); ido::IoError as the
/// readers; ido::Error when no window can be opened (no display) or a scripted wait times out.
WorkbenchStats run_workbench(const WorkbenchOptions& options);

}  // namespace ido::view

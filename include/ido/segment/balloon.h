// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/core/progress.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/triangle_mesh.h"
#include "ido/image/volume.h"
#include "ido/segment/balloon_forces.h"
#include "ido/segment/intensity_model.h"
#include "ido/segment/leak_guard.h"
#include "ido/sim/particles.h"

namespace ido::segment {

/// Tunables of the balloon. Lengths in voxels are multiples of the smallest spacing h.
struct BalloonOptions {
  std::optional<double> reference;  ///< organ grey level; estimated at the seeds if unset
  std::optional<double> tolerance;  ///< accepted band half-width; estimated if unset
  IntensityEstimateOptions estimate;  ///< how to estimate what is unset
  bool accept_brighter = false;       ///< see IntensityModel::accept_brighter (bone)
  /// Edge stop (the "edge term" against leaks): inflation is scaled by
  /// 1 / (1 + (|∇I| / k)²) with k = edge_stop × tolerance / h, the classic edge-stopping
  /// function of geodesic active contours (Caselles, Kimmel & Sapiro, IJCV 1997), so the
  /// steep partial-volume rim of a much brighter or darker neighbour across a thin gap holds
  /// the surface. With accept_brighter (bone) only a fall of intensity along the outward
  /// normal counts (−∂I/∂n instead of |∇I|): a rise into the cortex is more bone. 0 disables it.
  double edge_stop = 0.75;
  double seed_radius_voxels = 1.0;    ///< initial icosphere radius (≈ 2 voxels across)
  double smoothing_sigma_voxels = 0.7;  ///< Gaussian pre-smoothing of the image (× h)
  double edge_length_voxels = 1.0;      ///< target edge length of the surface (× h)
  double step_voxels = 0.5;             ///< largest displacement per step (× h)
  BalloonForceWeights weights;          ///< inflation and curvature stiffness
  double tangential_weight = 0.3;       ///< tangential umbrella relaxation per step
  int remesh_interval = 3;              ///< refine every this many steps
  int intersection_interval = 10;       ///< look for (and repair) self-intersections every this many steps, in the edge stage too
  int max_iterations = 4000;            ///< safeguard
  double max_volume_mm3 = INFINITY;     ///< safeguard; reaching it raises the leak warning
  /// Safeguard on time: the inflation stops once it has moved this many vertices (awake vertex ×
  /// step, BalloonReport::inflation_vertex_steps), which bounds a flood the leak control did not
  /// stop to a few seconds (the shared scans need at most about 1 million). Reaching it raises the
  /// leak warning and skips the edge stage. 0 = no limit.
  std::int64_t max_inflation_work = 2'000'000;
  /// Optional region of interest (world mm, axis-aligned {min, max}): outside it the
  /// balloon deflates. A user safeguard, not the leak-stopping mechanism.
  std::optional<geometry::Aabb> roi_mm;
  /// Leak control: the territory the front may enter (chambers wider than the seed region,
  /// stop points, a radius bound, neighbour separation). See LeakGuard; on by default.
  LeakControlOptions leak;
  int convergence_window = 20;          ///< steps between volume comparisons
  double convergence_rel_volume = 2e-3; ///< converged when |ΔV| / V over a window is below
  bool edge_refinement = true;          ///< final snap to the wall (edge attraction)
  int edge_iterations = 30;             ///< steps of the edge stage
  double edge_search_voxels = 2.0;      ///< edge profile half-length (× h)
  /// How far (× h) the edge stage may take the surface from where the inflation left it: a
  /// move that would end farther than this from the inflated surface (its signed distance,
  /// computed once when the edge stage starts) and farther than the vertex already is, is not
  /// made. 0 = no limit (the default). Each edge step searches ±edge_search_voxels around the
  /// vertex's present position, so without a limit the surface can creep a search per step:
  /// along thin structures whose blurred interior the inflation's band rejects (the vessel
  /// tree phantom's 2-mm twigs), which is also how it follows a real vessel's distal branches
  /// past where a reference stops (ctpa). Measured: docs/segmentation.md.
  double edge_reach_voxels = 0.0;
  /// The level (image units, e.g. HU) of the tissue bounding the organ, for the edge stage:
  /// where the intensity beyond the wall goes on past this level (for a vessel: lung or fat
  /// past a wall of soft tissue too thin to resolve), the wall is placed half-way between the
  /// inside and this level rather than the far surroundings, i.e. at the lumen's boundary
  /// (edge_offset_along_normal). Unset (the default): the surroundings' own level. For CT
  /// vessels, soft tissue (about 40 HU) gives the lumen; leave it unset where the organ is
  /// meant to include its wall. It also caps an estimated tolerance at half the distance from
  /// the reference to this level, so the band does not take the bounding tissue.
  /// Measured: docs/segmentation.md.
  std::optional<double> outside_level;
  /// One-ring averaging passes of the wall offsets found by the edge stage. The per-vertex wall
  /// is noise-limited; 10 passes spread it over about a Gaussian of σ ≈ 2 edge lengths on the
  /// surface (each pass adds ≈ 3/7 ℓ² of variance per axis). Measured: docs/segmentation.md.
  int edge_offset_smoothing = 10;
  /// Where the profile beyond the wall is a valley (a brighter neighbour, bone or another
  /// vessel, a few voxels out), read the wall half-way to the surroundings' level (their
  /// median over the surface) rather than to the valley's floor, which the blur of both
  /// flanks raises (see edge_offset_along_normal). false = the floor, as before.
  bool valley_background = true;
  /// Angle (degrees) between two neighbours' normals at which a neighbour's offset counts 1/e
  /// in that averaging (weight exp(−(1 − n_a·n_b) / (1 − cos angle))), so the average does not
  /// reach across a sharp bend such as a 2-mm twig's tip. 0 = plain average. Measured:
  /// docs/segmentation.md.
  double edge_offset_bend_deg = 45.0;
  /// Per-vertex stop of the edge stage's profile search: a vertex that moved less than this
  /// (× h) and whose normal turned less than edge_reuse_turn_deg since its last search keeps
  /// the wall point found then (read along its present normal), for at most edge_reuse_steps
  /// steps in a row; a vertex still travelling to its wall is searched every step. 0 = search
  /// every vertex every step. Measured against 0 (BalloonReport::edge_profile_searches and
  /// edge_profile_reuses): about half the searches skipped, phantom Dice within ±0.0015.
  double edge_reuse_move_voxels = 0.15;
  double edge_reuse_turn_deg = 3.0;  ///< see edge_reuse_move_voxels (degrees)
  int edge_reuse_steps = 4;          ///< see edge_reuse_move_voxels
  /// Scanner blur (σ, × h) assumed when correcting the inward shift σ² H of the half-way
  /// level of a blurred curved wall (σ² = pre-smoothing² + this²; H the mean curvature).
  double scanner_blur_voxels = 0.7;
  /// Thin-layer wall model of the edge stage with accept_brighter (bone): the wall is the
  /// outer edge of the cortex from a three-plateau fit (PlateauProfileFitter: marrow, cortex,
  /// surroundings) whose blur along the normal is the pre-smoothing plus, along each grid
  /// axis a, the scanner blur (scanner_blur_voxels · s_a), the voxel's partial-volume box
  /// (variance s_a² / 12) and the trilinear sampling (≈ s_a² / 6), s_a the spacing. The half-way level between the profile's extremes
  /// puts a 1.5-mm cortex's wall about half a voxel outward (measured: docs/segmentation.md).
  bool plateau_wall = true;
  /// The thin-layer wall model needs a cortex the grid resolves: with a voxel larger than this
  /// (mm, its largest spacing) the half-way level is used instead (a 2–3 mm spine scan's cortex
  /// is a voxel or less, and the fit put the wall about a voxel outward there).
  double plateau_wall_max_voxel_mm = INFINITY;
  /// Active front while inflating (a narrow band on the surface, as a sparse-field level set
  /// updates only the band near its front): a vertex that moved less than sleep_move_voxels
  /// (× h) in each of the last sleep_steps steps, and none of whose one-ring neighbours moved
  /// more than that meanwhile, sleeps: it keeps its position, is not sampled, and the remesher
  /// leaves the edges between two sleepers alone. A neighbour that moves wakes it; a topology
  /// repair wakes every vertex. On a long vessel most of the surface has settled on the wall
  /// while the two ends still travel. Not used in the edge stage. 0 = every vertex every step.
  int sleep_steps = 10;
  double sleep_move_voxels = 0.02;  ///< see sleep_steps (× h)
  /// Local folds: when every intersecting pair found lies at most fold_rings edges apart on
  /// the surface (a vertex pushed through its neighbours, not two sheets meeting), the fold is
  /// smoothed out where it is, in at most fold_rounds rounds (the region growing by a ring each
  /// round), instead of rebuilding the whole surface; otherwise, or when it does not open, the
  /// vertices are frozen and the surface rebuilt (repair_topology) as before. 0 = always rebuild.
  int fold_rings = 2;
  int fold_rounds = 6;  ///< see fold_rings
  bool threaded = true;                 ///< oneTBB for the per-vertex work
};

/// What a balloon run did and what it produced.
struct BalloonReport {
  IntensityModel model;             ///< reference and tolerance used
  /// The bounding tissue's level the run used: BalloonOptions::outside_level, unset when none was
  /// given or when the organ's level lies within half its estimated tolerance of it (not set
  /// apart from that tissue: no contrast), where it is not used.
  std::optional<double> outside_level;
  std::int64_t iterations = 0;      ///< inflation + edge steps
  double seconds = 0;               ///< wall-clock time of the run
  /// Where the wall-clock time went (s): set-up (smoothing, gradient, intensity model), the
  /// steps' moves (forces and edge search), remeshing, self-intersection searches and
  /// topology repairs (signed distance, marching cubes and the remesh of the new surface).
  struct Phases {
    double setup = 0, move = 0, remesh = 0, intersections = 0, repair = 0;
  } phase_seconds;
  double volume_mm3 = 0, area_mm2 = 0;
  std::int64_t vertices = 0, edges = 0, triangles = 0, euler_characteristic = 0, components = 0;
  bool closed = false, manifold = false, oriented = false;
  std::int64_t self_intersections = 0;  ///< of the output (0 by construction)
  std::int64_t repairs = 0;             ///< topology repairs performed (surface rebuilt)
  std::int64_t local_repairs = 0;       ///< local folds smoothed out in place (BalloonOptions::fold_rings)
  std::int64_t frozen_vertices = 0;     ///< vertices frozen at intersections (cumulative)
  std::int64_t inflation_vertex_steps = 0;  ///< vertices moved while inflating (vertex × step)
  std::int64_t slept_vertex_steps = 0;      ///< vertices left asleep while inflating (vertex × step)
  std::int64_t edge_profile_searches = 0;  ///< edge-stage profile searches (vertex × step)
  std::int64_t edge_profile_reuses = 0;    ///< edge-stage steps where a vertex kept its last wall
  bool converged = false;
  bool leak_warning = false;  ///< the volume kept growing until a safeguard stopped it
  std::string stop_reason;    ///< "converged", "max_iterations", "max_volume" or "work_limit"
  /// Leak control: every place where the front pressed against a closed part of the band.
  std::vector<LeakEvent> leaks;
  double seed_radius_mm = 0;             ///< the seed region's radius (LeakGuard::seed_radius_mm)
  double chamber_radius_mm = INFINITY;   ///< radius past which the band is a chamber (infinity: none)
  std::vector<Vec3> neighbour_markers_mm;  ///< markers put in neighbouring bodies (separate_neighbours)
  std::vector<Vec3> stop_points_mm;        ///< the user's stop points of the run (LeakControlOptions)
  double max_radius_mm = INFINITY;         ///< the user's bound on the local radius (infinity: none)
};

/// Sets the mesh figures of @p report (volume, area, V/E/F, Euler characteristic, components,
/// closed / manifold / oriented flags) from @p check, and its self-intersection count.
void set_surface_figures(BalloonReport& report, const geometry::MeshCheckReport& check,
                         std::int64_t self_intersections);

/// A surface and its report.
struct BalloonResult {
  geometry::TriangleMesh surface;
  BalloonReport report;
};

/// The balloon of Turini et al. (2007): a small icosphere at each seed whose vertices are
/// sim::Particles, inflated along its normals by an intensity-matching force that turns into
/// deflation beyond the tolerance, held smooth by tangential umbrella relaxation and a
/// curvature stiffness (which stops it squeezing through 1–2-voxel necks), refined so edges
/// stay voxel-sized (meshing::SurfaceRemesher), with self-intersections found every few
/// steps, their vertices frozen, and the surface rebuilt through a signed distance map
/// (repair_topology), so it takes the organ's topology. Integration: explicit Euler on the
/// overdamped (first-order) equation of motion, v = F / γ, displacement capped at
/// step_voxels · h. After convergence an edge stage snaps the surface to the wall.
/// The caller may drive it step by step (step()) or call run().
class Balloon {
 public:
  /// @throws ido::InvalidInput when the volume is empty or thinner than 3 voxels along an axis, there is no seed, a seed lies
  /// outside the volume, or an option is out of range (tolerance ≤ 0, ...).
  Balloon(const image::Volume<float>& ct, const std::vector<Vec3>& seeds_mm, const BalloonOptions& options = {});
  Balloon(Balloon&&) noexcept;
  Balloon& operator=(Balloon&&) noexcept;
  ~Balloon();

  /// One inflation step (with refinement / intersection handling when due). Returns true
  /// once converged or stopped by a safeguard.
  bool step();
  /// Runs step() until it returns true, then the edge stage and a final repair that
  /// guarantees a closed, manifold, non-self-intersecting output.
  BalloonResult run(Progress* progress = nullptr);

  /// The particles that are the surface's vertices (positions mm, velocities mm/step).
  [[nodiscard]] const sim::Particles& particles() const;
  /// The current surface.
  [[nodiscard]] geometry::TriangleMesh surface() const;
  [[nodiscard]] const IntensityModel& model() const;

 private:
  struct State;
  std::unique_ptr<State> m;
};

/// One-call balloon segmentation. See Balloon.
[[nodiscard]] BalloonResult segment_balloon(const image::Volume<float>& ct, const std::vector<Vec3>& seeds_mm,
                                            const BalloonOptions& options = {}, Progress* progress = nullptr);

/// Binary mask (1 inside) of the balloon's closed surface on the grid of @p grid (same size,
/// spacing, origin, direction): meshing::voxelize, ido's one inside rule, so `ido segment
/// --mask` and `ido compare --mesh` count the same voxels. @throws ido::InvalidInput on an
/// empty grid, or as meshing::voxelize.
[[nodiscard]] image::Volume<std::uint8_t> surface_to_mask(const geometry::TriangleMesh& surface,
                                                          const image::Volume<float>& grid,
                                                          bool threaded = true);

/// An icosphere (subdivided icosahedron, vertices projected to the sphere): closed,
/// outward-oriented, 10·4^s + 2 vertices.
[[nodiscard]] geometry::TriangleMesh balloon_icosphere(const Vec3& centre_mm, double radius_mm, int subdivisions);

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"
#include "ido/segment/intensity_model.h"

namespace ido::segment {

/// Per-vertex differential quantities of a closed triangle surface that the balloon's
/// forces use.
struct SurfaceDifferentials {
  std::vector<Vec3> normals;         ///< unit outward normals (area-weighted average)
  std::vector<Vec3> umbrella_mm;     ///< L_i = mean of the one-ring − x_i (mm)
  std::vector<double> mean_edge2_mm2;  ///< mean squared length of the edges at i (mm²)
};

/// Computes normals, umbrella vectors and mean squared edge lengths of a closed, oriented
/// manifold surface in O(V + F). On such a surface each neighbour of i follows i exactly
/// once in its triangles, which is how the one-ring is gathered. With @p needed (one flag per
/// vertex) only the triangles with a needed corner are read: the needed vertices' values are
/// exact, the others' are left partial (the balloon's sleeping vertices do not use theirs).
[[nodiscard]] SurfaceDifferentials surface_differentials(const std::vector<Vec3>& positions_mm,
                                                         const std::vector<Tri>& triangles,
                                                         const std::vector<std::uint8_t>& needed = {});

/// Mean curvature (1/mm) estimated from the umbrella operator: on a sphere of radius R with
/// edge length ℓ the one-ring centroid lies ℓ²/(2R) inside the vertex, so
/// H ≈ −2 (L·n) / ℓ² (positive where the surface is convex; Desbrun et al., "Implicit
/// fairing of irregular meshes", SIGGRAPH 1999, for the umbrella operator).
[[nodiscard]] inline double umbrella_mean_curvature(const Vec3& umbrella_mm, const Vec3& normal,
                                                    double mean_edge2_mm2) noexcept {
  return mean_edge2_mm2 > 0 ? -2.0 * umbrella_mm.dot(normal) / mean_edge2_mm2 : 0.0;
}

/// Tangential part of the umbrella vector: moves a vertex towards the centre of its one-ring
/// within the tangent plane, evening the sampling without shrinking the surface.
[[nodiscard]] inline Vec3 tangential_umbrella(const Vec3& umbrella_mm, const Vec3& normal) noexcept {
  return umbrella_mm - normal * normal.dot(umbrella_mm);
}

/// Weights of the balloon's normal speed, in units of the smallest voxel spacing h per step.
struct BalloonForceWeights {
  double inflation = 1.0;  ///< × inflation_speed(I) (dimensionless speed in [−1, 1])
  /// Surface stiffness: the speed is reduced by curvature × h × H, so a front whose radius
  /// of curvature is below h · curvature / speed cannot advance: a 1–2-voxel neck stops it.
  double curvature = 0.6;
};

/// The balloon's normal speed (voxels per step, before the step size): inflation by
/// intensity match minus curvature stiffness, w_i · s(I) − w_c · h · H.
[[nodiscard]] inline double balloon_normal_speed(double intensity, double mean_curvature_per_mm,
                                                 double h_mm, const IntensityModel& model,
                                                 const BalloonForceWeights& w) noexcept {
  return w.inflation * inflation_speed(intensity, model) - w.curvature * h_mm * mean_curvature_per_mm;
}

/// Edge attraction by a profile search: samples @p smoothed along the normal at offsets
/// t ∈ [−search_mm, search_mm] (step step_mm) and returns the offset (mm) where the
/// departure from the reference, |I − reference|, rises fastest outward — the organ's wall,
/// which for a blurred step lies where the intensity is half-way between organ and
/// neighbour. Returns nothing when the strongest rise is below @p min_rise_per_mm
/// (intensity units per mm), i.e. when there is no wall within reach. The rise is measured
/// over @p window_mm (about a voxel; 0 = step_mm), see the implementation note.
/// @p background_departure (> 0) is the surroundings' departure from the reference seen
/// elsewhere: where the profile beyond the wall is a valley whose floor departs less (it
/// rises again by more than a tolerance: a brighter neighbour a few voxels out), the
/// half-way level is taken towards that, not towards the blur-raised floor. 0 = the floor.
/// @p outside_level (optional): the level of the tissue that bounds the organ (a vessel's
/// wall, soft tissue); where the profile goes on beyond it on the same side of the reference
/// (lung or fat past a wall too thin to resolve), the half-way level is taken towards this
/// level instead, so the wall found is the organ's own boundary, not the far side of its wall.
[[nodiscard]] std::optional<double> edge_offset_along_normal(const image::Volume<float>& smoothed,
                                                             const Vec3& point_mm, const Vec3& normal,
                                                             const IntensityModel& model, double search_mm,
                                                             double step_mm, double min_rise_per_mm,
                                                             double window_mm = 0.0, double background_departure = 0.0,
                                                             std::optional<double> outside_level = std::nullopt);

/// Direction in which the intensity profile along @p normal first leaves the accepted band,
/// walking outward from the innermost accepted sample within ±@p search_mm (samples every
/// @p step_mm): +1 upward (brighter than reference + tolerance), −1 downward, 0 when it does
/// not leave it (or never enters it). The majority over a surface tells on which side of the
/// band the organ's usual surroundings lie.
[[nodiscard]] int first_exit_direction(const image::Volume<float>& smoothed, const Vec3& point_mm,
                                       const Vec3& normal, const IntensityModel& model, double search_mm,
                                       double step_mm);

/// The wall model that knows a thin gap: limits a wall offset @p wall_mm found by
/// edge_offset_along_normal (which takes the steepest rise, possibly a neighbour's rim across
/// a 1-voxel gap) to the FIRST transition out of the accepted band, walking outward from the
/// innermost accepted sample. @p background_side is the usual direction of that exit (−1: the
/// surroundings are darker, as for contrast-filled vessels; +1 brighter; 0 disables). An exit
/// to the other side into a clearly different neighbour (reaching reference ± 2 tolerances:
/// bone beside a vessel) after a dip of at least 0.1 tolerance beyond the reference within
/// 0.75 search_mm before the exit (the blurred 1-voxel gap) caps the wall at the exit
/// (|I − reference| = tolerance, linear interpolation between samples). An exit to the usual
/// side followed by a return of more than one tolerance (a resolved dark valley between the
/// organ and a neighbour) caps it at the half-way crossing between the inside level and the
/// valley floor, so the wall never crosses a dark valley. Returns @p wall_mm otherwise, and
/// always when model.accept_brighter. Offsets in mm along the normal.
[[nodiscard]] double first_transition_limit(const image::Volume<float>& smoothed, const Vec3& point_mm,
                                            const Vec3& normal, const IntensityModel& model, double search_mm,
                                            double step_mm, double wall_mm, int background_side);

/// A profile along a normal read as three plateaus blurred by a known Gaussian: level
/// inside up to @p inner_mm, a middle level up to @p outer_mm, an outside level beyond.
struct PlateauFit {
  double inner_mm = 0.0;              ///< first transition (offset along the normal, mm)
  double outer_mm = 0.0;              ///< second transition, > inner_mm
  std::array<double, 3> levels{};     ///< inside, middle, outside (intensity units)
  double rms_residual = 0.0;          ///< root mean square misfit (intensity units)
};

/// Least-squares fit of a blurred three-plateau profile with a known blur σ:
///   I(t) = c (1 − Φ((t − a)/σ)) + m (Φ((t − a)/σ) − Φ((t − b)/σ)) + o Φ((t − b)/σ),
/// Φ the standard normal CDF, a < b the transitions and c, m, o the levels, to samples
/// I(t_k) at t_k = −reach + k · step (k = 0 … 2·reach/step). The levels are linear given
/// (a, b), so (a, b) are searched on a grid of candidate_step within ±search (b − a ≥
/// min_separation) and the levels solved exactly for each pair (variable projection; Golub
/// & Pereyra, SIAM J. Numer. Anal. 1973); everything that does not depend on the samples is
/// precomputed here. A thin layer whose level blur has lowered (a 1.5-mm cortex) is read at
/// its real edges, where the half-way level between the profile's extremes lies up to half a
/// voxel outward. The model has three levels: a fourth within reach (e.g. vessel, 1-voxel gap,
/// cortex, marrow) is absorbed into a middle level and misplaces the edges.
class PlateauProfileFitter {
 public:
  /// All lengths in mm. @throws ido::InvalidInput unless 0 < step, candidate_step, sigma and
  /// search + 2 σ ≤ reach.
  PlateauProfileFitter(double sigma_mm, double step_mm, double reach_mm, double search_mm, double candidate_step_mm,
                       double min_separation_mm);
  /// The same with samples at t = samples_mm[0] + k · step up to samples_mm[1], transitions
  /// searched within candidates_mm (both ranges in mm along the normal) and, when
  /// @p outer_sigma_mm > 0, that blur for the second transition (a neighbour's rim crossed
  /// obliquely). @throws ido::InvalidInput unless σ, the steps and the ranges are positive /
  /// non-empty.
  PlateauProfileFitter(double sigma_mm, double step_mm, const std::array<double, 2>& samples_mm,
                       const std::array<double, 2>& candidates_mm, double candidate_step_mm, double min_separation_mm,
                       double outer_sigma_mm = 0.0);
  /// Number of samples fit() expects.
  [[nodiscard]] std::size_t sample_count() const noexcept { return m_samples; }
  /// Offset (mm) of sample k along the normal.
  [[nodiscard]] double sample_offset_mm(std::size_t k) const noexcept;
  /// The best fit, or nothing when @p samples has the wrong size.
  [[nodiscard]] std::optional<PlateauFit> fit(const std::vector<double>& samples) const;

 private:
  struct Pair {
    int a = 0, b = 0;              // candidate indices
    std::array<double, 6> inv{};   // inverse of the 3×3 normal matrix (xx, xy, xz, yy, yz, zz)
  };
  std::size_t m_samples = 0;
  double m_step = 0, m_first = 0;
  std::vector<double> m_candidates;  // transition offsets (mm)
  std::vector<double> m_cdf;         // Φ((t_k − x_j)/σ), row j, column k
  std::vector<double> m_cdf_outer;   // the same with the second transition's σ; empty = m_cdf
  std::vector<Pair> m_pairs;
};

/// The organ's wall along @p normal from a three-plateau fit (PlateauProfileFitter) of the
/// smoothed profile at @p point_mm: walking outward, the first transition into a level
/// outside the accepted band (model), provided the inside level is accepted. Nothing when
/// the fit finds no such transition. Offset in mm along the normal.
[[nodiscard]] std::optional<double> plateau_wall_offset(const image::Volume<float>& smoothed, const Vec3& point_mm,
                                                        const Vec3& normal, const IntensityModel& model,
                                                        const PlateauProfileFitter& fitter);

/// The wall of an organ separated by a thin gap from a neighbour on the other side of the band
/// (bone beside a contrast-filled vessel): blur fills the gap with the neighbour's intensity,
/// so both the band's exit and the half-way level lie outside the real wall, and where the
/// blurred gap still dips below the band a dark-valley reading lies inside it. Fits the three
/// plateaus organ, gap, neighbour (PlateauProfileFitter, blur σ = @p sigma_mm for the organ's
/// wall, 1–2.2 σ for the neighbour's rim, which a ray usually crosses obliquely) to the
/// profile from 2 search_mm + 2σ inside the neighbour's rim (@p neighbour_mm, the steepest
/// rise found by edge_offset_along_normal) to one widened σ beyond it, transitions searched
/// within 2 search_mm inside the rim every step_mm / 2, the profile sampled every @p step_mm;
/// the far side of the neighbour (a cortex's marrow) is left out of the fit. Returns the fit's
/// first transition when it reads organ | gap | neighbour: inside level accepted, gap level
/// beyond the band on the side of the usual surroundings (@p background_side, see
/// first_transition_limit), neighbour level a further tolerance beyond it on the other side
/// (reference ± 2 tolerances, as first_transition_limit's cap), and a root mean square misfit
/// within 0.1 tolerance (about the pre-smoothed noise); nothing otherwise (a
/// plain wall, whose blurred flank a middle level can also fit). Offsets in mm along the
/// normal. One call builds the fitters; ThinGapWallModel keeps them for repeated use.
[[nodiscard]] std::optional<double> thin_gap_wall_offset(const image::Volume<float>& smoothed, const Vec3& point_mm,
                                                         const Vec3& normal, const IntensityModel& model,
                                                         int background_side, double sigma_mm, double search_mm,
                                                         double step_mm, double neighbour_mm);

/// thin_gap_wall_offset with its fitters built once (they do not depend on the profile).
class ThinGapWallModel {
 public:
  /// @throws ido::InvalidInput unless σ, search and step (mm) are positive.
  ThinGapWallModel(double sigma_mm, double search_mm, double step_mm);
  /// See thin_gap_wall_offset.
  [[nodiscard]] std::optional<double> wall_offset(const image::Volume<float>& smoothed, const Vec3& point_mm,
                                                  const Vec3& normal, const IntensityModel& model, int background_side,
                                                  double neighbour_mm) const;

 private:
  std::vector<PlateauProfileFitter> m_fitters;  // one per widening of the neighbour's blur
};

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"

namespace ido::segment {

/// What the balloon looks for: the grey level of the organ and how far from it a voxel may
/// be and still belong to it (both in the image's intensity units, e.g. HU).
struct IntensityModel {
  double reference = 0.0;  ///< organ grey level
  double tolerance = 1.0;  ///< half-width of the accepted band, > 0
  /// When true, anything brighter than the reference also matches (the band is
  /// [reference − tolerance, +∞)): for bone, whose cortex is far brighter than the marrow
  /// where the seed lies. Default: the paper's symmetric band.
  bool accept_brighter = false;
};

/// How far (intensity units) @p intensity departs from what @p model accepts as the organ:
/// |I − reference|, or max(0, reference − I) when accept_brighter.
[[nodiscard]] inline double intensity_departure(double intensity, const IntensityModel& model) noexcept {
  const double d = intensity - model.reference;
  return model.accept_brighter ? (d < 0 ? -d : 0.0) : (d < 0 ? -d : d);
}

/// Tunables of estimate_intensity_model().
struct IntensityEstimateOptions {
  double radius_mm = 0.0;           ///< ball around each seed; 0 = 2 × the largest spacing
  double tolerance_sigmas = 2.5;    ///< tolerance = this × robust σ (1.4826 · MAD)
  double min_tolerance_fraction = 0.05;  ///< lower bound: this × |reference|, so a flat
                                         ///< (noise-free) region still gets a usable band
  /// Second pass of the noise estimate (used when the caller passes the smoothed image,
  /// as the balloon does): within a ball this many times the first radius, the voxels whose
  /// smoothed value lies within half the first band of the reference and whose six
  /// neighbours do too (the organ's interior, away from the partial-volume rim) give the
  /// noise σ from the MAD of their residual raw − smoothed, scaled to white noise by the
  /// smoothing kernel. About 20 × the first ball's voxels, and the residual leaves out the
  /// organ's slow grey-level variations, so the tolerance spreads far less over noise
  /// draws than the first ball's MAD. The scaling assumes uncorrelated noise: in a real
  /// scan, whose noise is correlated over neighbouring voxels, the residual is smaller and
  /// the band too narrow (vmtk-aorta: 272 → 106, Dice within its section 0.95 → 0.75), so it
  /// does not replace the first pass by default (it is a floor under it, below);
  /// `ido segment --white-noise` makes it replace it (5). Measured:
  /// bench/results/segment-seeds.md. 0 = first pass only.
  double residual_ball_factor = 0.0;
  /// When residual_ball_factor is 0 (the default), the same residual pass in a ball this
  /// many times the first radius still runs, as a floor: the tolerance is at least
  /// residual_floor_fraction × the residual's. A seed ball whose MAD came out far below the
  /// organ's noise (one draw in twenty of the vein-in-parenchyma phantom: 15 HU where 2.5 σ
  /// is 38) no longer narrows the band until the front stalls in its own noise and floods
  /// past it. The fraction lets through the first pass's ordinary spread and lifts only
  /// estimates clearly too low; on a real scan, whose correlated noise makes the residual
  /// small, the first pass stays (the shared scans: bench/results/segment-seeds.md).
  /// 0 = no floor.
  double residual_floor_ball_factor = 5.0;
  double residual_floor_fraction = 0.8;  ///< see residual_floor_ball_factor
  std::size_t residual_min_voxels = 64;  ///< fewer interior voxels: keep the first pass
};

/// Estimates the reference as the median of the voxels within radius_mm of the seeds (all
/// seeds pooled) and the tolerance as tolerance_sigmas × 1.4826 × MAD (median absolute
/// deviation; Rousseeuw & Croux, JASA 1993) — robust against a seed placed near the wall.
/// @throws ido::InvalidInput when there is no seed, a seed lies outside the volume, or the
/// volume is empty.
[[nodiscard]] IntensityModel estimate_intensity_model(const image::Volume<float>& ct,
                                                      const std::vector<Vec3>& seeds_mm,
                                                      const IntensityEstimateOptions& options = {});

/// As above, then the residual second pass of IntensityEstimateOptions::residual_ball_factor
/// (or, when that is 0, the floor of residual_floor_ball_factor) on @p smoothed, which must
/// be @p ct smoothed by an isotropic Gaussian of @p smoothing_sigma_mm (gaussian_smooth's
/// default truncation) on the same grid.
/// @throws ido::InvalidInput also when @p smoothed is not on @p ct's grid.
[[nodiscard]] IntensityModel estimate_intensity_model(const image::Volume<float>& ct,
                                                      const std::vector<Vec3>& seeds_mm,
                                                      const IntensityEstimateOptions& options,
                                                      const image::Volume<float>& smoothed,
                                                      double smoothing_sigma_mm);

/// The balloon's inflation speed for a vertex seeing @p intensity: 1 − departure /
/// tolerance (see intensity_departure), clamped to [−1, 1]. Positive (inflate) inside the band, largest at the
/// reference, negative (deflate) beyond the tolerance on either side — the paper's force
/// "inversely related to the grey-level difference" (Turini et al. 2007).
[[nodiscard]] inline double inflation_speed(double intensity, const IntensityModel& model) noexcept {
  const double s = 1.0 - intensity_departure(intensity, model) / model.tolerance;
  return s > 1.0 ? 1.0 : (s < -1.0 ? -1.0 : s);
}

}  // namespace ido::segment

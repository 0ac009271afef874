// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <vector>

#include "ido/core/math.h"
#include "ido/image/volume.h"

/// Image filters on Volume<float>: Gaussian smoothing, gradients, robust statistics.
/// All of them are spacing-aware (sigmas and derivatives in world millimetres) and honour
/// the volume's direction matrix.
namespace ido::image {

/// Tunables of gaussian_smooth.
struct GaussianOptions {
  double truncate_sigmas = 4.0;  ///< kernel half-width, in standard deviations (≥ 1)
  bool threaded = true;          ///< run the separable passes with oneTBB
};

/// The 1D kernel gaussian_smooth uses along an axis: the Gaussian of @p sigma_vox voxels
/// sampled at the integers −half … half, half = max(1, ⌈truncate_sigmas · sigma_vox⌉),
/// normalised to sum 1 (index half is the centre).
[[nodiscard]] std::vector<float> gaussian_kernel(double sigma_vox, double truncate_sigmas);

/// Smooths @p volume with an isotropic Gaussian of standard deviation @p sigma_mm
/// (millimetres, world units), as three separable 1D convolutions along i, j, k whose
/// per-axis sigma in voxels is sigma_mm / spacing. Each 1D kernel is the sampled Gaussian
/// normalised to sum 1, so constants are preserved and mass is conserved away from the
/// border; the border is replicated (clamp). sigma_mm = 0 returns a copy.
/// @throws ido::InvalidInput if sigma_mm is negative or not finite.
[[nodiscard]] Volume<float> gaussian_smooth(const Volume<float>& volume, double sigma_mm,
                                            const GaussianOptions& options = {});

/// Smooths with an axis-aligned Gaussian whose standard deviation along the volume's i, j, k
/// axes is @p sigma_mm_per_axis (mm each); otherwise as above. A zero component skips that
/// axis. @throws ido::InvalidInput if a component is negative or not finite.
[[nodiscard]] Volume<float> gaussian_smooth(const Volume<float>& volume, const Vec3& sigma_mm_per_axis,
                                            const GaussianOptions& options = {});

/// The world-frame gradient (intensity units per mm) at every voxel: central differences
/// along i, j, k (one-sided on the border) divided by the spacing, then mapped to world
/// axes through the direction matrix (∇_world = (D·S)^{-T} ∇_index). Exact for a field
/// that is linear in world coordinates.
[[nodiscard]] Volume<Vec3f> gradient(const Volume<float>& volume, bool threaded = true);

/// |gradient| at every voxel (intensity units per mm), same scheme as gradient().
[[nodiscard]] Volume<float> gradient_magnitude(const Volume<float>& volume,
                                               bool threaded = true);

/// Robust location and spread of a sample.
struct RobustStats {
  double median = 0.0;      ///< median of the sample (intensity units)
  double mad = 0.0;         ///< median absolute deviation from the median, unscaled
  std::size_t count = 0;    ///< number of values used
  /// MAD scaled to estimate a normal standard deviation (1.4826 · MAD; Rousseeuw & Croux,
  /// "Alternatives to the median absolute deviation", JASA 1993).
  [[nodiscard]] double sigma() const noexcept { return 1.482602218505602 * mad; }
};

/// Median and MAD of @p values. @throws ido::InvalidInput if @p values is empty.
[[nodiscard]] RobustStats robust_stats(std::vector<double> values);

/// Median and MAD of the voxels whose centres lie within @p radius_mm of @p centre_mm
/// (world mm). The voxel nearest the centre is always included, so a radius smaller than a
/// voxel gives that voxel's value.
/// @throws ido::InvalidInput if the volume is empty, the radius negative, or the centre
///         farther than half a voxel outside the grid.
[[nodiscard]] RobustStats robust_stats_in_ball(const Volume<float>& volume, const Vec3& centre_mm,
                                               double radius_mm);

}  // namespace ido::image

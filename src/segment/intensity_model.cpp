// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/intensity_model.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "ido/core/error.h"
#include "ido/image/filters.h"
#include "ido/image/index_box.h"

namespace ido::segment {
namespace {

/// Standard deviation of z − G ∗ z for unit white noise z and the separable sampled kernel G
/// gaussian_smooth applies: Var = 1 − 2 g₀ + Σ g², with g₀ = Π_a g_a[centre] and
/// Σ g² = Π_a Σ g_a².
double residual_sigma_per_unit_noise(const Vec3& spacing, double sigma_mm) {
  double centre = 1.0, sum_sq = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double sigma_vox = sigma_mm / spacing[a];
    if (sigma_vox < 1e-3) continue;  // gaussian_smooth skips the axis
    const std::vector<float> g = image::gaussian_kernel(sigma_vox, image::GaussianOptions{}.truncate_sigmas);
    double sq = 0.0;
    for (float w : g) sq += double(w) * double(w);
    centre *= g[g.size() / 2];
    sum_sq *= sq;
  }
  return std::sqrt(std::max(0.0, 1.0 - 2.0 * centre + sum_sq));
}

/// The seed ball's radius (mm): radius_mm, or 2 × the largest spacing when it is 0.
double seed_ball_radius(const image::Volume<float>& ct, const IntensityEstimateOptions& options) {
  return options.radius_mm > 0 ? options.radius_mm : 2.0 * ct.spacing().maxCoeff();
}

/// The band's half-width for a noise σ: tolerance_sigmas × σ, bounded below by
/// min_tolerance_fraction × |reference| (and kept positive).
double tolerance_from_sigma(double sigma, double reference, const IntensityEstimateOptions& options) {
  return std::max({options.tolerance_sigmas * sigma, options.min_tolerance_fraction * std::abs(reference), 1e-6});
}

}  // namespace

IntensityModel estimate_intensity_model(const image::Volume<float>& ct, const std::vector<Vec3>& seeds_mm,
                                        const IntensityEstimateOptions& options) {
  if (ct.empty()) throw InvalidInput("intensity model: the volume is empty");
  if (seeds_mm.empty()) throw InvalidInput("intensity model: at least one seed is needed");
  const double radius = seed_ball_radius(ct, options);
  std::vector<double> values;
  for (const Vec3& s : seeds_mm) {
    const Vec3 idx = ct.world_to_index(s);
    for (int a = 0; a < 3; ++a)
      if (!(idx[a] >= -0.5 && idx[a] <= double(ct.size(a)) - 0.5))
        throw InvalidInput("seed (" + std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " +
                           std::to_string(s[2]) + ") mm lies outside the volume");
    // Gather the ball's voxels (the foundation's robust_stats_in_ball works per seed; the
    // seeds are pooled here).
    image::for_each_voxel_in_ball(ct, s, radius, [&](std::int64_t i, std::int64_t j, std::int64_t k) { values.push_back(ct(i, j, k)); });
    if (values.empty()) values.push_back(ct.sample(s));
  }
  const image::RobustStats stats = image::robust_stats(values);
  IntensityModel m;
  m.reference = stats.median;
  m.tolerance = tolerance_from_sigma(stats.sigma(), stats.median, options);
  return m;
}

IntensityModel estimate_intensity_model(const image::Volume<float>& ct, const std::vector<Vec3>& seeds_mm,
                                        const IntensityEstimateOptions& options, const image::Volume<float>& smoothed,
                                        double smoothing_sigma_mm) {
  IntensityModel m = estimate_intensity_model(ct, seeds_mm, options);
  const bool replace = options.residual_ball_factor > 0;
  const double factor = replace ? options.residual_ball_factor : options.residual_floor_ball_factor;
  if (!(factor > 0) || !(smoothing_sigma_mm > 0)) return m;
  if (!smoothed.same_grid(ct)) throw InvalidInput("intensity model: the smoothed image is not on the CT's grid");
  const double unit = residual_sigma_per_unit_noise(ct.spacing(), smoothing_sigma_mm);
  if (!(unit > 1e-3)) return m;
  // The first band's half: the interior of a vessel lies well inside it even where the
  // first tolerance came out low, and the blurred rim of the wall falls outside.
  const double keep = 0.5 * m.tolerance;
  const auto organ_like = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    return smoothed.contains(i, j, k) && std::abs(double(smoothed(i, j, k)) - m.reference) <= keep;
  };
  const double radius = factor * seed_ball_radius(ct, options);
  std::vector<double> residuals;
  for (const Vec3& s : seeds_mm)
    image::for_each_voxel_in_ball(ct, s, radius, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      if (!organ_like(i, j, k) || !organ_like(i - 1, j, k) || !organ_like(i + 1, j, k) || !organ_like(i, j - 1, k) ||
          !organ_like(i, j + 1, k) || !organ_like(i, j, k - 1) || !organ_like(i, j, k + 1))
        return;
      residuals.push_back(double(ct(i, j, k)) - double(smoothed(i, j, k)));
    });
  if (residuals.size() < options.residual_min_voxels) return m;
  const double sigma = image::robust_stats(std::move(residuals)).sigma() / unit;
  const double residual_tolerance = tolerance_from_sigma(sigma, m.reference, options);
  m.tolerance = replace ? residual_tolerance : std::max(m.tolerance, options.residual_floor_fraction * residual_tolerance);
  return m;
}

}  // namespace ido::segment

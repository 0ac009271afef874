// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/intensity_model.h"

#include <cmath>
#include <string>

#include "ido/core/error.h"
#include "ido/image/filters.h"

namespace ido::segment {

IntensityModel estimate_intensity_model(const image::Volume<float>& ct, const std::vector<Vec3>& seeds_mm,
                                        const IntensityEstimateOptions& options) {
  if (ct.empty()) throw InvalidInput("intensity model: the volume is empty");
  if (seeds_mm.empty()) throw InvalidInput("intensity model: at least one seed is needed");
  const double radius = options.radius_mm > 0 ? options.radius_mm : 2.0 * ct.spacing().maxCoeff();
  std::vector<double> values;
  for (const Vec3& s : seeds_mm) {
    const Vec3 idx = ct.world_to_index(s);
    for (int a = 0; a < 3; ++a)
      if (!(idx[a] >= -0.5 && idx[a] <= double(ct.size(a)) - 0.5))
        throw InvalidInput("seed (" + std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " +
                           std::to_string(s[2]) + ") mm lies outside the volume");
    // Gather the ball's voxels (the foundation's robust_stats_in_ball works per seed; the
    // seeds are pooled here).
    const Vec3 r_idx = (Vec3::Constant(radius).array() / ct.spacing().array()).matrix();
    const double rmax = r_idx.maxCoeff();
    for (std::int64_t k = std::int64_t(std::floor(idx[2] - rmax)); k <= std::int64_t(std::ceil(idx[2] + rmax)); ++k)
      for (std::int64_t j = std::int64_t(std::floor(idx[1] - rmax)); j <= std::int64_t(std::ceil(idx[1] + rmax)); ++j)
        for (std::int64_t i = std::int64_t(std::floor(idx[0] - rmax)); i <= std::int64_t(std::ceil(idx[0] + rmax)); ++i) {
          if (!ct.contains(i, j, k)) continue;
          if ((ct.index_to_world(Vec3(double(i), double(j), double(k))) - s).norm() > radius) continue;
          values.push_back(ct(i, j, k));
        }
    if (values.empty()) values.push_back(ct.sample(s));
  }
  const image::RobustStats stats = image::robust_stats(values);
  IntensityModel m;
  m.reference = stats.median;
  m.tolerance = std::max({options.tolerance_sigmas * stats.sigma(),
                          options.min_tolerance_fraction * std::abs(stats.median), 1e-6});
  return m;
}

}  // namespace ido::segment

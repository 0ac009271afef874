// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/balloon_forces.h"

#include <cmath>

namespace ido::segment {

SurfaceDifferentials surface_differentials(const std::vector<Vec3>& x, const std::vector<Tri>& triangles) {
  SurfaceDifferentials d;
  const std::size_t n = x.size();
  d.normals.assign(n, Vec3::Zero());
  d.umbrella_mm.assign(n, Vec3::Zero());
  d.mean_edge2_mm2.assign(n, 0.0);
  std::vector<int> count(n, 0);
  for (const Tri& t : triangles) {
    const Vec3 an = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = t[k], w = t[(k + 1) % 3];
      d.normals[v] += an;
      d.umbrella_mm[v] += x[w];
      d.mean_edge2_mm2[v] += (x[w] - x[v]).squaredNorm();
      ++count[v];
    }
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (count[v] == 0) continue;
    const double l = d.normals[v].norm();
    if (l > 0) d.normals[v] /= l;
    d.umbrella_mm[v] = d.umbrella_mm[v] / double(count[v]) - x[v];
    d.mean_edge2_mm2[v] /= double(count[v]);
  }
  return d;
}

std::optional<double> edge_offset_along_normal(const image::Volume<float>& smoothed, const Vec3& p,
                                               const Vec3& normal, const IntensityModel& model,
                                               double search_mm, double step_mm, double min_rise_per_mm,
                                               double window_mm) {
  // Rise over a window: (D(t + w/2) − D(t − w/2)) / w with D = |I − reference|. With a
  // window of about a voxel the rise of a trilinearly interpolated image is continuous and
  // peaked, so its maximum locates the wall to a fraction of a voxel (a one-sample
  // difference would be piecewise constant between voxel centres). A plateau of equal
  // maxima returns its middle.
  const int steps = static_cast<int>(std::ceil(search_mm / step_mm));
  const double w = window_mm > 0 ? window_mm : step_mm;
  // Profile value that rises outward across the wall: the departure from the reference,
  // or, when brighter tissue also belongs to the organ (bone), minus the intensity, so the
  // wall is the outer fall of intensity whatever lies between marrow and cortex.
  auto depart = [&](double t) {
    const double I = smoothed.sample(p + normal * t);
    return model.accept_brighter ? -I : intensity_departure(I, model);
  };
  double best = -INFINITY, first_t = 0, last_t = 0;
  for (int s = -steps; s <= steps; ++s) {
    const double t = s * step_mm;
    const double rise = (depart(t + 0.5 * w) - depart(t - 0.5 * w)) / w;
    if (s == -steps || rise > best + 1e-9 * std::abs(best)) {
      best = rise;
      first_t = last_t = t;
    } else if (rise >= best - 1e-9 * std::abs(best)) {
      last_t = t;
    }
  }
  if (!(best >= min_rise_per_mm)) return std::nullopt;
  // The rise of a trilinear image is piecewise constant between voxel centres, so its
  // maximum only brackets the wall to about a voxel. Refine to where the departure crosses
  // half-way between the inside level (least departure within the search inward of the
  // bracket) and the outside level (largest departure outward): the wall of a blurred step.
  // Levels are searched search_mm + window_mm away from the bracket.
  const double tc = 0.5 * (first_t + last_t);
  // The levels are read a window beyond the search, where a blurred step has levelled off.
  double d_in = INFINITY, d_out = -INFINITY;
  const int reach = steps + static_cast<int>(std::ceil(w / step_mm));
  for (int s = 0; s <= reach; ++s) {
    d_in = std::min(d_in, depart(tc - s * step_mm));
    d_out = std::max(d_out, depart(tc + s * step_mm));
  }
  const double half = 0.5 * (d_in + d_out);
  double prev_t = tc, prev_d = depart(tc);
  const double dir = prev_d > half ? -1.0 : 1.0;  // walk towards the crossing
  for (int s = 1; s <= 2 * steps; ++s) {
    const double t = tc + dir * s * step_mm;
    const double d = depart(t);
    if ((d - half) * (prev_d - half) <= 0.0) {
      const double f = prev_d != d ? (half - prev_d) / (d - prev_d) : 0.5;
      return prev_t + f * (t - prev_t);
    }
    prev_t = t;
    prev_d = d;
  }
  return tc;
}

}  // namespace ido::segment

// SPDX-License-Identifier: Apache-2.0
#include "ido/segment/balloon_forces.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ido/core/error.h"

namespace ido::segment {

SurfaceDifferentials surface_differentials(const std::vector<Vec3>& x, const std::vector<Tri>& triangles,
                                           const std::vector<std::uint8_t>& needed) {
  SurfaceDifferentials d;
  const std::size_t n = x.size();
  d.normals.assign(n, Vec3::Zero());
  d.umbrella_mm.assign(n, Vec3::Zero());
  d.mean_edge2_mm2.assign(n, 0.0);
  std::vector<int> count(n, 0);
  const bool all = needed.size() != n;
  for (const Tri& t : triangles) {
    if (!all && !needed[std::size_t(t[0])] && !needed[std::size_t(t[1])] && !needed[std::size_t(t[2])]) continue;
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

int first_exit_direction(const image::Volume<float>& smoothed, const Vec3& p, const Vec3& normal,
                         const IntensityModel& model, double search_mm, double step_mm) {
  const int steps = static_cast<int>(std::ceil(search_mm / step_mm));
  const double lo = model.reference - model.tolerance, hi = model.reference + model.tolerance;
  bool inside = false;
  for (int s = -steps; s <= steps; ++s) {
    const double v = smoothed.sample(p + normal * (s * step_mm));
    const bool accepted = v >= lo && v <= hi;
    if (accepted) inside = true;
    else if (inside) return v > hi ? 1 : -1;
  }
  return 0;
}

double first_transition_limit(const image::Volume<float>& smoothed, const Vec3& p, const Vec3& normal,
                              const IntensityModel& model, double search_mm, double step_mm, double wall_mm,
                              int background_side) {
  // The wall found by the steepest rise may belong to a neighbour across a thin gap (a bone's
  // steep rim one voxel beyond a vessel). The organ's own wall is on the FIRST transition out
  // of the accepted band, walking outward from the innermost accepted sample:
  //  - an exit to the unusual side (for a bright vessel: upward, into a much brighter neighbour
  //    such as bone, the blurred 1-voxel gap in between showing only as a shallow dip) caps the
  //    wall at the exit, where |I − reference| = tolerance;
  //  - a downward exit followed by a rise of more than a tolerance (a resolved dark valley
  //    between two bright structures) caps it at the half-way crossing between the inside
  //    level and the valley floor, so the wall never crosses a dark valley.
  if (background_side == 0 || model.accept_brighter) return wall_mm;
  // Work on J = σ·I with σ = −background_side, so the usual surroundings lie below the band.
  const double sg = background_side > 0 ? -1.0 : 1.0;
  const int steps = static_cast<int>(std::ceil(search_mm / step_mm));
  const double ref = sg * model.reference;
  const double lo = ref - model.tolerance, hi = ref + model.tolerance;
  thread_local std::vector<double> I;  // the profile; kept per thread (called per vertex and step)
  I.resize(static_cast<std::size_t>(2 * steps + 1));
  for (int s = -steps; s <= steps; ++s) I[std::size_t(s + steps)] = sg * smoothed.sample(p + normal * (s * step_mm));
  auto t_of = [&](std::size_t k) { return (double(k) - steps) * step_mm; };
  std::size_t k = 0;
  while (k < I.size() && !(I[k] >= lo && I[k] <= hi)) ++k;  // innermost accepted sample
  if (k == I.size()) return wall_mm;
  const std::size_t k_in = k;
  while (k < I.size() && I[k] >= lo && I[k] <= hi) ++k;
  if (k == I.size() || k == 0) return wall_mm;
  if (I[k] > hi) {
    // Only a clearly brighter neighbour (reaching a further tolerance beyond the band) counts;
    // a bright fluctuation of the organ itself does not.
    double peak = -INFINITY;
    for (std::size_t q = k; q < I.size(); ++q) peak = std::max(peak, I[q]);
    if (!(peak >= hi + model.tolerance)) return wall_mm;
    // ... and only across a gap: the profile dips below the reference (by a tenth of the
    // tolerance, about one σ of the pre-smoothed noise) within 0.75 search_mm (1.5 voxels by
    // default) before the exit. A bright deposit against the organ (no gap) is left alone.
    double dip = INFINITY;
    const auto reach = static_cast<std::size_t>(std::ceil(0.75 * search_mm / step_mm));
    for (std::size_t q = k > reach ? k - reach : 0; q < k; ++q) dip = std::min(dip, I[q]);
    if (!(dip <= ref - 0.1 * model.tolerance)) return wall_mm;
    const double f = (hi - I[k - 1]) / (I[k] - I[k - 1]);
    return std::min(wall_mm, t_of(k - 1) + f * step_mm);
  }
  // Downward exit: follow the valley to its floor, then require a real rise after it.
  std::size_t floor_k = k;
  for (std::size_t q = k; q < I.size(); ++q)
    if (I[q] < I[floor_k]) floor_k = q;
    else if (I[q] > I[floor_k] + model.tolerance) break;
  double peak_after = -INFINITY;
  for (std::size_t q = floor_k; q < I.size(); ++q) peak_after = std::max(peak_after, double(I[q]));
  if (!(peak_after > I[floor_k] + model.tolerance) || !(wall_mm > t_of(floor_k))) return wall_mm;
  // Half-way between the inside level (the brightest accepted sample before the exit, at
  // least the reference, at most the band's edge) and the valley floor.
  double inside = ref;
  for (std::size_t q = k_in; q < k; ++q) inside = std::max(inside, double(I[q]));
  inside = std::min(inside, hi);
  const double level = 0.5 * (inside + I[floor_k]);
  for (std::size_t q = k_in + 1; q <= floor_k; ++q)
    if (I[q] <= level && I[q - 1] > level) {
      const double f = (I[q - 1] - level) / (I[q - 1] - I[q]);
      return std::min(wall_mm, t_of(q - 1) + f * step_mm);
    }
  return std::min(wall_mm, t_of(floor_k));
}

std::optional<double> edge_offset_along_normal(const image::Volume<float>& smoothed, const Vec3& p,
                                               const Vec3& normal, const IntensityModel& model,
                                               double search_mm, double step_mm, double min_rise_per_mm,
                                               double window_mm, double background_departure,
                                               std::optional<double> outside_level) {
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
  // The window's inner end at step s is often, bit for bit, the outer end at step s − r
  // (w = r steps): that departure is reused, not sampled again (same offsets, same values).
  const int r = static_cast<int>(std::lround(w / step_mm));
  thread_local std::vector<double> outer_t, outer_d;  // outer end's offset and departure per step
  outer_t.resize(std::size_t(2 * steps + 1));
  outer_d.resize(std::size_t(2 * steps + 1));
  for (int s = -steps; s <= steps; ++s) {
    const double t = s * step_mm;
    const double t_out = t + 0.5 * w, t_in = t - 0.5 * w;
    const double d_out = depart(t_out);
    const std::size_t q = std::size_t(s + steps);
    outer_t[q] = t_out;
    outer_d[q] = d_out;
    const bool reuse = r >= 1 && s - r >= -steps && outer_t[q - std::size_t(r)] == t_in;
    const double d_in = reuse ? outer_d[q - std::size_t(r)] : depart(t_in);
    const double rise = (d_out - d_in) / w;
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
  // The walk to the crossing below reads the same offsets tc ± s·step (tc + (−x) rounds as
  // tc − x), so the departures read here are kept for it.
  double d_in = INFINITY, d_out = -INFINITY;
  const int reach = steps + static_cast<int>(std::ceil(w / step_mm));
  thread_local std::vector<double> inward, outward;  // departure at tc − s·step, tc + s·step
  inward.resize(std::size_t(reach) + 1);
  outward.resize(std::size_t(reach) + 1);
  int s_out = 0;  // where the outward departure peaks
  for (int s = 0; s <= reach; ++s) {
    inward[std::size_t(s)] = depart(tc - s * step_mm);
    outward[std::size_t(s)] = s == 0 ? inward[0] : depart(tc + s * step_mm);
    d_in = std::min(d_in, inward[std::size_t(s)]);
    if (outward[std::size_t(s)] > d_out) {
      d_out = outward[std::size_t(s)];
      s_out = s;
    }
  }
  if (background_departure > d_out && !model.accept_brighter) {
    // A valley: beyond its peak the departure falls back by more than a tolerance (a
    // brighter neighbour a few voxels out). Its floor, raised by the blur of both flanks,
    // is not the surroundings' level, and half-way to it lies inside the wall: the
    // surroundings' level seen elsewhere on the surface is used instead.
    double after = d_out;
    for (int s = s_out; s <= reach; ++s) after = std::min(after, outward[std::size_t(s)]);
    if (d_out - after > model.tolerance) d_out = background_departure;
  }
  if (outside_level && !model.accept_brighter) {
    // The organ's bounding tissue: the outside level goes no further than it on its side.
    const double beyond = smoothed.sample(p + normal * (tc + s_out * step_mm)) - model.reference;
    const double bound = *outside_level - model.reference;
    if (beyond * bound > 0) d_out = std::min(d_out, std::abs(bound));
  }
  const double half = 0.5 * (d_in + d_out);
  double wall = tc;
  {
    double prev_t = tc, prev_d = inward[0];
    const double dir = prev_d > half ? -1.0 : 1.0;  // walk towards the crossing
    const std::vector<double>& kept = dir < 0 ? inward : outward;
    for (int s = 1; s <= 2 * steps; ++s) {
      const double t = tc + dir * s * step_mm;
      const double d = s <= reach ? kept[std::size_t(s)] : depart(t);
      if ((d - half) * (prev_d - half) <= 0.0) {
        const double f = prev_d != d ? (half - prev_d) / (d - prev_d) : 0.5;
        wall = prev_t + f * (t - prev_t);
        break;
      }
      prev_t = t;
      prev_d = d;
    }
  }
  return wall;
}

PlateauProfileFitter::PlateauProfileFitter(double sigma_mm, double step_mm, double reach_mm, double search_mm,
                                           double candidate_step_mm, double min_separation_mm)
    : PlateauProfileFitter(sigma_mm, step_mm, {-reach_mm, reach_mm}, {-search_mm, search_mm}, candidate_step_mm,
                           min_separation_mm) {
  if (!(search_mm + 2.0 * sigma_mm <= reach_mm))
    throw InvalidInput("plateau profile fit: need search + 2σ ≤ reach");
}

PlateauProfileFitter::PlateauProfileFitter(double sigma_mm, double step_mm, const std::array<double, 2>& samples_mm,
                                           const std::array<double, 2>& candidates_mm, double candidate_step_mm,
                                           double min_separation_mm, double outer_sigma_mm) {
  if (!(outer_sigma_mm >= 0) || !(sigma_mm > 0) || !(step_mm > 0) || !(candidate_step_mm > 0) || !(samples_mm[0] < samples_mm[1]) ||
      !(candidates_mm[0] <= candidates_mm[1]))
    throw InvalidInput("plateau profile fit: need positive σ and steps and non-empty ranges");
  m_step = step_mm;
  m_first = samples_mm[0];
  m_samples = static_cast<std::size_t>(std::floor((samples_mm[1] - samples_mm[0]) / step_mm + 1e-9)) + 1;
  const auto c0 = static_cast<long>(std::ceil(candidates_mm[0] / candidate_step_mm - 1e-9));
  const auto c1 = static_cast<long>(std::floor(candidates_mm[1] / candidate_step_mm + 1e-9));
  for (long j = c0; j <= c1; ++j) m_candidates.push_back(double(j) * candidate_step_mm);
  const std::size_t nc = m_candidates.size();
  m_cdf.resize(nc * m_samples);
  for (std::size_t j = 0; j < nc; ++j)
    for (std::size_t k = 0; k < m_samples; ++k)
      m_cdf[j * m_samples + k] = 0.5 * std::erfc(-(sample_offset_mm(k) - m_candidates[j]) / (sigma_mm * std::sqrt(2.0)));
  if (outer_sigma_mm > 0 && outer_sigma_mm != sigma_mm) {
    m_cdf_outer.resize(nc * m_samples);
    for (std::size_t j = 0; j < nc; ++j)
      for (std::size_t k = 0; k < m_samples; ++k)
        m_cdf_outer[j * m_samples + k] =
            0.5 * std::erfc(-(sample_offset_mm(k) - m_candidates[j]) / (outer_sigma_mm * std::sqrt(2.0)));
  }
  const std::vector<double>& outer = m_cdf_outer.empty() ? m_cdf : m_cdf_outer;
  const auto min_sep = static_cast<std::size_t>(std::ceil(min_separation_mm / candidate_step_mm - 1e-9));
  for (std::size_t a = 0; a < nc; ++a)
    for (std::size_t b = a + std::max<std::size_t>(min_sep, 1); b < nc; ++b) {
      // Normal matrix of the basis (1 − Φa, Φa − Φb, Φb).
      double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
      for (std::size_t k = 0; k < m_samples; ++k) {
        const double pa = m_cdf[a * m_samples + k], pb = outer[b * m_samples + k];
        const double u = 1.0 - pa, v = pa - pb, w = pb;
        xx += u * u;
        xy += u * v;
        xz += u * w;
        yy += v * v;
        yz += v * w;
        zz += w * w;
      }
      const double c00 = yy * zz - yz * yz, c01 = xz * yz - xy * zz, c02 = xy * yz - xz * yy;
      const double det = xx * c00 + xy * c01 + xz * c02;
      const double scale = xx + yy + zz;
      if (!(det > 1e-9 * scale * scale * scale)) continue;  // a plateau the samples cannot see
      Pair p;
      p.a = static_cast<int>(a);
      p.b = static_cast<int>(b);
      p.inv = {c00 / det, c01 / det, c02 / det, (xx * zz - xz * xz) / det, (xy * xz - xx * yz) / det,
               (xx * yy - xy * xy) / det};
      m_pairs.push_back(p);
    }
}

double PlateauProfileFitter::sample_offset_mm(std::size_t k) const noexcept {
  return m_first + double(k) * m_step;
}

std::optional<PlateauFit> PlateauProfileFitter::fit(const std::vector<double>& samples) const {
  if (samples.size() != m_samples || m_pairs.empty()) return std::nullopt;
  // S_j = Σ_k Φ((t_k − x_j)/σ) I_k; the right-hand side of every pair is made of these.
  const std::size_t nc = m_candidates.size();
  thread_local std::vector<double> s, s_outer;  // projections, kept per thread
  s.assign(nc, 0.0);
  double total = 0, squares = 0;
  for (std::size_t k = 0; k < m_samples; ++k) {
    total += samples[k];
    squares += samples[k] * samples[k];
  }
  auto project = [&](const std::vector<double>& cdf, std::vector<double>& out) {
    for (std::size_t j = 0; j < nc; ++j) {
      const double* row = cdf.data() + j * m_samples;
      double acc = 0;
      for (std::size_t k = 0; k < m_samples; ++k) acc += row[k] * samples[k];
      out[j] = acc;
    }
  };
  project(m_cdf, s);
  s_outer.clear();
  if (!m_cdf_outer.empty()) {
    s_outer.resize(nc);
    project(m_cdf_outer, s_outer);
  }
  const std::vector<double>& so = m_cdf_outer.empty() ? s : s_outer;
  double best = INFINITY;
  const Pair* best_pair = nullptr;
  std::array<double, 3> best_levels{};
  for (const Pair& p : m_pairs) {
    const double r0 = total - s[std::size_t(p.a)], r1 = s[std::size_t(p.a)] - so[std::size_t(p.b)], r2 = so[std::size_t(p.b)];
    const auto& q = p.inv;
    const double c = q[0] * r0 + q[1] * r1 + q[2] * r2;
    const double m = q[1] * r0 + q[3] * r1 + q[4] * r2;
    const double o = q[2] * r0 + q[4] * r1 + q[5] * r2;
    const double sse = squares - (c * r0 + m * r1 + o * r2);  // least-squares residual
    if (sse < best) {
      best = sse;
      best_pair = &p;
      best_levels = {c, m, o};
    }
  }
  if (!best_pair) return std::nullopt;
  PlateauFit f;
  f.inner_mm = m_candidates[std::size_t(best_pair->a)];
  f.outer_mm = m_candidates[std::size_t(best_pair->b)];
  f.levels = best_levels;
  f.rms_residual = std::sqrt(std::max(best, 0.0) / double(m_samples));
  return f;
}

std::optional<double> plateau_wall_offset(const image::Volume<float>& smoothed, const Vec3& p, const Vec3& normal,
                                          const IntensityModel& model, const PlateauProfileFitter& fitter) {
  thread_local std::vector<double> samples;  // kept per thread (called per vertex and step)
  samples.resize(fitter.sample_count());
  for (std::size_t k = 0; k < samples.size(); ++k) samples[k] = smoothed.sample(p + normal * fitter.sample_offset_mm(k));
  auto accepted = [&](double level) { return intensity_departure(level, model) <= model.tolerance; };
  // A valley outward (a disc or a joint gap between two bones): the profile falls and rises
  // again by more than a tolerance, into the band, within the window. Three plateaus then
  // read the neighbour's bright plate as part of the surroundings and put the wall into the
  // gap (the vertebra-stack phantom's discs: 1.5 mm outward, against 0.5 mm for the half-way
  // level); the half-way level is left to stand.
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (fitter.sample_offset_mm(k) < 0) continue;
    lowest = std::min(lowest, samples[k]);
    if (samples[k] - lowest > model.tolerance && accepted(samples[k])) return std::nullopt;
  }
  const auto f = fitter.fit(samples);
  if (!f) return std::nullopt;
  if (!accepted(f->levels[0])) return std::nullopt;
  if (!accepted(f->levels[1])) return f->inner_mm;
  if (!accepted(f->levels[2])) return f->outer_mm;
  return std::nullopt;
}

ThinGapWallModel::ThinGapWallModel(double sigma_mm, double search_mm, double step_mm) {
  if (!(sigma_mm > 0) || !(search_mm > 0) || !(step_mm > 0))
    throw InvalidInput("thin gap wall model: σ, search and step must be positive");
  // The neighbour's rim is usually crossed obliquely (a bone beside a round vessel), which
  // widens its blurred step along the normal: its blur is searched too, 1–2.2 σ. Offsets are
  // relative to the rim: the organ's wall is searched up to two searches inside it.
  for (double widen : {1.0, 1.3, 1.7, 2.2})
    m_fitters.emplace_back(sigma_mm, step_mm, std::array<double, 2>{-(2.0 * search_mm + 2.0 * sigma_mm), widen * sigma_mm},
                           std::array<double, 2>{-2.0 * search_mm, 0.0}, 0.5 * step_mm, 2.5 * step_mm, widen * sigma_mm);
}

std::optional<double> ThinGapWallModel::wall_offset(const image::Volume<float>& smoothed, const Vec3& p,
                                                    const Vec3& normal, const IntensityModel& model,
                                                    int background_side, double neighbour_mm) const {
  if (background_side == 0) return std::nullopt;
  std::optional<PlateauFit> f;
  thread_local std::vector<double> samples;  // kept per thread (called per vertex and step)
  for (const PlateauProfileFitter& fitter : m_fitters) {
    samples.resize(fitter.sample_count());
    for (std::size_t k = 0; k < samples.size(); ++k)
      samples[k] = smoothed.sample(p + normal * (neighbour_mm + fitter.sample_offset_mm(k)));
    const auto g = fitter.fit(samples);
    if (g && (!f || g->rms_residual < f->rms_residual)) f = g;
  }
  if (!f) return std::nullopt;
  // The fit must read organ | gap | neighbour: the inside level accepted, the gap beyond the
  // band on the surroundings' side, the neighbour clearly beyond it (a further tolerance) on
  // the other side. A plain wall (whose blurred flank a middle level can also fit) is left to
  // the other wall models.
  const double bg = background_side > 0 ? 1.0 : -1.0;
  const auto& lv = f->levels;
  if (!(std::abs(lv[0] - model.reference) <= model.tolerance)) return std::nullopt;
  if (!((lv[1] - model.reference) * bg > model.tolerance)) return std::nullopt;
  if (!((lv[2] - model.reference) * bg < -2.0 * model.tolerance)) return std::nullopt;
  // ... and fit within the noise: the tolerance is 2.5 robust σ of the raw noise, which the
  // pre-smoothing (σ = 0.7 voxel) reduces about fourfold, so 0.1 tolerance is about one σ of
  // the smoothed profile. A profile the three plateaus do not explain is not read.
  if (!(f->rms_residual <= 0.1 * model.tolerance)) return std::nullopt;
  return neighbour_mm + f->inner_mm;
}

std::optional<double> thin_gap_wall_offset(const image::Volume<float>& smoothed, const Vec3& p, const Vec3& normal,
                                           const IntensityModel& model, int background_side, double sigma_mm,
                                           double search_mm, double step_mm, double neighbour_mm) {
  return ThinGapWallModel(sigma_mm, search_mm, step_mm).wall_offset(smoothed, p, normal, model, background_side,
                                                                     neighbour_mm);
}

}  // namespace ido::segment

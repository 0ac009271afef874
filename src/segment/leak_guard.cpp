// SPDX-License-Identifier: Apache-2.0
// The balloon's territory against leaks. Written by hand for ido: the opening by a ball uses
// the project's distance transform (meshing::distance_to_mask); the floods and the geodesic
// competition are plain breadth-first and Dijkstra passes over the voxel grid, for which no
// packaged library fits the balloon's band and masks without copying them into its types.
#include "ido/segment/leak_guard.h"

#include <algorithm>
#include <deque>
#include <functional>
#include <limits>
#include <queue>
#include <type_traits>

#include "ido/core/error.h"
#include "ido/core/statistics.h"
#include "ido/image/filters.h"
#include "ido/image/index_box.h"
#include "ido/meshing/distance_field.h"

namespace ido::segment {

const char* leak_cause_name(LeakCause cause) noexcept {
  switch (cause) {
    case LeakCause::Chamber: return "chamber";
    case LeakCause::StopPoint: return "stop_point";
    case LeakCause::Neighbour: return "neighbour";
    case LeakCause::None: break;
  }
  return "none";
}

namespace {

struct Grid {
  Index3 n;
  std::size_t at(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return std::size_t(i + n[0] * (j + n[1] * k));
  }
  Index3 ijk(std::size_t l) const {
    const auto q = std::int64_t(l);
    return {q % n[0], (q / n[0]) % n[1], q / (n[0] * n[1])};
  }
  bool inside(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < n[0] && j < n[1] && k < n[2];
  }
};

std::optional<std::size_t> voxel_of(const image::Volume<float>& v, const Grid& g, const Vec3& p) {
  const Vec3 idx = v.world_to_index(p);
  const auto i = std::int64_t(std::lround(idx[0])), j = std::int64_t(std::lround(idx[1])),
             k = std::int64_t(std::lround(idx[2]));
  if (!v.contains(i, j, k)) return std::nullopt;
  return g.at(i, j, k);
}

// Six-connected flood from @p starts through the voxels where @p open is nonzero.
std::vector<std::uint8_t> flood(const Grid& g, const std::vector<std::uint8_t>& open, const std::vector<std::size_t>& starts) {
  std::vector<std::uint8_t> reached(open.size(), 0);
  std::deque<std::size_t> queue;
  for (std::size_t s : starts)
    if (open[s] && !reached[s]) {
      reached[s] = 1;
      queue.push_back(s);
    }
  static constexpr int kStep[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!queue.empty()) {
    const std::size_t l = queue.front();
    queue.pop_front();
    const Index3 c = g.ijk(l);
    for (const auto& d : kStep) {
      const std::int64_t i = c[0] + d[0], j = c[1] + d[1], k = c[2] + d[2];
      if (!g.inside(i, j, k)) continue;
      const std::size_t q = g.at(i, j, k);
      if (open[q] && !reached[q]) {
        reached[q] = 1;
        queue.push_back(q);
      }
    }
  }
  return reached;
}

// Follows the inside distance uphill (26 neighbours) from @p l to a local maximum: the radius
// of the region around a point placed anywhere in it.
double ridge_radius(const Grid& g, const image::Volume<float>& inside, std::size_t l) {
  const std::vector<float>& d = inside.data();
  for (int guard = 0; guard < 10000; ++guard) {
    const Index3 c = g.ijk(l);
    std::size_t best = l;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const std::int64_t i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
          if (g.inside(i, j, k) && d[g.at(i, j, k)] > d[best]) best = g.at(i, j, k);
        }
    if (best == l) break;
    l = best;
  }
  return double(d[l]);
}

// The mean of the smoothed image over a disc of @p radius_mm across @p axis at @p p.
double disc_mean(const image::Volume<float>& v, const Vec3& p, const Vec3& axis, double radius_mm) {
  const Vec3 u = axis.unitOrthogonal(), w = axis.cross(u);
  double sum = v.sample(p);
  for (int q = 0; q < 8; ++q) {
    const double a = q * kPi / 4.0;
    sum += v.sample(p + radius_mm * (std::cos(a) * u + std::sin(a) * w));
  }
  return sum / 9.0;
}

}  // namespace

LeakGuard::LeakGuard(const image::Volume<float>& smoothed, const IntensityModel& model, const std::vector<Vec3>& seeds_mm,
                     const LeakControlOptions& o, const std::optional<geometry::Aabb>& roi_mm, bool threaded) {
  if (!(o.chamber_factor == 0 || (o.chamber_factor >= 1 && std::isfinite(o.chamber_factor))))
    throw InvalidInput("leak control: chamber_factor must be 0 (off) or a finite number >= 1");
  if (!(o.max_radius_mm > 0)) throw InvalidInput("leak control: max_radius_mm must be positive");
  if (!(o.neighbour_search_mm > 0 && std::isfinite(o.neighbour_search_mm)))
    throw InvalidInput("leak control: neighbour_search_mm must be a positive number");
  if (!o.enabled || smoothed.empty() || seeds_mm.empty()) return;
  const Grid g{smoothed.size()};
  const std::size_t n = smoothed.data().size();
  const double h = smoothed.spacing().minCoeff();
  for (const Vec3& p : o.stop_points_mm)
    if (!p.allFinite() || !voxel_of(smoothed, g, p))
      throw InvalidInput("leak control: a stop point lies outside the volume");

  // The band the balloon could fill, grown from the seeds.
  std::vector<std::uint8_t> band(n, 0);
  const std::vector<float>& I = smoothed.data();
  {
    // Noise punches single-voxel holes in a band that is one tolerance wide: the band is read
    // from its indicator smoothed over a voxel (σ = h) and taken above one half, which fills
    // such holes and drops isolated specks, so the region's inside distance measures its width.
    image::Volume<float> indicator = smoothed.like<float>(0.0f);
    for (std::size_t l = 0; l < n; ++l) indicator.data()[l] = intensity_departure(I[l], model) < model.tolerance ? 1.0f : 0.0f;
    indicator = image::gaussian_smooth(indicator, h, {.threaded = threaded});
    for (std::size_t l = 0; l < n; ++l) band[l] = indicator.data()[l] > 0.5f ? 1 : 0;
  }
  if (roi_mm)
    for (std::size_t l = 0; l < n; ++l) {
      if (!band[l]) continue;
      const Index3 c = g.ijk(l);
      const Vec3 p = smoothed.index_to_world(Vec3(double(c[0]), double(c[1]), double(c[2])));
      if (!roi_mm->contains(p)) band[l] = 0;
    }
  std::vector<std::size_t> starts;
  for (const Vec3& s : seeds_mm)
    if (const auto l = voxel_of(smoothed, g, s); l && band[*l]) starts.push_back(*l);
  if (starts.empty()) return;  // the seeds sit outside their own band: nothing to guard
  const std::vector<std::uint8_t> region = flood(g, band, starts);

  // Inside distance of the region (mm to the nearest voxel centre outside it). A region voxel's
  // nearest outside voxel lies in the region's index box grown by one voxel, so the transform
  // runs on that box only (the region is often a small part of the scan); it is 0 elsewhere.
  // The index box of a mask's nonzero voxels.
  const auto box_of = [&](const std::vector<std::uint8_t>& mask) {
    image::IndexBox b = image::IndexBox::none();
    for (std::size_t l = 0; l < n; ++l)
      if (mask[l]) b.extend(g.ijk(l));
    return b;
  };
  const image::IndexBox box = box_of(region).grown(1, g.n);
  // A grid-sized array's values over an index box, as a volume of the box's extent (the box's
  // lowest corner at index 0).
  const auto cut = [&](const image::IndexBox& b, const auto& values) {
    using T = std::decay_t<decltype(values[0])>;
    image::Volume<T> v(b.extent(), smoothed.spacing(), Vec3::Zero(), Mat3::Identity(), T{});
    b.for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) {
      v(i - b.lo[0], j - b.lo[1], k - b.lo[2]) = values[g.at(i, j, k)];
    });
    return v;
  };
  // The distance to a mask over the box, pasted into a grid-sized volume filled with @p fill.
  const auto distance_in_box = [&](const std::vector<std::uint8_t>& mask, float fill) {
    const image::Volume<float> d = meshing::distance_to_mask(cut(box, mask), {.threaded = threaded});
    image::Volume<float> full = smoothed.like<float>(fill);
    box.for_each([&](std::int64_t i, std::int64_t j, std::int64_t k) {
      full.data()[g.at(i, j, k)] = d(i - box.lo[0], j - box.lo[1], k - box.lo[2]);
    });
    return full;
  };
  std::vector<std::uint8_t> outside(n);
  for (std::size_t l = 0; l < n; ++l) outside[l] = region[l] ? 0 : 1;
  const image::Volume<float> inside = distance_in_box(outside, 0.0f);
  for (std::size_t s : starts) m_seed_radius_mm = std::max(m_seed_radius_mm, ridge_radius(g, inside, s));
  if (!std::isfinite(m_seed_radius_mm)) return;  // the band fills the whole grid: no scale to compare with

  std::vector<std::uint8_t> cause(n, 0);
  // A chamber of another grey level than the seed region's (a liver 15 HU darker than the vein
  // it wraps, where the band holds both): read on the image smoothed further, by two voxels or
  // a quarter of the seed region's radius if less (the vein phantom's noise: 1.0 HU there
  // against 4.4 on the balloon's image), the seed region's level and spread (in the ball of
  // half its radius around the seeds) and the chamber's median. When they lie more than four
  // spreads apart, the chamber's voxels nearer the seed's level are opened again: the vessel
  // goes on through the chamber's wrap, the chamber stays closed. Same-level chambers (a
  // ventricle past a valve) are left as they are. The smoothing runs on the region's box grown
  // by the kernel's reach, so the region's voxels see what the whole image would give them.
  const auto reopen_other_level = [&](std::vector<std::uint8_t>& closed) {
    const double sigma_mm = std::min(2.0 * h, 0.25 * m_seed_radius_mm);
    const image::IndexBox wb = box.grown(std::int64_t(std::ceil(4.0 * sigma_mm / h)) + 1, g.n);
    const image::Volume<float> wide = image::gaussian_smooth(cut(wb, I), sigma_mm, {.threaded = threaded});
    const auto W = [&](std::size_t l) {
      const Index3 c = g.ijk(l);
      return double(wide(c[0] - wb.lo[0], c[1] - wb.lo[1], c[2] - wb.lo[2]));
    };
    std::vector<double> seed_levels, chamber_levels;
    for (const Vec3& seed : seeds_mm)
      image::for_each_voxel_in_ball(smoothed, seed, 0.5 * m_seed_radius_mm, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        if (const std::size_t q = g.at(i, j, k); region[q]) seed_levels.push_back(W(q));
      });
    for (std::size_t l = 0; l < n; ++l)
      if (closed[l] == std::uint8_t(LeakCause::Chamber)) chamber_levels.push_back(W(l));
    if (seed_levels.empty() || chamber_levels.empty()) return;
    const image::RobustStats seed = image::robust_stats(std::move(seed_levels));
    const double seed_level = seed.median, chamber_level = median(std::move(chamber_levels));
    if (!(std::abs(seed_level - chamber_level) > 4.0 * seed.sigma())) return;
    for (std::size_t l = 0; l < n; ++l)
      if (closed[l] == std::uint8_t(LeakCause::Chamber) && std::abs(W(l) - seed_level) < std::abs(W(l) - chamber_level))
        closed[l] = 0;
  };
  // Chambers: the opening of the region by a ball of radius R.
  double R = o.chamber_factor > 0 ? o.chamber_factor * m_seed_radius_mm : INFINITY;
  R = std::max(std::min(R, o.max_radius_mm), h);
  if (std::isfinite(R)) {
    image::Volume<std::uint8_t> core = smoothed.like<std::uint8_t>(0);
    bool any = false;
    for (std::size_t l = 0; l < n; ++l)
      if (region[l] && inside.data()[l] > R) core.data()[l] = 1, any = true;
    if (any) {
      // The core lies in the region, so a region voxel's nearest core voxel lies in its box.
      const image::Volume<float> to_core = distance_in_box(core.data(), std::numeric_limits<float>::infinity());
      bool seed_in_chamber = false;
      for (std::size_t s : starts) seed_in_chamber |= to_core.data()[s] <= R;
      // A seed the opening covers is itself in a wide region (the user meant it): no chamber test.
      if (!seed_in_chamber) {
        m_chamber_radius_mm = R;
        for (std::size_t l = 0; l < n; ++l)
          if (region[l] && to_core.data()[l] <= R) cause[l] = std::uint8_t(LeakCause::Chamber);
        reopen_other_level(cause);
      }
    }
  }
  // Stop points: a ball of 1.5 × the local radius (at least 2 voxels) around each.
  for (const Vec3& p : o.stop_points_mm) {
    const std::size_t l = *voxel_of(smoothed, g, p);
    const double r = std::max(region[l] ? 1.5 * ridge_radius(g, inside, l) : 0.0, 2.0 * h);
    image::for_each_voxel_in_ball(smoothed, p, r, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
      if (const std::size_t q = g.at(i, j, k); region[q]) cause[q] = std::uint8_t(LeakCause::StopPoint);
    });
  }
  for (std::size_t s : starts) cause[s] = 0;  // a seed is never closed to its own balloon
  // What is reached from the seeds without crossing a closed voxel stays open; the rest of the
  // region lies beyond a closure and takes its cause.
  std::vector<std::uint8_t> open(n, 0);
  for (std::size_t l = 0; l < n; ++l) open[l] = region[l] && !cause[l] ? 1 : 0;
  std::vector<std::uint8_t> reach = flood(g, open, starts);
  const auto beyond = std::uint8_t(std::isfinite(m_chamber_radius_mm) ? LeakCause::Chamber : LeakCause::StopPoint);
  for (std::size_t l = 0; l < n; ++l)
    if (region[l] && !reach[l] && !cause[l]) cause[l] = beyond;

  if (o.separate_neighbours) {
    // The long axis: the grid axis nearest the world's z (LPS: inferior → superior).
    const Mat3& D = smoothed.direction();
    int ax = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(D(2, a)) > std::abs(D(2, ax))) ax = a;
    const Vec3 axis = D.col(ax).normalized();
    const double dt = 0.5 * h, disc_r = std::min(4.0, 0.25 * o.neighbour_search_mm);
    const Vec3 s0 = seeds_mm.front();
    const double depth = 0.3 * model.tolerance, look_mm = 15.0;
    const auto w = std::max<std::ptrdiff_t>(1, std::lround(h / dt));
    // The slab between two bodies along a direction d: a valley of the profile (averaged over a
    // disc across d) deeper than 0.3 tolerance below both the highest value before it (the
    // seed's end plate) and the highest within 15 mm after it (the neighbour's end plate, which
    // must lie in the band). A vertebral body is darker inside than at its end plates, so a seed
    // off its centre sees a dip of its own body (abdomen-spine L1 1.5 mm off the voxel seed: 34
    // HU deep, against 98 for the disc past it): the first valley at least half as deep as the
    // deepest one along d is the slab. The profile stops at the image's border, past which
    // nothing is known; where it descends into the border (its last sample the lowest of the
    // last 15 mm), the image ends in a valley whose far side is not seen: it cannot be a slab,
    // but its drop below the highest value before it takes part in "the deepest", so that the
    // seed's own shallower dips before it are not taken for a slab either (abdomen-dicom's
    // vertebra, its lower disc in the last two slices: a 19 HU dip in the body against the
    // disc's 116 HU drop, which cut the body in half). Returns {valley, that highest point
    // after it, depth} in mm along d, or depth < 0.
    struct Slab { double t_min = -1, t_back = -1, depth = -1; };
    auto find_slab = [&](const Vec3& d) {
      std::vector<double> prof;
      for (double t = 0; t <= o.neighbour_search_mm + look_mm; t += dt) {
        if (!voxel_of(smoothed, g, s0 + t * d)) break;
        prof.push_back(disc_mean(smoothed, s0 + t * d, d, disc_r));
      }
      if (prof.empty()) return Slab{};
      const auto m = std::ptrdiff_t(prof.size()), last = std::ptrdiff_t(o.neighbour_search_mm / dt);
      const auto ahead = std::ptrdiff_t(look_mm / dt);
      double p1 = prof[0];
      std::vector<Slab> found;
      for (std::ptrdiff_t i = 1; i <= last && i < m; ++i) {
        p1 = std::max(p1, prof[std::size_t(i)]);
        bool valley = true;
        for (std::ptrdiff_t q = std::max<std::ptrdiff_t>(0, i - w); q <= std::min(m - 1, i + w); ++q)
          valley = valley && prof[std::size_t(q)] >= prof[std::size_t(i)];
        if (!valley) continue;
        double p2 = -INFINITY;
        std::ptrdiff_t at = i;
        for (std::ptrdiff_t q = i; q <= std::min(m - 1, i + ahead); ++q)
          if (prof[std::size_t(q)] > p2) p2 = prof[std::size_t(q)], at = q;
        const double dep = std::min(p1, p2) - prof[std::size_t(i)];
        // The far side must be of the organ's grey level (another body, not soft tissue past fat).
        if (dep >= depth && intensity_departure(p2, model) < model.tolerance)
          found.push_back(Slab{double(i) * dt, double(at) * dt, dep});
      }
      double deepest = -1;
      for (const Slab& sl : found) deepest = std::max(deepest, sl.depth);
      if (m > 1 && m - 1 <= last) {  // the image's border lies within the search
        const double end = prof.back();
        bool descends = true;
        for (std::ptrdiff_t q = std::max<std::ptrdiff_t>(0, m - 1 - ahead); q < m; ++q)
          descends = descends && prof[std::size_t(q)] >= end;
        if (descends && p1 - end >= depth) deepest = std::max(deepest, p1 - end);
      }
      for (const Slab& sl : found)
        if (sl.depth >= 0.5 * deepest) return sl;
      return Slab{};
    };
    const Vec3 side = D.col((ax + 1) % 3).normalized(), front = D.col((ax + 2) % 3).normalized();
    std::vector<std::size_t> mine, neighbour_lines;  // marker voxels of the seed's body and of the neighbours'
    for (const double sign : {1.0, -1.0}) {
      // Up or down the axis; where no slab lies there, tilted by 15° and then 30° towards the
      // four sides (the spine's curvature: the lumbosacral disc faces forward and down), the
      // direction whose slab is deepest at the smallest tilt that has one.
      Slab best;
      Vec3 dir = sign * axis;
      for (const double deg : {0.0, 15.0, 30.0}) {
        for (const Vec3& toward : {side, Vec3(-side), front, Vec3(-front)}) {
          const double a = deg * kPi / 180.0;
          const Vec3 d = (std::cos(a) * sign * axis + std::sin(a) * toward).normalized();
          const Slab sl = find_slab(d);
          // A tilted slab must be a tolerance deep: eight more lines multiply the chances that the
          // marrow's own texture passes the axis's 0.3 tolerance (abdomen-dicom's vertebra, 2 mm
          // slices: dips of 16-25 HU in its body along four of them); the lumbosacral disc the
          // tilt is for lies 1.6 tolerances deep (abdomen-spine's L5).
          if (deg > 0.0 && sl.depth < model.tolerance) continue;
          if (sl.depth > best.depth) best = sl, dir = d;
          if (deg == 0.0) break;  // the axis itself once
        }
        if (best.depth >= 0) break;
      }
      const double t_min = best.t_min, t_back = best.t_back;
      if (t_min < 0) continue;
      // The markers are segments of the profile's line, not points, so the competition's border
      // crosses the bodies at the slab itself (two points would put it half-way between them):
      // the seed's side up to a voxel before the slab's valley, the neighbour's from a voxel past
      // it to 15 mm past its end plate.
      std::vector<std::size_t> theirs;
      for (double q = t_min + h; q <= t_back + look_mm; q += dt)
        if (const auto l = voxel_of(smoothed, g, s0 + q * dir); l && reach[*l]) theirs.push_back(*l);
      if (theirs.empty()) continue;
      for (double q = 0; q <= t_min - h; q += dt)
        if (const auto l = voxel_of(smoothed, g, s0 + q * dir); l && reach[*l]) mine.push_back(*l);
      neighbour_lines.insert(neighbour_lines.end(), theirs.begin(), theirs.end());
      const Index3 c = g.ijk(theirs[theirs.size() / 2]);
      m_markers.push_back(smoothed.index_to_world(Vec3(double(c[0]), double(c[1]), double(c[2]))));
    }
    if (!m_markers.empty()) {
      // Geodesic competition inside the open region: 26 neighbours, steps in mm, up to three
      // times longer through voxels darker than the reference (the discs and joint gaps between
      // two bodies, where the border belongs). Measured on abdomen-spine: L5 took 348 voxels of
      // S1 with plain steps, 211 with these (docs/segmentation.md).
      std::vector<float> dist(n, std::numeric_limits<float>::infinity());
      std::vector<std::uint8_t> owner(n, 0);
      using Item = std::pair<float, std::size_t>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
      auto push = [&](std::size_t l, std::uint8_t who) {
        if (!reach[l] || dist[l] == 0.0f) return;
        dist[l] = 0.0f;
        owner[l] = who;
        heap.emplace(0.0f, l);
      };
      for (std::size_t s : starts) push(s, 1);
      for (std::size_t l : mine) push(l, 1);
      for (std::size_t l : neighbour_lines) push(l, 2);
      const Vec3 sp = smoothed.spacing();
      // A vertebra lies within reach of its seed: past 3 x neighbour_search_mm of steps from every
      // marker nothing is the seed's (a bone band that takes in a whole MRA or a contrast scan's
      // vessels no longer has the competition visit all of it).
      const auto reach_mm = float(3.0 * o.neighbour_search_mm);
      while (!heap.empty()) {
        const auto [dl, l] = heap.top();
        heap.pop();
        if (dl > dist[l]) continue;
        if (dl > reach_mm) break;
        const Index3 c = g.ijk(l);
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const std::int64_t i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
              if ((di | dj | dk) == 0 || !g.inside(i, j, k)) continue;
              const std::size_t q = g.at(i, j, k);
              if (!reach[q]) continue;
              const double dark = std::clamp((model.reference - I[q]) / model.tolerance, 0.0, 1.0);
              const auto step = float((1.0 + 2.0 * dark) * std::sqrt(di * di * sp[0] * sp[0] + dj * dj * sp[1] * sp[1] + dk * dk * sp[2] * sp[2]));
              if (dl + step < dist[q]) {
                dist[q] = dl + step;
                owner[q] = owner[l];
                heap.emplace(dist[q], q);
              }
            }
      }
      for (std::size_t l = 0; l < n; ++l)
        if (reach[l] && (owner[l] == 2 || dist[l] > reach_mm)) cause[l] = std::uint8_t(LeakCause::Neighbour);
    }
  }
  // The balloon's vertices sit on the wall, half-way between band and surroundings, often in a
  // voxel just outside the band: close two layers of such voxels around the closed ones (but
  // none that touches the open band), so a held front cannot creep past a cap along the wall.
  // Only voxels next to a closed one can change: each layer visits the closed voxels' index box
  // grown by one more voxel.
  image::IndexBox near_closed = box_of(cause);
  for (int layer = 0; layer < 2 && !near_closed.empty(); ++layer) {
    near_closed = near_closed.grown(1, g.n);
    std::vector<std::uint8_t> grown = cause;
    near_closed.for_each([&](std::int64_t ci, std::int64_t cj, std::int64_t ck) {
      const std::size_t l = g.at(ci, cj, ck);
      if (region[l] || cause[l]) return;
      std::uint8_t from = 0;
      bool touches_open = false;
      for (int dk = -1; dk <= 1 && !touches_open; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const std::int64_t i = ci + di, j = cj + dj, k = ck + dk;
            if (!g.inside(i, j, k)) continue;
            const std::size_t q = g.at(i, j, k);
            if (region[q] && !cause[q]) touches_open = true;
            if (cause[q]) from = cause[q];
          }
      if (from && !touches_open) grown[l] = from;
    });
    cause = std::move(grown);
  }
  m_closed = smoothed.like<std::uint8_t>(0);
  m_closed.data() = std::move(cause);
}

LeakCause LeakGuard::cause_at(const Vec3& p_mm) const noexcept {
  if (m_closed.empty()) return LeakCause::None;
  const Vec3 idx = m_closed.world_to_index(p_mm);
  const auto i = std::int64_t(std::lround(idx[0])), j = std::int64_t(std::lround(idx[1])),
             k = std::int64_t(std::lround(idx[2]));
  if (!m_closed.contains(i, j, k)) return LeakCause::None;
  return LeakCause(m_closed(i, j, k));
}

}  // namespace ido::segment

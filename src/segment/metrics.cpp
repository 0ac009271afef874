// SPDX-License-Identifier: Apache-2.0
// Segmentation metrics; the project's own implementation. The squared Euclidean distance
// transform is the separable lower-envelope algorithm of Felzenszwalb & Huttenlocher,
// "Distance transforms of sampled functions", Theory of Computing 8 (2012).
#include "ido/segment/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/predicates.h"

namespace ido::segment {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// 1D squared distance transform of f (n samples, spacing w mm) into d, using scratch v, z.
void edt_1d(const double* f, double* d, std::size_t n, double w, std::vector<std::int64_t>& v,
            std::vector<double>& z) {
  v.resize(n);
  z.resize(n + 1);
  std::int64_t k = -1;  // index of the rightmost parabola of the lower envelope
  for (std::size_t q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    const double fq = f[q] + (w * double(q)) * (w * double(q));
    while (true) {
      if (k < 0) {
        k = 0;
        v[0] = std::int64_t(q);
        z[0] = -kInf;
        z[1] = kInf;
        break;
      }
      const std::size_t vk = std::size_t(v[std::size_t(k)]);
      const double fv = f[vk] + (w * double(vk)) * (w * double(vk));
      // Where the parabolas rooted at vk and q intersect, in index units.
      const double s = (fq - fv) / (2.0 * w * w * double(q - vk));
      if (s <= z[std::size_t(k)]) {
        --k;
        continue;
      }
      ++k;
      v[std::size_t(k)] = std::int64_t(q);
      z[std::size_t(k)] = s;
      z[std::size_t(k) + 1] = kInf;
      break;
    }
  }
  if (k < 0) {
    std::fill(d, d + n, kInf);
    return;
  }
  std::int64_t j = 0;
  for (std::size_t q = 0; q < n; ++q) {
    while (z[std::size_t(j) + 1] < double(q)) ++j;
    const double dq = w * (double(q) - double(v[std::size_t(j)]));
    d[q] = dq * dq + f[std::size_t(v[std::size_t(j)])];
  }
}

/// Squared distance (mm²) from every voxel of a box to the nearest feature voxel.
/// @p features: 1 where a feature lies; box size b, voxel spacing s.
std::vector<double> squared_edt(const std::vector<std::uint8_t>& features, const Index3& b, const Vec3& s) {
  const std::size_t n = features.size();
  std::vector<double> g(n);
  for (std::size_t i = 0; i < n; ++i) g[i] = features[i] ? 0.0 : kInf;
  const std::size_t stride[3] = {1, std::size_t(b[0]), std::size_t(b[0] * b[1])};
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t len = std::size_t(b[axis]);
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const std::size_t lines = std::size_t(b[a1] * b[a2]);
    parallel_for_ranges(
        lines,
        [&](std::size_t lb, std::size_t le) {
          std::vector<double> in(len), out(len), z;
          std::vector<std::int64_t> v;
          for (std::size_t l = lb; l < le; ++l) {
            const std::size_t u1 = l % std::size_t(b[a1]), u2 = l / std::size_t(b[a1]);
            const std::size_t base = u1 * stride[a1] + u2 * stride[a2];
            for (std::size_t q = 0; q < len; ++q) in[q] = g[base + q * stride[axis]];
            edt_1d(in.data(), out.data(), len, s[axis], v, z);
            for (std::size_t q = 0; q < len; ++q) g[base + q * stride[axis]] = out[q];
          }
        },
        true, 16);
  }
  return g;
}

/// Linear indices of inside voxels with an outside 6-neighbour or on the grid border.
std::vector<std::size_t> surface_voxels(const image::Volume<std::uint8_t>& m) {
  std::vector<std::size_t> out;
  const Index3 n = m.size();
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        if (!m(i, j, k)) continue;
        const bool border = i == 0 || j == 0 || k == 0 || i == n[0] - 1 || j == n[1] - 1 || k == n[2] - 1;
        if (border || !m(i - 1, j, k) || !m(i + 1, j, k) || !m(i, j - 1, k) || !m(i, j + 1, k) ||
            !m(i, j, k - 1) || !m(i, j, k + 1))
          out.push_back(m.linear_index(i, j, k));
      }
  return out;
}

/// Distances (mm) from each voxel of @p from to the nearest voxel of @p to, both given as
/// linear indices of a grid of size n and spacing s, via an EDT over their joint bounding box.
std::vector<double> directed_distances(const std::vector<std::size_t>& from, const std::vector<std::size_t>& to,
                                       const Index3& n, const Vec3& s) {
  if (from.empty()) return {};
  if (to.empty()) return std::vector<double>(from.size(), kInf);
  auto unpack = [&](std::size_t li) {
    return Index3{std::int64_t(li % std::size_t(n[0])), std::int64_t((li / std::size_t(n[0])) % std::size_t(n[1])),
                  std::int64_t(li / std::size_t(n[0] * n[1]))};
  };
  Index3 lo{n[0], n[1], n[2]}, hi{-1, -1, -1};
  for (const auto* set : {&from, &to})
    for (std::size_t li : *set) {
      const Index3 p = unpack(li);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], p[a]);
        hi[a] = std::max(hi[a], p[a]);
      }
    }
  const Index3 b{hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  auto local = [&](std::size_t li) {
    const Index3 p = unpack(li);
    return std::size_t((p[0] - lo[0]) + b[0] * ((p[1] - lo[1]) + b[1] * (p[2] - lo[2])));
  };
  std::vector<std::uint8_t> feat(std::size_t(b[0] * b[1] * b[2]), 0);
  for (std::size_t li : to) feat[local(li)] = 1;
  const std::vector<double> d2 = squared_edt(feat, b, s);
  std::vector<double> out(from.size());
  for (std::size_t m = 0; m < from.size(); ++m) out[m] = std::sqrt(d2[local(from[m])]);
  return out;
}

/// Nearest-rank percentile (p in (0, 1]) of a non-empty sample.
double percentile(std::vector<double> v, double p) {
  const std::size_t rank = std::size_t(std::ceil(p * double(v.size())));
  const auto it = v.begin() + std::ptrdiff_t(std::clamp<std::size_t>(rank, 1, v.size()) - 1);
  std::nth_element(v.begin(), it, v.end());
  return *it;
}

void require_nonempty(const image::Volume<std::uint8_t>& v, const char* what) {
  if (v.empty()) throw InvalidInput(std::string(what) + " volume is empty");
}

}  // namespace

int count_components(const image::Volume<std::uint8_t>& mask, Connectivity connectivity) {
  const Index3 n = mask.size();
  std::vector<std::uint8_t> seen(mask.voxel_count(), 0);
  std::vector<Index3> stack;
  std::vector<Index3> offsets;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int manhattan = std::abs(dx) + std::abs(dy) + std::abs(dz);
        if (manhattan == 0) continue;
        if (connectivity == Connectivity::Six && manhattan != 1) continue;
        offsets.push_back({dx, dy, dz});
      }
  int components = 0;
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        const std::size_t li = mask.linear_index(i, j, k);
        if (!mask.data()[li] || seen[li]) continue;
        ++components;
        seen[li] = 1;
        stack.push_back({i, j, k});
        while (!stack.empty()) {
          const Index3 p = stack.back();
          stack.pop_back();
          for (const Index3& o : offsets) {
            const std::int64_t x = p[0] + o[0], y = p[1] + o[1], z = p[2] + o[2];
            if (!mask.contains(x, y, z)) continue;
            const std::size_t q = mask.linear_index(x, y, z);
            if (mask.data()[q] && !seen[q]) {
              seen[q] = 1;
              stack.push_back({x, y, z});
            }
          }
        }
      }
  return components;
}

std::int64_t mask_euler_characteristic(const image::Volume<std::uint8_t>& mask) {
  const Index3 n = mask.size();
  auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> bool {
    return mask.contains(i, j, k) && mask(i, j, k) != 0;
  };
  std::int64_t v = 0, e = 0, f = 0, c = 0, h = 0;
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        // The 2×2×2 block with this voxel as its lowest corner; bit q = corner (q&1, q>>1&1, q>>2&1).
        unsigned block = 0;
        for (int q = 0; q < 8; ++q)
          if (at(i + (q & 1), j + ((q >> 1) & 1), k + ((q >> 2) & 1))) block |= 1u << q;
        if (!(block & 1u)) {
          // Only the loop correction can involve a block whose lowest corner is outside.
          if (block == (0xFFu & ~1u & ~0x80u)) ++h;
          continue;
        }
        ++v;
        e += ((block >> 1) & 1) + ((block >> 2) & 1) + ((block >> 4) & 1);
        f += ((block & 0x0Fu) == 0x0Fu) + ((block & 0x33u) == 0x33u) + ((block & 0x55u) == 0x55u);
        c += block == 0xFFu;
        // Two outside corners that are antipodal (q and 7 − q) and the other six inside.
        for (unsigned q = 1; q < 4; ++q)
          if (block == (0xFFu & ~(1u << q) & ~(1u << (7 - q)))) ++h;
      }
  return 2 * (v - e + f - c + h);
}

image::Volume<std::uint8_t> rasterize_mesh(const geometry::TriangleMesh& mesh, const image::GridGeometry& grid) {
  image::Volume<std::uint8_t> out(grid.size, grid.spacing_mm, grid.origin_mm, grid.direction, 0);
  if (out.empty() || mesh.triangles.empty()) return out;
  const std::int64_t nx = grid.size[0], ny = grid.size[1], nz = grid.size[2];
  const std::size_t nv = mesh.vertices.size();
  std::vector<Vec3> q(nv);
  for (std::size_t m = 0; m < nv; ++m) {
    if (!mesh.vertices[m].allFinite()) throw InvalidInput("rasterize_mesh: vertex coordinate is not finite");
    q[m] = out.world_to_index(mesh.vertices[m]);
  }
  const double handed = out.world_to_index_matrix().determinant() < 0.0 ? -1.0 : 1.0;
  // Bin triangles by the (j, k) rows their (y, z) bounding box may cover.
  const std::size_t rows = std::size_t(ny * nz);
  std::vector<std::size_t> start(rows + 1, 0);
  std::vector<std::array<std::int64_t, 4>> span(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Tri& tri = mesh.triangles[t];
    for (int c = 0; c < 3; ++c)
      if (tri[std::size_t(c)] < 0 || std::size_t(tri[std::size_t(c)]) >= nv)
        throw InvalidInput("rasterize_mesh: triangle " + std::to_string(t) + " has a vertex index out of range");
    double ylo = kInf, yhi = -kInf, zlo = kInf, zhi = -kInf;
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = q[std::size_t(tri[std::size_t(c)])];
      ylo = std::min(ylo, p.y());
      yhi = std::max(yhi, p.y());
      zlo = std::min(zlo, p.z());
      zhi = std::max(zhi, p.z());
    }
    auto& s = span[t];
    s = {std::max<std::int64_t>(0, std::int64_t(std::floor(ylo))), std::min<std::int64_t>(ny - 1, std::int64_t(std::ceil(yhi))),
         std::max<std::int64_t>(0, std::int64_t(std::floor(zlo))), std::min<std::int64_t>(nz - 1, std::int64_t(std::ceil(zhi)))};
    for (std::int64_t k = s[2]; k <= s[3]; ++k)
      for (std::int64_t j = s[0]; j <= s[1]; ++j) ++start[std::size_t(j + ny * k) + 1];
  }
  for (std::size_t r = 0; r < rows; ++r) start[r + 1] += start[r];
  std::vector<std::int32_t> bins(start[rows]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& s = span[t];
      for (std::int64_t k = s[2]; k <= s[3]; ++k)
        for (std::int64_t j = s[0]; j <= s[1]; ++j) bins[fill[std::size_t(j + ny * k)]++] = std::int32_t(t);
    }
  }
  // Side of the query point (py, pz) + (ε, ε²) w.r.t. the directed edge a→b in the (y, z)
  // plane, ±1 (Simulation of Simplicity, Edelsbrunner & Mücke 1990, for the point only). The edge is evaluated in a canonical vertex order so the two triangles
  // sharing it get exactly opposite answers.
  auto side = [](const Vec3& a0, const Vec3& b0, double py, double pz) -> int {
    const bool swap = (b0.y() < a0.y()) || (b0.y() == a0.y() && b0.z() < a0.z());
    const Vec3& a = swap ? b0 : a0;
    const Vec3& b = swap ? a0 : b0;
    const double ey = b.y() - a.y(), ez = b.z() - a.z();
    // Exact sign (adaptive predicate), so the triangles around a vertex partition the plane.
    const double o = geometry::orient2d(Vec2(a.y(), a.z()), Vec2(b.y(), b.z()), Vec2(py, pz));
    int sgn = o > 0 ? 1 : o < 0 ? -1 : 0;
    if (sgn == 0) sgn = ez != 0 ? (ez < 0 ? 1 : -1) : (ey > 0 ? 1 : ey < 0 ? -1 : 0);
    return swap ? -sgn : sgn;
  };
  parallel_for_ranges(
      rows,
      [&](std::size_t rb, std::size_t re) {
        std::vector<std::pair<double, int>> hits;
        for (std::size_t r = rb; r < re; ++r) {
          if (start[r] == start[r + 1]) continue;
          const double py = double(std::int64_t(r) % ny), pz = double(std::int64_t(r) / ny);
          hits.clear();
          for (std::size_t b = start[r]; b < start[r + 1]; ++b) {
            const Tri& tri = mesh.triangles[std::size_t(bins[b])];
            const Vec3 &a = q[std::size_t(tri[0])], &bb = q[std::size_t(tri[1])], &c = q[std::size_t(tri[2])];
            const int s0 = side(a, bb, py, pz), s1 = side(bb, c, py, pz), s2 = side(c, a, py, pz);
            if (s0 == 0 || s0 != s1 || s1 != s2) continue;
            // Barycentric weights from the unperturbed sub-areas; x of the crossing.
            const double wa = (c.y() - bb.y()) * (pz - bb.z()) - (c.z() - bb.z()) * (py - bb.y());
            const double wb = (a.y() - c.y()) * (pz - c.z()) - (a.z() - c.z()) * (py - c.y());
            const double wc = (bb.y() - a.y()) * (pz - a.z()) - (bb.z() - a.z()) * (py - a.y());
            const double sum = wa + wb + wc;
            const double x = sum != 0.0 ? (wa * a.x() + wb * bb.x() + wc * c.x()) / sum : (a.x() + bb.x() + c.x()) / 3.0;
            // s0 > 0: the triangle is counter-clockwise in (y, z), its normal has +x: leaving.
            hits.emplace_back(x, s0 > 0 ? -1 : 1);
          }
          if (hits.empty()) continue;
          std::sort(hits.begin(), hits.end());
          std::uint8_t* row = out.data().data() + r * std::size_t(nx);
          int winding = 0;
          std::size_t h = 0;
          for (std::int64_t i = 0; i < nx; ++i) {
            while (h < hits.size() && hits[h].first < double(i)) winding += hits[h++].second;
            row[i] = (winding * handed) != 0 ? 1 : 0;
          }
        }
      },
      true, 16);
  return out;
}

SegmentationScores compare_masks(const image::Volume<std::uint8_t>& mask_in, const image::Volume<std::uint8_t>& truth) {
  require_nonempty(mask_in, "mask");
  require_nonempty(truth, "truth");
  SegmentationScores s;
  image::Volume<std::uint8_t> resampled;
  const image::Volume<std::uint8_t>* mask = &mask_in;
  if (!mask_in.same_grid(truth)) {
    resampled = image::resample_nearest(mask_in, truth);
    mask = &resampled;
    s.resampled = true;
  }
  std::size_t both = 0;
  const auto& a = mask->data();
  const auto& b = truth.data();
  for (std::size_t n = 0; n < a.size(); ++n) {
    const bool in_a = a[n] != 0, in_b = b[n] != 0;
    s.voxels_mask += in_a;
    s.voxels_truth += in_b;
    both += in_a && in_b;
  }
  const double voxel_mm3 = truth.spacing().prod();
  s.volume_mask_mm3 = double(s.voxels_mask) * voxel_mm3;
  s.volume_truth_mm3 = double(s.voxels_truth) * voxel_mm3;
  const std::size_t total = s.voxels_mask + s.voxels_truth;
  s.dice = total == 0 ? 1.0 : 2.0 * double(both) / double(total);
  s.volume_ratio = s.voxels_truth == 0 ? (s.voxels_mask == 0 ? 1.0 : kInf)
                                       : double(s.voxels_mask) / double(s.voxels_truth);
  const auto sa = surface_voxels(*mask), sb = surface_voxels(truth);
  if (sa.empty() || sb.empty()) {
    const bool both_empty = sa.empty() && sb.empty();
    s.hd95_mm = s.assd_mm = s.hd_mm = both_empty ? 0.0 : kInf;
  } else {
    const auto dab = directed_distances(sa, sb, truth.size(), truth.spacing());
    const auto dba = directed_distances(sb, sa, truth.size(), truth.spacing());
    double sum = 0.0, mx = 0.0;
    for (double d : dab) sum += d, mx = std::max(mx, d);
    for (double d : dba) sum += d, mx = std::max(mx, d);
    s.assd_mm = sum / double(dab.size() + dba.size());
    s.hd_mm = mx;
    s.hd95_mm = std::max(percentile(dab, 0.95), percentile(dba, 0.95));
  }
  s.components_mask = count_components(*mask);
  s.components_truth = count_components(truth);
  return s;
}

SegmentationScores compare_mesh_to_mask(const geometry::TriangleMesh& mesh, const image::Volume<std::uint8_t>& truth) {
  require_nonempty(truth, "truth");
  // Only a closed surface has an inside: an open one rasterised to nothing (Dice 0, HD inf).
  const geometry::MeshCheckReport check = geometry::check_mesh(mesh);
  if (!check.closed)
    throw InvalidInput(check.triangles == 0 ? std::string("the surface has no triangles")
                                            : "the surface is not closed (" + std::to_string(check.boundary_edges) +
                                                  " boundary edges): only a closed surface has an inside to score");
  return compare_masks(rasterize_mesh(mesh, truth), truth);
}

}  // namespace ido::segment

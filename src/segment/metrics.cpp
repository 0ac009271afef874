// SPDX-License-Identifier: Apache-2.0
// Segmentation metrics; the project's own implementation. Surface distances use the
// project's one distance transform (meshing::distance_to_mask) and its one percentile.
#include "ido/segment/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/core/statistics.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/predicates.h"
#include "ido/image/index_box.h"
#include "ido/meshing/distance_field.h"
#include "ido/meshing/voxelize.h"

namespace ido::segment {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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
/// linear indices of a grid of size n and spacing s, via the distance transform over their joint bounding box.
std::vector<double> directed_distances(const std::vector<std::size_t>& from, const std::vector<std::size_t>& to,
                                       const Index3& n, const Vec3& s) {
  if (from.empty()) return {};
  if (to.empty()) return std::vector<double>(from.size(), kInf);
  auto unpack = [&](std::size_t li) {
    return Index3{std::int64_t(li % std::size_t(n[0])), std::int64_t((li / std::size_t(n[0])) % std::size_t(n[1])),
                  std::int64_t(li / std::size_t(n[0] * n[1]))};
  };
  image::IndexBox box = image::IndexBox::none();
  for (const auto* set : {&from, &to})
    for (std::size_t li : *set) box.extend(unpack(li));
  const Index3 &lo = box.lo, b = box.extent();
  auto local = [&](std::size_t li) {
    const Index3 p = unpack(li);
    return std::size_t((p[0] - lo[0]) + b[0] * ((p[1] - lo[1]) + b[1] * (p[2] - lo[2])));
  };
  image::Volume<std::uint8_t> feat(b, s, Vec3::Zero(), Mat3::Identity(), 0);
  for (std::size_t li : to) feat.data()[local(li)] = 1;
  const image::Volume<float> d = meshing::distance_to_mask(feat);
  std::vector<double> out(from.size());
  for (std::size_t m = 0; m < from.size(); ++m) out[m] = double(d.data()[local(from[m])]);
  return out;
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
  return compare_masks(meshing::voxelize(mesh, image::GridGeometry::of(truth)), truth);
}

}  // namespace ido::segment

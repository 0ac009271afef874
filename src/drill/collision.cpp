// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/collision.h"

#include <algorithm>
#include <array>
#include <span>

namespace ido::drill {

ContactModel collide(const TetHierarchy& hierarchy, const Tool& tool, const ToolPose& pose) noexcept {
  ContactModel m;
  m.position_mm = pose.position_mm;
  const Mat3 rot = pose.orientation.normalized().toRotationMatrix();
  const Vec3& c = pose.position_mm;
  Vec3 dir = Vec3::Zero();
  int inside = 0;
  std::int32_t hint = -1;  // the last root found (the shaft rings start from it)
  // On a Fibonacci sphere consecutive samples lie a golden angle apart; the nearest ones are
  // a Fibonacci number of indices apart (13, 21, 34 for 1000 samples), so the roots found
  // for those samples are tried first, then the previous sample's, then the hash.
  constexpr std::size_t kRecent = 64;
  std::array<std::int32_t, kRecent> recent;
  recent.fill(-1);
  const auto samples = tool.burr_samples();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Vec3& s = samples[i];
    const Vec3 p = c + rot * s;
    const std::array<std::int32_t, 4> hints{recent[(i + kRecent - 21) % kRecent], recent[(i + kRecent - 13) % kRecent],
                                            recent[(i + kRecent - 34) % kRecent], hint};
    const Location loc = hierarchy.locate(p, std::span<const std::int32_t>(hints));
    recent[i % kRecent] = loc.inside_mesh ? static_cast<std::int32_t>(loc.leaf.root) : -1;
    if (loc.inside_mesh) hint = static_cast<std::int32_t>(loc.leaf.root);
    if (loc.inside_mesh && loc.state == NodeState::Full) {
      ++inside;
      dir -= rot * s;  // centre − sample
    }
  }
  m.burr_samples_inside = inside;
  const double r = tool.burr_radius();
  double depth = 2.0 * r * inside / static_cast<double>(tool.burr_samples().size());
  const auto shaft = tool.shaft_samples();
  const int ring = tool.shaft_ring_size();
  if (ring > 0) {
    const double rs = tool.options().shaft_radius_mm;
    int best_ring = 0;
    for (std::size_t start = 0; start + static_cast<std::size_t>(ring) <= shaft.size(); start += static_cast<std::size_t>(ring)) {
      int in_ring = 0;
      for (std::size_t k = start; k < start + static_cast<std::size_t>(ring); ++k) {
        const Vec3 p = c + rot * shaft[k];
        const Location loc = hierarchy.locate(p, hint);
        if (loc.inside_mesh) hint = static_cast<std::int32_t>(loc.leaf.root);
        if (loc.inside_mesh && loc.state == NodeState::Full) {
          ++in_ring;
          const Vec3 radial(shaft[k].x(), shaft[k].y(), 0.0);
          dir -= rot * radial * (r / rs);  // same weight per sample as the burr's
        }
      }
      best_ring = std::max(best_ring, in_ring);
      m.shaft_samples_inside += in_ring;
    }
    depth = std::max(depth, 2.0 * rs * best_ring / static_cast<double>(ring));
  }
  if (m.burr_samples_inside + m.shaft_samples_inside == 0) return m;
  m.in_contact = true;
  m.depth_mm = depth;
  const double n = dir.norm();
  // A direction takes at least one sample's worth of asymmetry (weight r): the inward normals
  // of a whole Fibonacci sphere do not sum to zero (up to 0.21 r for 20 samples, 0.013 r for
  // 1000), so a fully buried burr would otherwise be pushed along that residue, sideways.
  if (n > 0.5 * r) {
    m.normal = dir / n;
  } else {
    m.normal = rot * Vec3::UnitZ();  // buried: push back along the shaft
  }
  return m;
}

}  // namespace ido::drill

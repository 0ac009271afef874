// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/tet_hierarchy.h"

namespace ido::drill {

/// How the burr removes material.
struct ErosionOptions {
  /// Pressing force (N) above which the burr cuts.
  double force_threshold_n = 0.2;
  /// Volume removed per second (mm³/s) at relative density 1 while cutting; a node of
  /// volume V in a root of relative density ρ costs V·ρ. ≤ 0: unlimited (everything the
  /// burr covers goes at once).
  double removal_rate_mm3_per_s = 40.0;
  /// Finest level (0 … kMaxDepth) used when min_size_mm is 0.
  int max_depth = 6;
  /// > 0: the finest level of each root is the first whose leaves' longest edge is
  /// ≤ min_size_mm (capped at kMaxDepth); overrides max_depth.
  double min_size_mm = 0.0;
};

/// What one erosion call did.
struct ErosionStats {
  double removed_volume_mm3 = 0.0;
  std::size_t nodes_removed = 0;
  std::size_t nodes_refined = 0;
  bool rate_limited = false;  ///< the volume budget ran out before the burr's region was done
};

/// Removes material covered by a spherical burr (Turini et al. 2007: nodes in contact are
/// eroded when the tool presses hard enough, partly covered nodes are refined down to a
/// minimum size). Per call: nodes entirely inside the sphere go whole; partly covered full
/// leaves are refined until the finest level, where a leaf goes when its centroid is inside
/// the sphere; a partly covered full leaf is refined only when a dry run on its derived
/// geometry finds a descendant that will go (so only the cut's boundary becomes fine, and
/// nothing is refined and then undone). The volume budget grows by removal_rate · dt while the pressing force is at
/// least the threshold (capped at 0.1 s worth) and carries over between calls.
class Eroder {
 public:
  /// @throws ido::InvalidInput for max_depth outside [0, kMaxDepth] or a negative size.
  explicit Eroder(const ErosionOptions& options = {});

  /// One erosion step with the burr centred at @p centre_mm of radius @p radius_mm.
  ErosionStats erode(TetHierarchy& hierarchy, const Vec3& centre_mm, double radius_mm, double pressing_force_n,
                     double dt_s);

  /// Roots whose nodes changed since the last clear_changed_roots() (each listed once).
  [[nodiscard]] const std::vector<std::uint32_t>& changed_roots() const noexcept { return m_changed; }
  /// Parallel to changed_roots(): bit f set when a changed node had a face on root face f
  /// (only then can the face neighbour's v_list change; see BoundarySurface::update).
  [[nodiscard]] const std::vector<std::uint8_t>& changed_root_faces() const noexcept { return m_changed_faces; }
  void clear_changed_roots() noexcept;

  /// Finest level used in root @p r.
  [[nodiscard]] int finest_level(const TetHierarchy& hierarchy, std::size_t r) const noexcept;
  [[nodiscard]] const ErosionOptions& options() const noexcept { return m_options; }
  /// Volume budget left (mm³ at density 1).
  [[nodiscard]] double budget() const noexcept { return m_budget; }

 private:
  bool process(TetHierarchy& h, const NodeRef& node, const std::array<Vec3, 4>& x, int finest,
               const std::array<std::int8_t, 4>& root_face, ErosionStats& stats);
  bool pay(double cost) noexcept;

  ErosionOptions m_options;
  Vec3 m_centre = Vec3::Zero();
  double m_radius = 0.0;
  double m_budget = 0.0;
  bool m_unlimited = false;
  std::vector<std::uint32_t> m_changed;
  std::vector<std::uint32_t> m_stamp;
  std::uint32_t m_epoch = 0;
  std::vector<std::uint32_t> m_candidates;
  std::vector<std::uint8_t> m_is_changed;
  std::vector<std::uint8_t> m_changed_faces;
  std::vector<std::uint32_t> m_slot;  // root → index in m_changed
  std::array<std::uint8_t, kMaxDepth + 1> m_face_mask{};  // root faces touched per level of the current path
};

}  // namespace ido::drill

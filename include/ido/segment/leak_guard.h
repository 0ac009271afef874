// SPDX-License-Identifier: Apache-2.0
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/aabb.h"
#include "ido/image/volume.h"
#include "ido/segment/intensity_model.h"

namespace ido::segment {

/// Tunables of the balloon's leak control (LeakGuard). Lengths in mm.
struct LeakControlOptions {
  bool enabled = true;  ///< false: no territory, the balloon goes wherever the band lets it
  /// Chambers: where a ball wider than this many times the seed region's own radius fits in
  /// the band (a heart chamber past an aortic valve, a liver around a vein, a lung around a
  /// seed placed in it), the front may not go: the band is opened by a ball of that radius
  /// and the opened part, with what lies only beyond it, is closed to the balloon. 0 = off.
  double chamber_factor = 2.5;
  /// The user's bound on the organ's local radius: where a ball of this radius fits in the
  /// band the front may not go (as a chamber). Infinity = no bound.
  double max_radius_mm = INFINITY;
  /// Points the front may not pass: each closes a ball of 1.5 × the local radius of the band
  /// there (at least 2 voxels) and whatever lies only beyond it.
  std::vector<Vec3> stop_points_mm;
  /// Neighbours of the same grey level stacked along the scanner's long axis (vertebrae
  /// separated by discs and facet joints): markers are put in the neighbouring bodies found
  /// past the darker slab above and below the seed, and the band is shared between the seed
  /// and them by geodesic distance inside it (the nearer marker takes a voxel).
  bool separate_neighbours = false;
  double neighbour_search_mm = 60.0;  ///< how far along the axis to look for a neighbour
};

/// Why a part of the band is closed to the balloon.
enum class LeakCause : std::uint8_t { None = 0, Chamber = 1, StopPoint = 2, Neighbour = 3 };

/// The name of @p cause as reports spell it: "chamber", "stop_point", "neighbour".
[[nodiscard]] const char* leak_cause_name(LeakCause cause) noexcept;

/// One place where the front pressed against a closed part of the band: a leak stopped.
struct LeakEvent {
  LeakCause cause = LeakCause::None;
  Vec3 position_mm = Vec3::Zero();  ///< centroid of the held vertices (world mm)
  std::int64_t iteration = 0;       ///< balloon step at which it was first seen
  double neck_area_mm2 = 0;         ///< area of the surface held there (largest seen)
  double neck_radius_mm = 0;        ///< radius of a disc of that area
};

/// The territory of a balloon: which voxels of the intensity band the front may enter, from
/// the seed region's own size (chambers), the user's stop points and radius bound, and
/// neighbour separation. Built once, before inflating, on the smoothed image the balloon
/// samples; blocks() is then a voxel look-up.
class LeakGuard {
 public:
  LeakGuard() = default;  ///< blocks nothing
  /// @p roi_mm optional box outside which the band is not grown.
  /// @throws ido::InvalidInput on a non-finite or negative option, or a stop point outside the volume.
  LeakGuard(const image::Volume<float>& smoothed, const IntensityModel& model, const std::vector<Vec3>& seeds_mm,
            const LeakControlOptions& options, const std::optional<geometry::Aabb>& roi_mm = {},
            bool threaded = true);

  [[nodiscard]] bool active() const noexcept { return !m_closed.empty(); }
  /// Why the voxel nearest @p p_mm is closed (None where the front may go or outside the grid).
  [[nodiscard]] LeakCause cause_at(const Vec3& p_mm) const noexcept;
  [[nodiscard]] bool blocks(const Vec3& p_mm) const noexcept { return cause_at(p_mm) != LeakCause::None; }
  /// The seed region's radius (mm): the inside distance of the band at the ridge nearest the seeds.
  [[nodiscard]] double seed_radius_mm() const noexcept { return m_seed_radius_mm; }
  /// The radius (mm) past which the band counts as a chamber (infinity when none).
  [[nodiscard]] double chamber_radius_mm() const noexcept { return m_chamber_radius_mm; }
  /// The neighbour markers found (world mm), for reports and pictures.
  [[nodiscard]] const std::vector<Vec3>& neighbour_markers_mm() const noexcept { return m_markers; }
  /// Per voxel the LeakCause (0 = open), on the smoothed image's grid; empty when inactive.
  [[nodiscard]] const image::Volume<std::uint8_t>& closed() const noexcept { return m_closed; }

 private:
  image::Volume<std::uint8_t> m_closed;
  double m_seed_radius_mm = 0, m_chamber_radius_mm = INFINITY;
  std::vector<Vec3> m_markers;
};

}  // namespace ido::segment

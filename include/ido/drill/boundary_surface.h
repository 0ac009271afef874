// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::drill {

/// Exact global identity of a point of the hierarchy: up to 4 (mesh vertex, weight) pairs
/// sorted by vertex, weights scaled by kBaryScale (summing to it), unused slots id = −1 at
/// the end. A point on a face shared by two roots has the same key from both sides.
struct PointKey {
  std::array<std::int32_t, 4> id{-1, -1, -1, -1};
  std::array<std::int32_t, 4> weight{0, 0, 0, 0};
  friend bool operator==(const PointKey&, const PointKey&) = default;
};

/// Global key of a root barycentric key of root @p r.
[[nodiscard]] PointKey point_key(const TetHierarchy& hierarchy, std::size_t r, const BaryKey& key) noexcept;
/// World position (mm) of a point key on the mesh vertices @p vertices_mm.
[[nodiscard]] Vec3 point_position(const PointKey& key, std::span<const Vec3> vertices_mm) noexcept;

/// A visible face, counter-clockwise seen from outside the material.
using SurfaceFace = std::array<PointKey, 3>;

/// The boundary surface of the remaining material (the paper's per-root v_list): for each
/// root, the faces of its full leaves that border erased material or the outside of the
/// mesh. Where the leaf across a face is refined deeper, the face is split (recursively,
/// following the neighbour's red refinement) and only the parts bordering erased material
/// are kept, so the surface has no cracks. assemble_surface() then splits edges at the
/// vertices of finer neighbours, so it has no T-junctions either.
class BoundarySurface {
 public:
  /// Builds every root's v_list.
  explicit BoundarySurface(const TetHierarchy& hierarchy);
  ~BoundarySurface();
  BoundarySurface(BoundarySurface&&) noexcept;
  BoundarySurface& operator=(BoundarySurface&&) noexcept;

  /// Rebuilds the v_lists of @p changed_roots and of their face neighbours (a change can
  /// expose a neighbour's face); the rebuilt roots are then in last_rebuilt().
  void update(const TetHierarchy& hierarchy, std::span<const std::uint32_t> changed_roots);
  /// As above, but the neighbour across root face f of changed_roots[i] is rebuilt only
  /// when bit f of @p changed_faces[i] is set (Eroder::changed_root_faces(): a changed node
  /// had a face on that root face), so untouched neighbours are not rebuilt.
  void update(const TetHierarchy& hierarchy, std::span<const std::uint32_t> changed_roots,
              std::span<const std::uint8_t> changed_faces);
  /// Rebuilds every v_list.
  void rebuild_all(const TetHierarchy& hierarchy);

  [[nodiscard]] std::size_t root_count() const noexcept { return m_faces.size(); }
  [[nodiscard]] const std::vector<SurfaceFace>& v_list(std::size_t r) const noexcept { return m_faces[r]; }
  [[nodiscard]] const std::vector<std::vector<SurfaceFace>>& v_lists() const noexcept { return m_faces; }
  [[nodiscard]] const std::vector<std::uint32_t>& last_rebuilt() const noexcept { return m_rebuilt; }
  /// Faces over all v_lists.
  [[nodiscard]] std::size_t face_count() const noexcept;

 private:
  void rebuild_root(const TetHierarchy& hierarchy, std::size_t r);

  std::vector<std::vector<SurfaceFace>> m_faces;
  std::vector<std::uint32_t> m_rebuilt;
  std::vector<std::uint8_t> m_mark;
  std::unique_ptr<struct AcrossCache> m_cache;  // scratch memo of face neighbours
};

/// The welded, crack-free triangle mesh (mm) of the faces in @p v_lists on mesh vertices
/// @p vertices_mm: a face edge holding vertices of finer faces is split at them and the
/// face is fanned from its centroid. Cell field "root" gives each triangle's root.
[[nodiscard]] geometry::TriangleMesh assemble_surface(std::span<const std::vector<SurfaceFace>> v_lists,
                                                      std::span<const Vec3> vertices_mm);

}  // namespace ido::drill

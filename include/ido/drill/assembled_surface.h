// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/boundary_surface.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::drill {

/// Options of AssembledSurface.
struct SurfaceAssemblyOptions {
  /// The 2-manifold split looks at every vertex's triangles; it lists them for a range of
  /// vertices at a time holding at most about this many triangle corners (4 bytes each), so a
  /// large surface is never doubled by that table. The result does not depend on it.
  std::size_t star_batch_corners = std::size_t(1) << 19;
};

/// The boundary surface of assemble_surface() held compactly, for writing large surfaces:
/// the same vertices, triangles and "root" field in the same order, but the vertices kept as
/// point keys (24 bytes; positions computed on request), the triangles in blocks (no growth
/// slack) and the root of each triangle as ranges. Assembling it takes the v_lists over and
/// frees each root's faces as soon as they are numbered, so the faces, the key index and the
/// triangles are never all held at once. Triangle t's vertices are in counter-clockwise order
/// seen from outside the material.
class AssembledSurface {
 public:
  /// Assembles the faces of @p v_lists (freed root by root) on the mesh vertices
  /// @p vertices_mm, which must outlive the surface.
  AssembledSurface(std::vector<std::vector<SurfaceFace>>&& v_lists, std::span<const Vec3> vertices_mm,
                   const SurfaceAssemblyOptions& options = {});
  /// The same from v_lists that stay with the caller.
  AssembledSurface(std::span<const std::vector<SurfaceFace>> v_lists, std::span<const Vec3> vertices_mm,
                   const SurfaceAssemblyOptions& options = {});
  ~AssembledSurface();
  AssembledSurface(AssembledSurface&&) noexcept;
  AssembledSurface& operator=(AssembledSurface&&) noexcept;

  [[nodiscard]] std::size_t vertex_count() const noexcept;
  [[nodiscard]] std::size_t triangle_count() const noexcept;
  /// Position (mm) of vertex @p i (< vertex_count()).
  [[nodiscard]] Vec3 vertex(std::size_t i) const noexcept;
  /// Vertex indices of triangle @p t (< triangle_count()).
  [[nodiscard]] const Tri& triangle(std::size_t t) const noexcept;
  /// Root tetrahedron of each triangle's face: calls @p f(root) for every triangle in order.
  template <class F>
  void for_each_triangle_root(F&& f) const {
    std::size_t t = 0;
    const auto& end = root_ends();
    for (std::size_t r = 0; r < end.size(); ++r)
      for (; t < end[r]; ++t) f(static_cast<std::uint32_t>(r));
  }
  /// The surface as a TriangleMesh: exactly assemble_surface()'s.
  [[nodiscard]] geometry::TriangleMesh to_mesh() const;
  /// Bytes held (keys, triangles, root ranges, face centres, vertex copies).
  [[nodiscard]] std::size_t memory_bytes() const noexcept;

 private:
  struct Data;
  template <class Release>
  void assemble(std::span<const std::vector<SurfaceFace>> v_lists, const SurfaceAssemblyOptions& options,
                Release&& release);
  [[nodiscard]] const std::vector<std::size_t>& root_ends() const noexcept;
  std::unique_ptr<Data> m;
};

}  // namespace ido::drill

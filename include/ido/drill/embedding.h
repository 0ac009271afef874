// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/leaf_mesh.h"  // full_leaf_mesh
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/image/volume.h"

namespace ido::drill {

/// A leaf embedded in its root: the leaf's vertices as root barycentric coordinates
/// (decoupling drilling from physics, Turini et al. 2007). Its world vertices are
/// Σ λ_i · x_root_i, so when a simulation moves the root mesh's vertices
/// (TetHierarchy::set_vertex_positions) the drilled detail follows.
struct LeafEmbedding {
  std::uint32_t root = 0;
  std::uint8_t depth = 0;
  std::array<std::array<double, 4>, 4> barycentric{};  ///< per leaf vertex, in TreeTable order
  bool flipped = false;                                ///< orientation opposite to the root's
};

/// Embeddings of every full leaf.
[[nodiscard]] std::vector<LeafEmbedding> full_leaf_embeddings(const TetHierarchy& hierarchy);

/// World position (mm) of barycentric coordinates @p lambda in root @p r.
[[nodiscard]] Vec3 embedded_position(const TetHierarchy& hierarchy, std::size_t r,
                                     const std::array<double, 4>& lambda) noexcept;

/// Relative density from Hounsfield units: (HU + 1000) / 1000 (water 1, air 0, dense
/// cortical bone ≈ 2–3), clamped to [0.05, 4].
[[nodiscard]] float density_from_hu(double hu) noexcept;

/// Sets each root's density from @p ct (HU) sampled trilinearly at the root's centroid.
void assign_density_from_ct(TetHierarchy& hierarchy, const image::Volume<float>& ct);

}  // namespace ido::drill

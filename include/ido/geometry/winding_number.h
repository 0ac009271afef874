// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/geometry/triangle_mesh.h"

namespace ido::geometry {

/// Tunables of WindingNumber.
struct WindingNumberOptions {
  /// Far-field criterion: a cluster of triangles is approximated when the query point is
  /// farther than beta × (cluster radius) from the cluster's centre. Larger is more
  /// accurate and slower; beta ≤ 0 disables the approximation (exact sum). Barill et al.
  /// use 2.
  double beta = 2.0;
  int leaf_size = 8;  ///< triangles per leaf of the hierarchy
};

/// The generalized winding number of a triangle mesh (Jacobson, Kavan & Sorkine-Hornung,
/// "Robust inside-outside segmentation using generalized winding numbers", SIGGRAPH 2013):
/// w(p) = Σ Ω_t(p) / 4π over the triangles, with Ω_t the signed solid angle of triangle t
/// seen from p (Van Oosterom & Strackee 1983). For a closed, outward-oriented surface w is 1
/// inside and 0 outside; for open or imperfect meshes it degrades gracefully.
///
/// Queries use a hierarchy (Barill, Dickson, Schmidt, Levin & Jacobson, "Fast winding
/// numbers for soups and clouds", SIGGRAPH 2018): a cluster far from the query contributes
/// through a Taylor expansion of its dipole field about the cluster's centre up to the
/// second derivative (area-weighted normals and their first and second moments, the
/// "order 2" expansion of that paper), so the error of a cluster falls as (radius /
/// distance)³; leaves near the query are summed exactly. The object copies what it
/// needs: the mesh may change or die afterwards. Queries are const and thread-safe.
class WindingNumber {
 public:
  /// @throws ido::InvalidInput for an index out of range or a non-finite coordinate.
  explicit WindingNumber(const TriangleMesh& mesh, const WindingNumberOptions& options = {});

  /// Winding number at @p p (dimensionless). On the surface itself the value is not
  /// defined; points on a triangle contribute 0 for that triangle.
  [[nodiscard]] double at(const Vec3& p) const;
  /// Winding numbers of many points, in parallel when @p threaded.
  [[nodiscard]] std::vector<double> at(const std::vector<Vec3>& points, bool threaded = true) const;
  /// The exact sum over every triangle, O(T) per query (for checks).
  [[nodiscard]] double exact_at(const Vec3& p) const;

 private:
  struct Node {
    Vec3 centre;                         // area-weighted centroid (mm)
    Vec3 normal_area;                    // Σ area · unit normal (mm²)
    Mat3 moment;                         // Σ area · (centroid − centre) ⊗ normal (mm³)
    std::array<Mat3, 3> second;          // [i] = ∫ nᵢ (x − centre)(x − centre)ᵀ dA (mm⁴)
    double radius = 0.0;                 // max distance from centre to a corner (mm)
    std::int32_t first = 0;              // leaf: first slot; inner: left child
    std::int32_t count = 0;              // leaf: slots; inner: 0
  };
  double node_sum(const Vec3& p) const;
  std::vector<Node> m_nodes;
  std::vector<std::array<Vec3, 3>> m_corners;  // by slot
  double m_beta;
};

/// Signed solid angle (steradians, in [−2π, 2π]) of triangle (a, b, c) seen from @p p,
/// positive when p lies on the side opposite the normal (b − a) × (c − a) — the convention
/// that makes the winding number of an outward-oriented closed surface +1 inside.
[[nodiscard]] double solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace ido::geometry

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>

namespace ido::drill {

/// The static table of Bey's regular ("red") refinement of a tetrahedron into 8 children
/// (the paper's TreeTable; J. Bey, "Tetrahedral grid refinement", Computing 55, 1995).
/// With parent vertices x0..x3 and xij the midpoint of xi and xj, the children are
///   C0=[x0,x01,x02,x03] C1=[x01,x1,x12,x13] C2=[x02,x12,x2,x23] C3=[x03,x13,x23,x3]
///   C4=[x01,x02,x03,x13] C5=[x01,x02,x12,x13] C6=[x02,x03,x13,x23] C7=[x02,x12,x13,x23]
/// (inner octahedron cut along x02–x13). C5 and C7 have the opposite orientation of their
/// parent; their vertex order is kept (reordering would break Bey's bound of 3 congruence
/// classes) and the flip is recorded as a parity bit.
///
/// Faces are numbered by the opposite vertex: face f of a tetrahedron is the triangle of
/// its vertices other than f.
struct TreeTable {
  /// Child vertex k of slot s is the midpoint of parent vertices vertex[s][k][0] and
  /// vertex[s][k][1] (equal indices: the parent vertex itself).
  std::array<std::array<std::array<std::uint8_t, 2>, 4>, 8> vertex{};
  /// 1 when the child's orientation is opposite to its parent's (C5, C7).
  std::array<std::uint8_t, 8> parity{};
  /// Integer matrix taking parent barycentric coordinates λ (Σλ = 1) to the child's:
  /// μ_k = Σ_j to_child[s][k][j] λ_j.
  std::array<std::array<std::array<std::int8_t, 4>, 4>, 8> to_child{};

  /// What lies across face f of child s inside its parent.
  struct FaceLink {
    std::int8_t sibling = -1;      ///< the sibling slot sharing the face, or -1
    std::int8_t sibling_face = -1; ///< the sibling's face index for that face
    std::int8_t parent_face = -1;  ///< when no sibling: the parent face the child face lies on
  };
  /// Child–child and child–parent-face adjacency: face_link[s][f].
  std::array<std::array<FaceLink, 4>, 8> face_link{};

  /// The unique table (computed once, on first use; thread-safe).
  [[nodiscard]] static const TreeTable& get();

  /// Point location (Bey's rule): the child slot containing a point of parent barycentric
  /// coordinates @p lambda. λk ≥ ½ selects corner child k; otherwise the point lies in the
  /// inner octahedron and the signs of (λ0−λ2)−(λ1−λ3) and (λ0−λ2)+(λ1−λ3) select C4..C7.
  [[nodiscard]] static int locate_child(const std::array<double, 4>& lambda) noexcept {
    for (int k = 0; k < 4; ++k) {
      if (lambda[static_cast<std::size_t>(k)] >= 0.5) return k;
    }
    const double d02 = lambda[0] - lambda[2];
    const double d13 = lambda[1] - lambda[3];
    const bool a = d02 - d13 >= 0.0;  // side of the plane through x01, x02, x13, x23
    const bool b = d02 + d13 >= 0.0;  // side of the plane through x02, x03, x12, x13
    if (a && b) return 4;
    if (!a && b) return 5;
    if (a && !b) return 6;
    return 7;
  }

  /// Parent barycentric coordinates → child slot @p s barycentric coordinates (exact up to
  /// one rounding per term: the matrix entries are small integers).
  [[nodiscard]] std::array<double, 4> to_child_coordinates(int s,
                                                           const std::array<double, 4>& lambda) const noexcept {
    std::array<double, 4> mu{};
    const auto& m = to_child[static_cast<std::size_t>(s)];
    for (std::size_t k = 0; k < 4; ++k) {
      mu[k] = m[k][0] * lambda[0] + m[k][1] * lambda[1] + m[k][2] * lambda[2] + m[k][3] * lambda[3];
    }
    return mu;
  }
};

}  // namespace ido::drill

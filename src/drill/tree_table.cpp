// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/tree_table.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

namespace ido::drill {
namespace {

// Child vertex lists in Bey's order, each vertex as a pair of parent vertex indices.
constexpr std::uint8_t kBey[8][4][2] = {
    {{0, 0}, {0, 1}, {0, 2}, {0, 3}},  // C0
    {{0, 1}, {1, 1}, {1, 2}, {1, 3}},  // C1
    {{0, 2}, {1, 2}, {2, 2}, {2, 3}},  // C2
    {{0, 3}, {1, 3}, {2, 3}, {3, 3}},  // C3
    {{0, 1}, {0, 2}, {0, 3}, {1, 3}},  // C4
    {{0, 1}, {0, 2}, {1, 2}, {1, 3}},  // C5
    {{0, 2}, {0, 3}, {1, 3}, {2, 3}},  // C6
    {{0, 2}, {1, 2}, {1, 3}, {2, 3}},  // C7
};

// Parent-barycentric weights (×2, so integers) of child vertex k of slot s.
std::array<int, 4> weights2(int s, int k) {
  std::array<int, 4> w{};
  w[kBey[s][k][0]] += 1;
  w[kBey[s][k][1]] += 1;
  return w;
}

TreeTable build() {
  TreeTable t;
  // A reference parent: the child's orientation and the barycentric maps do not depend
  // on the parent's shape (they are affine invariants), so any non-degenerate tet works.
  for (int s = 0; s < 8; ++s) {
    Eigen::Matrix4d a;  // column k: child vertex k in parent barycentrics
    for (int k = 0; k < 4; ++k) {
      t.vertex[s][k] = {kBey[s][k][0], kBey[s][k][1]};
      const auto w = weights2(s, k);
      for (int j = 0; j < 4; ++j) a(j, k) = 0.5 * w[static_cast<std::size_t>(j)];
    }
    // Orientation: the determinant of the barycentric map (columns sum to one) has the
    // sign of the child's signed volume relative to the parent's.
    t.parity[s] = a.determinant() < 0.0 ? 1 : 0;
    const Eigen::Matrix4d inv = a.inverse();
    for (int k = 0; k < 4; ++k) {
      for (int j = 0; j < 4; ++j) {
        const double v = inv(k, j);
        const double r = std::round(v);
        if (std::abs(v - r) > 1e-9) throw std::logic_error("TreeTable: non-integer barycentric map");
        t.to_child[s][k][j] = static_cast<std::int8_t>(r);
      }
    }
  }
  // Adjacency: compare faces as sets of parent-barycentric vertices.
  auto face_key = [](int s, int f) {
    std::array<int, 3> key{};
    int n = 0;
    for (int k = 0; k < 4; ++k) {
      if (k == f) continue;
      const auto w = weights2(s, k);
      key[static_cast<std::size_t>(n++)] = w[0] * 27 + w[1] * 9 + w[2] * 3 + w[3];
    }
    std::sort(key.begin(), key.end());
    return key;
  };
  for (int s = 0; s < 8; ++s) {
    for (int f = 0; f < 4; ++f) {
      TreeTable::FaceLink link;
      const auto key = face_key(s, f);
      for (int s2 = 0; s2 < 8 && link.sibling < 0; ++s2) {
        if (s2 == s) continue;
        for (int f2 = 0; f2 < 4; ++f2) {
          if (face_key(s2, f2) == key) {
            link.sibling = static_cast<std::int8_t>(s2);
            link.sibling_face = static_cast<std::int8_t>(f2);
            break;
          }
        }
      }
      if (link.sibling < 0) {
        // On a parent face: the parent vertex whose weight is zero at all three vertices.
        for (int j = 0; j < 4; ++j) {
          bool zero = true;
          for (int k = 0; k < 4; ++k) {
            if (k != f && weights2(s, k)[static_cast<std::size_t>(j)] != 0) zero = false;
          }
          if (zero) link.parent_face = static_cast<std::int8_t>(j);
        }
        if (link.parent_face < 0) throw std::logic_error("TreeTable: face neither inner nor on parent");
      }
      t.face_link[s][f] = link;
    }
  }
  return t;
}

}  // namespace

const TreeTable& TreeTable::get() {
  static const TreeTable table = build();
  return table;
}

}  // namespace ido::drill

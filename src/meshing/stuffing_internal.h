// SPDX-License-Identifier: Apache-2.0
// Internal to the meshing module: the pieces of isosurface stuffing (Labelle & Shewchuk 2007)
// shared by the uniform lattice (tetrahedralize.cpp) and the octree-graded lattice
// (tetrahedralize_graded.cpp): field reading, cut-point search and the stencils that replace
// one lattice tetrahedron. Written for ido from the paper.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/core/parallel.h"
#include "ido/core/progress.h"
#include "ido/geometry/tet_mesh.h"
#include "ido/image/volume.h"

namespace ido::meshing::detail {

using Id = std::int32_t;
using Coord = std::array<std::int64_t, 3>;  // integer lattice coordinates (see Stuffer)

/// Reads the field in world space: trilinear inside the grid, intersected with the box of
/// the voxel centres outside it (so regions touching the border are closed there).
class FieldReader {
 public:
  explicit FieldReader(const image::Volume<float>& field) : m_field(field) {}
  [[nodiscard]] double operator()(const Vec3& world) const {
    const Vec3 idx = m_field.world_to_index(world);
    const double value = m_field.sample_index(idx, image::Boundary::Clamp);
    // Signed distance (mm, approximate for skewed grids) to the box of voxel centres.
    Vec3 q;
    for (int a = 0; a < 3; ++a) {
      const double hi = double(m_field.size(a) - 1);
      q[a] = std::max(-idx[a], idx[a] - hi) * m_field.spacing()[a];
    }
    const double box = q.maxCoeff() <= 0.0 ? q.maxCoeff() : q.cwiseMax(0.0).norm();
    return std::max(value, box);
  }

 private:
  const image::Volume<float>& m_field;
};

/// Root of the field on the segment a → b where fa and fb have opposite signs, as the
/// fraction t ∈ (0, 1) from a (Illinois variant of regula falsi on the trilinear field).
inline double find_cut(const FieldReader& field, const Vec3& a, const Vec3& b, double fa, double fb) {
  double t0 = 0, t1 = 1, f0 = fa, f1 = fb;
  double t = f0 / (f0 - f1);
  int side = 0;
  for (int it = 0; it < 30; ++it) {
    t = (t0 * f1 - t1 * f0) / (f1 - f0);
    const double ft = field(a + t * (b - a));
    if (ft == 0.0 || (t1 - t0) < 1e-9) break;
    if ((ft < 0) == (f0 < 0)) {
      t0 = t;
      f0 = ft;
      if (side == -1) f1 *= 0.5;
      side = -1;
    } else {
      t1 = t;
      f1 = ft;
      if (side == 1) f0 *= 0.5;
      side = 1;
    }
    if (std::abs(ft) < 1e-12) break;
  }
  return std::clamp(t, 1e-6, 1.0 - 1e-6);
}

/// Replaces lattice tetrahedra by the stencils of their sign patterns. View provides
/// node_position(n) (lattice vertices first, then cut points), cut(u, v) (the node id of the
/// cut point on lattice edge u–v), is_long(u, v) (an axis-parallel lattice edge) and
/// coord(v) (integer coordinates in which a red vertex is offset from its black neighbours
/// by the same amount along every axis).
template <class View>
struct Stuffer {
  const View& L;
  const std::vector<std::int8_t>& sign;              // per lattice vertex: -1, 0, +1

  [[nodiscard]] Vec3 node_position(Id n) const { return L.node_position(n); }
  [[nodiscard]] Id cut(Id u, Id v) const { return L.cut(u, v); }

  void emit(std::vector<Tet>& out, Id a, Id b, Id c, Id d) const {
    const Vec3 pa = node_position(a);
    const double vol =
        (node_position(b) - pa).dot((node_position(c) - pa).cross(node_position(d) - pa));
    if (vol > 0) out.push_back({a, b, c, d});
    else if (vol < 0) out.push_back({a, b, d, c});
    // a zero-volume tetrahedron cannot come out of the stencils; dropped defensively.
  }

  /// Quadrilateral on the lattice face (a, b, t) where a and b are negative and t positive:
  /// returns true when the diagonal joins a to cut(b, t), false when it joins b to
  /// cut(a, t). The rule depends only on the face, so both tetrahedra sharing it agree:
  /// with a long edge through t, the diagonal joins the cut point on that long edge to the
  /// opposite lattice vertex; with the long edge a–b, a parity rule on the apex's position
  /// around the edge picks the end (adjacent apexes around an edge pick opposite ends, so
  /// the two quadrilaterals of one tetrahedron never make an untetrahedralizable prism).
  [[nodiscard]] bool diagonal_from_a(Id a, Id b, Id t) const {
    if (L.is_long(a, t)) return false;  // cut(a,t) on the long edge → joins b
    if (L.is_long(b, t)) return true;   // cut(b,t) on the long edge → joins a
    const Coord ca = L.coord(a), cb = L.coord(b), ct = L.coord(t);
    int axis = 0;
    while (ca[axis] == cb[axis]) ++axis;
    std::int64_t s = 0;
    for (int k = 0; k < 3; ++k)
      if (k != axis) s += ct[k] - ca[k];
    const bool odd = s != 0;
    const bool a_is_min = ca[axis] < cb[axis];
    return odd == a_is_min;
  }

  /// Tetrahedralizes the prism with triangles (a0, a1, a2) and (b0, b1, b2), vertical edges
  /// ai–bi; r[i] says quad i (between i and i+1) is split by ai–b(i+1), -1 = free.
  void prism(std::vector<Tet>& out, const std::array<Id, 3>& a, const std::array<Id, 3>& b,
             std::array<int, 3> r) const {
    for (int i = 0; i < 3; ++i) {
      if (r[i] >= 0) continue;
      const int o1 = r[(i + 1) % 3], o2 = r[(i + 2) % 3];
      if (o1 == 1 && o2 == 1) r[i] = 0;
      else if (o1 == 0 && o2 == 0) r[i] = 1;
      else {
        // both choices valid: the shorter diagonal
        const int j = (i + 1) % 3;
        const double dr = (node_position(a[i]) - node_position(b[j])).squaredNorm();
        const double dl = (node_position(a[j]) - node_position(b[i])).squaredNorm();
        r[i] = dr <= dl ? 1 : 0;
      }
    }
    for (int i = 0; i < 3; ++i) {
      const int prev = (i + 2) % 3, n1 = (i + 1) % 3, n2 = (i + 2) % 3;
      // quad n1 = (a[n1], a[n2], b[n2], b[n1]); R_n1 splits it by a[n1]–b[n2]
      const std::array<Id, 4> q = {a[n1], a[n2], b[n2], b[n1]};
      if (r[i] == 1 && r[prev] == 0) {  // a[i] carries two diagonals
        emit(out, a[i], b[0], b[1], b[2]);
        pyramid(out, a[i], q, r[n1] == 1);
        return;
      }
      if (r[i] == 0 && r[prev] == 1) {  // b[i] carries two diagonals
        emit(out, b[i], a[0], a[1], a[2]);
        pyramid(out, b[i], q, r[n1] == 1);
        return;
      }
    }
  }

  /// Pyramid with apex @p apex over quad q (cyclic); diag02 = split by q0–q2, else q1–q3.
  void pyramid(std::vector<Tet>& out, Id apex, const std::array<Id, 4>& q, bool diag02) const {
    if (diag02) {
      emit(out, apex, q[0], q[1], q[2]);
      emit(out, apex, q[0], q[2], q[3]);
    } else {
      emit(out, apex, q[0], q[1], q[3]);
      emit(out, apex, q[1], q[2], q[3]);
    }
  }

  /// Replaces the lattice tetrahedron v by its stencil.
  void stencil(std::vector<Tet>& out, const std::array<Id, 4>& v) const {
    std::array<Id, 4> neg{}, zer{}, pos{};
    int nn = 0, nz = 0, np = 0;
    for (Id x : v) {
      const int s = sign[std::size_t(x)];
      if (s < 0) neg[std::size_t(nn++)] = x;
      else if (s > 0) pos[std::size_t(np++)] = x;
      else zer[std::size_t(nz++)] = x;
    }
    if (np == 0) {
      // A tetrahedron with four zero vertices lies along the surface and may be nearly
      // flat (its vertices were warped independently): it is left out, which keeps every
      // output tetrahedron within the proven dihedral bounds.
      if (nn > 0) emit(out, v[0], v[1], v[2], v[3]);
      return;
    }
    if (nn == 0) return;
    if (nn == 1) {
      const Id n = neg[0];
      if (np == 3) emit(out, n, cut(n, pos[0]), cut(n, pos[1]), cut(n, pos[2]));
      else if (np == 2) emit(out, n, zer[0], cut(n, pos[0]), cut(n, pos[1]));
      else emit(out, n, zer[0], zer[1], cut(n, pos[0]));
      return;
    }
    if (nn == 2 && np == 1) {
      const Id a = neg[0], b = neg[1], t = pos[0];
      // quad (a, b, cut(b,t), cut(a,t)); split a–cut(b,t) is q0–q2
      pyramid(out, zer[0], {a, b, cut(b, t), cut(a, t)}, diagonal_from_a(a, b, t));
      return;
    }
    if (nn == 2 && np == 2) {
      const Id l = neg[0], r = neg[1], t = pos[0], m = pos[1];
      // prism: bottom (l, cut(l,t), cut(l,m)), top (r, cut(r,t), cut(r,m))
      const std::array<Id, 3> a = {l, cut(l, t), cut(l, m)};
      const std::array<Id, 3> b = {r, cut(r, t), cut(r, m)};
      // quad 0 = (l, cut(l,t), cut(r,t), r) on face (l, r, t): R = l–cut(r,t)
      // quad 2 = (cut(l,m), l, r, cut(r,m)) on face (l, r, m): R = cut(l,m)–r
      const int r0 = diagonal_from_a(l, r, t) ? 1 : 0;
      const int r2 = diagonal_from_a(l, r, m) ? 0 : 1;
      prism(out, a, b, {r0, -1, r2});
      return;
    }
    // nn == 3, np == 1: prism between the negative face and its three cut points
    const Id t = pos[0];
    const std::array<Id, 3> a = {neg[0], neg[1], neg[2]};
    const std::array<Id, 3> b = {cut(a[0], t), cut(a[1], t), cut(a[2], t)};
    std::array<int, 3> r{};
    for (int i = 0; i < 3; ++i) {
      // quad i = (a_i, a_{i+1}, b_{i+1}, b_i) on face (a_i, a_{i+1}, t): R = a_i–cut(a_{i+1},t)
      r[std::size_t(i)] = diagonal_from_a(a[std::size_t(i)], a[std::size_t((i + 1) % 3)], t) ? 1 : 0;
    }
    prism(out, a, b, r);
  }
};

/// The field at every lattice vertex (@p value) and its sign (@p sign: −1, 0, +1).
/// @p position maps a vertex id to mm, @p field a point in mm to its signed distance.
template <class Position, class Field>
void sample_lattice(std::size_t nv, Position&& position, Field&& field, bool threaded,
                    std::vector<double>& value, std::vector<std::int8_t>& sign) {
  value.assign(nv, 0.0);
  sign.assign(nv, 0);
  parallel_for_ranges(
      nv,
      [&](std::size_t b, std::size_t e) {
        for (std::size_t v = b; v < e; ++v) {
          value[v] = field(position(Id(v)));
          sign[v] = value[v] < 0 ? -1 : (value[v] > 0 ? 1 : 0);
        }
      },
      threaded, 1024);
}

/// The output mesh of a stuffing pass: the nodes the per-block tetrahedra use, renumbered in
/// node order, and the tetrahedra block by block. @p node_position maps a node id to mm.
template <class NodePosition>
[[nodiscard]] geometry::TetMesh compact_tets(const std::vector<std::vector<Tet>>& block_tets,
                                             std::size_t nnodes, NodePosition&& node_position) {
  std::vector<Id> remap(nnodes, -1);
  std::size_t ntets = 0;
  for (const auto& b : block_tets) {
    ntets += b.size();
    for (const Tet& t : b)
      for (Id x : t) remap[std::size_t(x)] = 0;
  }
  geometry::TetMesh mesh;
  for (std::size_t n = 0; n < nnodes; ++n) {
    if (remap[n] < 0) continue;
    remap[n] = Id(mesh.vertices.size());
    mesh.vertices.push_back(node_position(Id(n)));
  }
  mesh.tets.reserve(ntets);
  for (const auto& b : block_tets)
    for (const Tet& t : b)
      mesh.tets.push_back({remap[std::size_t(t[0])], remap[std::size_t(t[1])],
                           remap[std::size_t(t[2])], remap[std::size_t(t[3])]});
  return mesh;
}

/// Graded isosurface stuffing (tetrahedralize_graded.cpp): @p field is finite, at least
/// 2 voxels along every axis, and @p h > 0 is the finest lattice spacing (mm).
[[nodiscard]] geometry::TetMesh tetrahedralize_graded(const image::Volume<float>& field, double h,
                                                      bool threaded, Progress* progress);

}  // namespace ido::meshing::detail

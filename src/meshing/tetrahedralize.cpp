// SPDX-License-Identifier: Apache-2.0
// One-level isosurface stuffing (Labelle & Shewchuk 2007), written for ido from the paper.
#include "ido/meshing/tetrahedralize.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/geometry/aabb.h"
#include "ido/meshing/signed_distance.h"
#include "stuffing_internal.h"

namespace ido::meshing {
namespace {

using detail::Coord;
using detail::FieldReader;
using detail::Id;
using detail::find_cut;

/// The body-centred cubic lattice: black vertices at p0 + h·(i, j, k), red vertices at the
/// cube centres p0 + h·(i + ½, j + ½, k + ½). Vertex ids: black first, then red. Edges are
/// stored in slots owned by one end: a black vertex owns its +x, +y, +z black edges (slots
/// 0–2); a red vertex owns its +x, +y, +z red edges (slots 0–2) and its 8 diagonal edges to
/// the corners of its cube (slots 3–10, corner bits x | y << 1 | z << 2).
struct Lattice {
  Vec3 p0;
  double h = 1;
  std::int64_t nx = 0, ny = 0, nz = 0;  // cubes per axis
  std::int64_t nb = 0, nr = 0;          // black and red vertex counts

  [[nodiscard]] std::int64_t vertex_count() const { return nb + nr; }
  [[nodiscard]] std::int64_t slot_count() const { return 3 * nb + 11 * nr; }
  [[nodiscard]] Id black(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return Id(i + (nx + 1) * (j + (ny + 1) * k));
  }
  [[nodiscard]] Id red(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return Id(nb + i + nx * (j + ny * k));
  }
  [[nodiscard]] bool is_red(Id v) const { return v >= nb; }
  [[nodiscard]] Coord coord(Id v) const {
    if (v < nb) {
      const std::int64_t i = v % (nx + 1), r = v / (nx + 1);
      return {2 * i, 2 * (r % (ny + 1)), 2 * (r / (ny + 1))};
    }
    const std::int64_t w = v - nb;
    const std::int64_t i = w % nx, r = w / nx;
    return {2 * i + 1, 2 * (r % ny) + 1, 2 * (r / ny) + 1};
  }
  [[nodiscard]] Id at(const Coord& c) const {
    if (c[0] & 1) return red(c[0] / 2, c[1] / 2, c[2] / 2);
    return black(c[0] / 2, c[1] / 2, c[2] / 2);
  }
  [[nodiscard]] bool valid(const Coord& c) const {
    const bool odd = c[0] & 1;
    const std::int64_t lim[3] = {2 * nx, 2 * ny, 2 * nz};
    for (int a = 0; a < 3; ++a) {
      if (c[a] < 0 || c[a] > lim[a] || bool(c[a] & 1) != odd) return false;
    }
    return true;
  }
  [[nodiscard]] Vec3 position(Id v) const {
    const Coord c = coord(v);
    return p0 + 0.5 * h * Vec3(double(c[0]), double(c[1]), double(c[2]));
  }
  [[nodiscard]] std::int64_t slot_base(Id v) const {
    return v < nb ? 3 * std::int64_t(v) : 3 * nb + 11 * (std::int64_t(v) - nb);
  }
  [[nodiscard]] int slot_count(Id v) const { return v < nb ? 3 : 11; }
  /// The other end of slot s of vertex v, or nullopt when it falls outside the lattice.
  [[nodiscard]] std::optional<Id> slot_target(Id v, int s) const {
    Coord c = coord(v);
    if (s < 3) {
      c[s] += 2;
    } else {
      const int corner = s - 3;
      for (int a = 0; a < 3; ++a) c[a] += ((corner >> a) & 1) ? 1 : -1;
    }
    if (!valid(c)) return std::nullopt;
    return at(c);
  }
  /// Global slot index of the lattice edge (u, v), which must be a lattice edge.
  [[nodiscard]] std::int64_t edge_slot(Id u, Id v) const {
    const Coord cu = coord(u), cv = coord(v);
    const bool ru = is_red(u), rv = is_red(v);
    if (ru == rv) {  // axis-parallel edge, owned by the lower end
      for (int a = 0; a < 3; ++a) {
        if (cu[a] != cv[a]) return cu[a] < cv[a] ? slot_base(u) + a : slot_base(v) + a;
      }
    }
    const Id r = ru ? u : v;
    const Coord& cr = ru ? cu : cv;
    const Coord& cb = ru ? cv : cu;
    int corner = 0;
    for (int a = 0; a < 3; ++a) corner |= (cb[a] > cr[a] ? 1 : 0) << a;
    return slot_base(r) + 3 + corner;
  }
  /// True for the axis-parallel (black–black or red–red) edges of length h.
  [[nodiscard]] bool is_long(Id u, Id v) const { return is_red(u) == is_red(v); }
};

constexpr std::size_t kBlock = 2048;

/// The uniform lattice's view for detail::Stuffer.
struct UniformView {
  const Lattice& lattice;
  const std::vector<Id>& cut_id;                // per slot
  const std::unordered_map<Id, Vec3>& warped;   // snapped lattice vertices
  const std::vector<Vec3>& cut_pos;             // per cut id
  Id nv;                                        // lattice vertex count

  [[nodiscard]] Vec3 node_position(Id n) const {
    if (n >= nv) return cut_pos[std::size_t(n - nv)];
    auto it = warped.find(n);
    return it != warped.end() ? it->second : lattice.position(n);
  }
  [[nodiscard]] Id cut(Id u, Id v) const {
    return nv + cut_id[std::size_t(lattice.edge_slot(u, v))];
  }
  [[nodiscard]] bool is_long(Id u, Id v) const { return lattice.is_long(u, v); }
  [[nodiscard]] Coord coord(Id v) const { return lattice.coord(v); }
};


}  // namespace

double stuffing_lattice_spacing(const image::Volume<float>& field,
                                const TetrahedralizeOptions& options) {
  if (!std::isfinite(options.edge_mm) || options.edge_mm < 0)
    throw InvalidInput("tetrahedralize: edge_mm must be a finite length >= 0 (mm)");
  if (options.edge_mm > 0) return options.edge_mm;
  const Vec3& s = field.spacing();
  return 2.0 * std::cbrt(s[0] * s[1] * s[2]);
}

geometry::TetMesh tetrahedralize(const image::Volume<float>& signed_distance_mm,
                                 const TetrahedralizeOptions& options, Progress* progress) {
  if (signed_distance_mm.empty())
    throw InvalidInput("tetrahedralize: the signed distance field is empty");
  for (int a = 0; a < 3; ++a) {
    if (signed_distance_mm.size(a) < 2)
      throw InvalidInput("tetrahedralize: the signed distance field needs at least 2 voxels "
                         "along every axis");
  }
  const double h = stuffing_lattice_spacing(signed_distance_mm, options);

  // Infinite values (e.g. from an empty mask) would make trilinear weights produce NaN.
  const image::Volume<float>* field_volume = &signed_distance_mm;
  image::Volume<float> clamped;
  {
    bool has_inf = false;
    for (float x : signed_distance_mm.data()) {
      if (std::isnan(x)) throw InvalidInput("tetrahedralize: the signed distance field holds NaN");
      if (std::isinf(x)) has_inf = true;
    }
    if (has_inf) {
      clamped = signed_distance_mm;
      for (float& x : clamped.data()) x = std::clamp(x, -1e30f, 1e30f);
      field_volume = &clamped;
    }
  }
  if (options.graded) return detail::tetrahedralize_graded(*field_volume, h, options.threaded, progress);
  const FieldReader field(*field_volume);

  Lattice L;
  {
    const auto [lo, hi] = field_volume->world_bounds();
    // half-voxel beyond the hull plus one lattice step keeps the lattice border outside.
    const Vec3 margin = Vec3::Constant(h + 0.5 * field_volume->spacing().maxCoeff());
    L.h = h;
    L.p0 = lo - margin;
    const Vec3 ext = (hi + margin) - L.p0;
    const double n[3] = {std::ceil(ext[0] / h), std::ceil(ext[1] / h), std::ceil(ext[2] / h)};
    const double total = (n[0] + 1) * (n[1] + 1) * (n[2] + 1) + n[0] * n[1] * n[2];
    if (!(total < 2.0e9 / 11.0))
      throw EdgeTooSmall("tetrahedralize: edge_mm is too small for this field (lattice of " +
                         std::to_string(total) + " vertices)");
    L.nx = std::int64_t(n[0]);
    L.ny = std::int64_t(n[1]);
    L.nz = std::int64_t(n[2]);
    L.nb = (L.nx + 1) * (L.ny + 1) * (L.nz + 1);
    L.nr = L.nx * L.ny * L.nz;
  }
  const std::size_t nv = std::size_t(L.vertex_count());
  const bool threaded = options.threaded;
  const std::size_t nblocks = (nv + kBlock - 1) / kBlock;

  // 1. field at the lattice vertices
  report(progress, 0.0, "tetrahedralize: sampling the field");
  std::vector<double> value;
  std::vector<std::int8_t> sign;
  detail::sample_lattice(nv, [&](Id v) { return L.position(v); }, field, threaded, value, sign);
  check_cancel(progress);

  // 2. cut points on the edges whose ends have opposite signs
  report(progress, 0.25, "tetrahedralize: cut points");
  std::vector<Id> cut_id(std::size_t(L.slot_count()), -1);
  std::vector<std::int64_t> block_cuts(nblocks + 1, 0);
  parallel_for(
      nblocks,
      [&](std::size_t blk) {
        std::int64_t count = 0;
        const std::size_t end = std::min(nv, (blk + 1) * kBlock);
        for (std::size_t v = blk * kBlock; v < end; ++v) {
          if (sign[v] == 0) continue;
          for (int s = 0; s < L.slot_count(Id(v)); ++s) {
            const auto w = L.slot_target(Id(v), s);
            if (w && sign[v] * sign[std::size_t(*w)] < 0) ++count;
          }
        }
        block_cuts[blk + 1] = count;
      },
      threaded, 1);
  for (std::size_t b = 0; b < nblocks; ++b) block_cuts[b + 1] += block_cuts[b];
  const std::int64_t ncuts = block_cuts[nblocks];
  if (ncuts >= std::int64_t(std::numeric_limits<Id>::max()) - std::int64_t(nv))
    throw InvalidInput("tetrahedralize: too many cut points for 32-bit indices");
  const auto ncut_size = static_cast<std::size_t>(ncuts);
  std::vector<Vec3> cut_pos(ncut_size);
  std::vector<double> cut_t(ncut_size);                // fraction from the slot owner
  std::vector<std::array<Id, 2>> cut_ends(ncut_size);  // owner, other
  parallel_for(
      nblocks,
      [&](std::size_t blk) {
        std::int64_t id = block_cuts[blk];
        const std::size_t end = std::min(nv, (blk + 1) * kBlock);
        for (std::size_t v = blk * kBlock; v < end; ++v) {
          if (sign[v] == 0) continue;
          for (int s = 0; s < L.slot_count(Id(v)); ++s) {
            const auto w = L.slot_target(Id(v), s);
            if (!w || sign[v] * sign[std::size_t(*w)] >= 0) continue;
            const Vec3 a = L.position(Id(v)), b = L.position(*w);
            const double t = find_cut(field, a, b, value[v], value[std::size_t(*w)]);
            cut_id[std::size_t(L.slot_base(Id(v)) + s)] = Id(id);
            cut_pos[std::size_t(id)] = a + t * (b - a);
            cut_t[std::size_t(id)] = t;
            cut_ends[std::size_t(id)] = {Id(v), *w};
            ++id;
          }
        }
      },
      threaded, 1);
  check_cancel(progress);

  // 3. warping: a vertex with a cut point closer than alpha × edge length on one of its
  //    edges is snapped to the closest such cut point and becomes a zero vertex (the cut
  //    points on its other edges disappear). Candidates in id order, checked again when
  //    their turn comes, so the result does not depend on threading.
  report(progress, 0.5, "tetrahedralize: warping");
  std::vector<std::int64_t> violators;
  {
    std::vector<char> violated(nv, 0);
    parallel_for(
        std::size_t(ncuts),
        [&](std::size_t c) {
          const auto [u, w] = cut_ends[c];
          const double alpha = L.is_long(u, w) ? kStuffingAlphaLong : kStuffingAlphaShort;
          if (cut_t[c] < alpha) violated[std::size_t(u)] = 1;       // benign race: same value
          if (1.0 - cut_t[c] < alpha) violated[std::size_t(w)] = 1;
        },
        false);
    for (std::size_t v = 0; v < nv; ++v)
      if (violated[v]) violators.push_back(std::int64_t(v));
  }
  std::unordered_map<Id, Vec3> warped;
  warped.reserve(violators.size());
  for (std::int64_t vv : violators) {
    const Id v = Id(vv);
    if (sign[std::size_t(v)] == 0) continue;
    const Coord c = L.coord(v);
    double best = INFINITY;
    Vec3 best_pos;
    auto consider = [&](const Coord& other) {
      if (!L.valid(other)) return;
      const Id w = L.at(other);
      if (sign[std::size_t(v)] * sign[std::size_t(w)] >= 0) return;
      const Id id = cut_id[std::size_t(L.edge_slot(v, w))];
      const bool owner = cut_ends[std::size_t(id)][0] == v;
      const double t = owner ? cut_t[std::size_t(id)] : 1.0 - cut_t[std::size_t(id)];
      const bool is_long = L.is_long(v, w);
      const double alpha = is_long ? kStuffingAlphaLong : kStuffingAlphaShort;
      if (t >= alpha) return;
      const double dist = t * (is_long ? 1.0 : std::sqrt(3.0) / 2.0);
      if (dist < best) {
        best = dist;
        best_pos = cut_pos[std::size_t(id)];
      }
    };
    for (int a = 0; a < 3; ++a) {
      for (int d : {-2, 2}) {
        Coord o = c;
        o[std::size_t(a)] += d;
        consider(o);
      }
    }
    for (int corner = 0; corner < 8; ++corner) {
      Coord o = c;
      for (int a = 0; a < 3; ++a) o[std::size_t(a)] += ((corner >> a) & 1) ? 1 : -1;
      consider(o);
    }
    if (best < INFINITY) {
      sign[std::size_t(v)] = 0;
      warped[v] = best_pos;
    }
  }
  check_cancel(progress);

  // 4. stencils, one lattice tetrahedron at a time: each pair of face-adjacent cubes
  //    (a red edge) carries the 4 tetrahedra of that red edge and the black edges of the
  //    shared face.
  report(progress, 0.6, "tetrahedralize: stencils");
  const UniformView view{L, cut_id, warped, cut_pos, Id(nv)};
  const detail::Stuffer<UniformView> stuffer{view, sign};
  const std::size_t nred = std::size_t(L.nr);
  const std::size_t rblocks = (nred + kBlock - 1) / kBlock;
  std::vector<std::vector<Tet>> block_tets(rblocks);
  parallel_for(
      rblocks,
      [&](std::size_t blk) {
        auto& out = block_tets[blk];
        const std::size_t end = std::min(nred, (blk + 1) * kBlock);
        for (std::size_t w = blk * kBlock; w < end; ++w) {
          const Id r = Id(L.nb + std::int64_t(w));
          const Coord c = L.coord(r);
          const std::int64_t ci[3] = {(c[0] - 1) / 2, (c[1] - 1) / 2, (c[2] - 1) / 2};
          const std::int64_t lim[3] = {L.nx, L.ny, L.nz};
          for (int a = 0; a < 3; ++a) {
            if (ci[a] + 1 >= lim[a]) continue;
            std::int64_t cn[3] = {ci[0], ci[1], ci[2]};
            cn[a] += 1;
            const Id r2 = L.red(cn[0], cn[1], cn[2]);
            const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
            auto corner = [&](int u, int v2) {
              std::int64_t q[3] = {ci[0], ci[1], ci[2]};
              q[a] += 1;
              q[b1] += u;
              q[b2] += v2;
              return L.black(q[0], q[1], q[2]);
            };
            const Id q00 = corner(0, 0), q10 = corner(1, 0), q01 = corner(0, 1),
                     q11 = corner(1, 1);
            const std::array<std::array<Id, 2>, 4> blacks = {
                {{q00, q10}, {q01, q11}, {q00, q01}, {q10, q11}}};
            for (const auto& be : blacks) {
              const std::array<Id, 4> tet = {r, r2, be[0], be[1]};
              bool any_neg = false, any_pos = false;
              for (Id x : tet) {
                any_neg |= sign[std::size_t(x)] < 0;
                any_pos |= sign[std::size_t(x)] > 0;
              }
              if (!any_neg && any_pos) continue;
              stuffer.stencil(out, tet);
            }
          }
        }
      },
      threaded, 1);
  check_cancel(progress);

  // 5. compact: keep the nodes the tetrahedra use, in node order
  report(progress, 0.9, "tetrahedralize: output");
  geometry::TetMesh mesh = detail::compact_tets(block_tets, nv + std::size_t(ncuts),
                                                [&](Id n) { return stuffer.node_position(n); });
  report(progress, 1.0, "tetrahedralize: done");
  return mesh;
}

geometry::TetMesh tetrahedralize_surface(const geometry::TriangleMesh& surface,
                                         const TetrahedralizeOptions& options,
                                         Progress* progress) {
  if (surface.triangles.empty())
    throw InvalidInput("tetrahedralize_surface: the surface has no triangles");
  if (!std::isfinite(options.edge_mm) || options.edge_mm < 0)
    throw InvalidInput("tetrahedralize_surface: edge_mm must be a finite length >= 0 (mm)");
  const auto nv = surface.vertices.size();
  geometry::Aabb box;  // of the corners the triangles use
  double edge_sum = 0;
  for (const Tri& t : surface.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      if (a < 0 || std::size_t(a) >= nv || b < 0 || std::size_t(b) >= nv)
        throw InvalidInput("tetrahedralize_surface: triangle index out of range");
      edge_sum += (surface.vertices[std::size_t(a)] - surface.vertices[std::size_t(b)]).norm();
      box.extend(surface.vertices[std::size_t(a)]);
    }
  }
  const Vec3 &lo = box.min, &hi = box.max;
  if (!lo.allFinite() || !hi.allFinite())
    throw InvalidInput("tetrahedralize_surface: the surface has non-finite coordinates");
  const double h = options.edge_mm > 0 ? options.edge_mm
                                       : edge_sum / (3.0 * double(surface.triangles.size()));
  if (!(h > 0)) throw InvalidInput("tetrahedralize_surface: the surface has zero size");
  const double s = 0.5 * h;
  const Vec3 origin = lo - Vec3::Constant(2 * h);
  const Vec3 extent = (hi + Vec3::Constant(2 * h)) - origin;
  Index3 size;
  double count = 1;
  for (int a = 0; a < 3; ++a) {
    size[std::size_t(a)] = std::int64_t(std::ceil(extent[a] / s)) + 1;
    count *= double(size[std::size_t(a)]);
  }
  if (!(count < 2.0e9))
    throw EdgeTooSmall("tetrahedralize_surface: edge_mm is too small for this surface");
  report(progress, 0.0, "tetrahedralize: signed distance of the surface");
  const image::Volume<float> grid(size, Vec3::Constant(s), origin);
  SignedDistanceOptions sd;
  sd.band_mm = 2 * h;
  sd.threaded = options.threaded;
  const auto field = signed_distance(surface, grid, sd);
  check_cancel(progress);
  TetrahedralizeOptions o = options;
  o.edge_mm = h;
  return tetrahedralize(field, o, progress);
}

}  // namespace ido::meshing

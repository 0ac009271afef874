// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/self_intersection.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include <tbb/task_arena.h>

#include "ido/core/error.h"
#include "ido/core/parallel.h"
#include "ido/geometry/aabb.h"
#include "ido/geometry/bvh.h"
#include "ido/geometry/mesh_topology.h"
#include "ido/geometry/predicates.h"
#include "ido/geometry/triangle_intersection.h"

namespace ido::geometry {
namespace {

/// Reorders the corners of two triangles so that the shared vertex indices come first, in
/// the same order in both; returns the number of shared distinct indices.
int align_shared(const Tri& a, const Tri& b, std::array<int, 3>& pa, std::array<int, 3>& pb) {
  int shared = 0;
  std::array<bool, 3> used_a{false, false, false};
  std::array<bool, 3> used_b{false, false, false};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (!used_a[static_cast<std::size_t>(i)] && !used_b[static_cast<std::size_t>(j)] &&
          a[static_cast<std::size_t>(i)] == b[static_cast<std::size_t>(j)]) {
        used_a[static_cast<std::size_t>(i)] = used_b[static_cast<std::size_t>(j)] = true;
        pa[static_cast<std::size_t>(shared)] = i;
        pb[static_cast<std::size_t>(shared)] = j;
        ++shared;
        break;
      }
    }
  }
  int na = shared;
  int nb = shared;
  for (int i = 0; i < 3; ++i) {
    if (!used_a[static_cast<std::size_t>(i)]) pa[static_cast<std::size_t>(na++)] = i;
    if (!used_b[static_cast<std::size_t>(i)]) pb[static_cast<std::size_t>(nb++)] = i;
  }
  return shared;
}

bool pair_intersects(const std::vector<Vec3>& vertices, const Tri& ta, const Tri& tb) {
  std::array<int, 3> pa{};
  std::array<int, 3> pb{};
  const int shared = align_shared(ta, tb, pa, pb);
  auto at = [&](const Tri& t, int k) -> const Vec3& {
    return vertices[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
  };
  const Triangle3 a{at(ta, pa[0]), at(ta, pa[1]), at(ta, pa[2])};
  const Triangle3 b{at(tb, pb[0]), at(tb, pb[1]), at(tb, pb[2])};
  if (shared == 0) return triangles_intersect(a, b);
  // Fast exits for the common neighbour pairs (the full test repeats them in rare cases).
  if (shared == 1) {
    if (sign_of(orient3d(b[0], b[1], b[2], a[1])) * sign_of(orient3d(b[0], b[1], b[2], a[2])) > 0) return false;
    if (sign_of(orient3d(a[0], a[1], a[2], b[1])) * sign_of(orient3d(a[0], a[1], a[2], b[2])) > 0) return false;
  } else if (shared == 2) {
    if (orient3d(a[0], a[1], a[2], b[2]) != 0.0) return false;
  }
  return adjacent_triangles_intersect(a, b, shared);
}

}  // namespace

bool mesh_triangles_intersect(const TriangleMesh& mesh, std::int32_t t1, std::int32_t t2) {
  const Tri& a = mesh.triangles[static_cast<std::size_t>(t1)];
  const Tri& b = mesh.triangles[static_cast<std::size_t>(t2)];
  return pair_intersects(mesh.vertices, a, b);
}

namespace {

using Pairs = std::vector<std::pair<std::int32_t, std::int32_t>>;

constexpr double kUnitRoundoff = 0x1p-53;
/// Forward error bound of plane_side's determinant relative to its permanent: the same
/// evaluation (three coordinate differences from one base point, three 2 × 2 minors, one dot
/// product) and the same bound as orient3d's filter (above Shewchuk's (7 + 56ε)ε).
constexpr double kPlaneSideBound = 8.0 * kUnitRoundoff;

/// The supporting plane of a triangle (a, b, c) prepared for many sign tests: the normal
/// n = (b − a) × (c − a) as evaluated in floating point, the absolute sums of the products
/// in each of its components (for the error bound), and the base point a.
struct Plane {
  double nx, ny, nz;
  double px, py, pz;
  double ax, ay, az;
};

Plane plane_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double bax = b.x() - a.x(), bay = b.y() - a.y(), baz = b.z() - a.z();
  const double cax = c.x() - a.x(), cay = c.y() - a.y(), caz = c.z() - a.z();
  const double m1 = bay * caz, m2 = baz * cay;
  const double m3 = baz * cax, m4 = bax * caz;
  const double m5 = bax * cay, m6 = bay * cax;
  return {m1 - m2, m3 - m4, m5 - m6,
          std::abs(m1) + std::abs(m2), std::abs(m3) + std::abs(m4), std::abs(m5) + std::abs(m6),
          a.x(), a.y(), a.z()};
}

/// Sign of orient3d(a, b, c, d) when the floating-point filter certifies it (+1 / −1), 0 when
/// it cannot (the point may lie on the plane: ask the exact predicate). The determinant is
/// det[d − a; b − a; c − a] = det[b − a; c − a; d − a], evaluated like orient3d's filter.
inline int plane_side(const Plane& p, const Vec3& d) {
  const double dx = d.x() - p.ax, dy = d.y() - p.ay, dz = d.z() - p.az;
  const double det = p.nx * dx + p.ny * dy + p.nz * dz;
  const double bound =
      kPlaneSideBound * (p.px * std::abs(dx) + p.py * std::abs(dy) + p.pz * std::abs(dz));
  return (det > bound) - (det < -bound);
}

/// Sign of orient3d(a, b, c, d) when its floating-point filter certifies it, else 0.
inline int orient3d_certified(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return plane_side(plane_of(a, b, c), d);
}

/// Whether the segment [p, q], whose end points are certified strictly on opposite sides of
/// the plane of the triangle (t0, t1, t2), passes through the closed triangle: the line is on
/// one side of (or on) all three edge lines (as in the exact segment–triangle test).
/// 1 yes, 0 no, −1 undecided by the filter.
inline int crossing_segment_hits(const Vec3& p, const Vec3& q, const Vec3& t0, const Vec3& t1,
                                 const Vec3& t2) {
  const int s1 = orient3d_certified(p, q, t0, t1);
  const int s2 = orient3d_certified(p, q, t1, t2);
  const int s3 = orient3d_certified(p, q, t2, t0);
  if (s1 == 0 || s2 == 0 || s3 == 0) return -1;
  return s1 == s2 && s2 == s3 ? 1 : 0;
}

/// pair_intersects with a floating-point filter in front. When certified signs decide the
/// exact test's own steps, it answers from them: a separating plane through one triangle; an
/// edge neighbour's third corner off the other's plane; for a vertex neighbour, both planes
/// crossed and each opposite edge tested against the other triangle. Anything the filter
/// cannot certify (near-coplanar, degenerate, repeated indices) goes to the exact test, so
/// the answers are those of pair_intersects. @p pa is the plane of @p ta.
bool filtered_pair_intersects(const std::vector<Vec3>& vertices, const Tri& ta, const Plane& pa,
                              const Tri& tb) {
  auto at = [&](std::int32_t i) -> const Vec3& { return vertices[static_cast<std::size_t>(i)]; };
  const bool distinct = ta[0] != ta[1] && ta[1] != ta[2] && ta[0] != ta[2] && tb[0] != tb[1] &&
                        tb[1] != tb[2] && tb[0] != tb[2];
  if (distinct) {
    // Which corners are shared by index, as bit masks.
    unsigned shared_b = 0;
    unsigned shared_a = 0;
    for (unsigned j = 0; j < 3; ++j) {
      for (unsigned i = 0; i < 3; ++i) {
        if (tb[j] == ta[i]) {
          shared_b |= 1u << j;
          shared_a |= 1u << i;
        }
      }
    }
    const unsigned shared = (0x3221'2110u >> (4 * shared_b)) & 0xfu;  // bits set in shared_b
    if (shared == 2) {
      const auto free_b = static_cast<unsigned>(std::countr_zero(~shared_b & 7u));
      if (plane_side(pa, at(tb[free_b])) != 0) return false;
    } else if (shared == 1) {
      const auto vb = static_cast<unsigned>(std::countr_zero(shared_b));
      const auto va = static_cast<unsigned>(std::countr_zero(shared_a));
      const Vec3& b1 = at(tb[(vb + 1) % 3]);
      const Vec3& b2 = at(tb[(vb + 2) % 3]);
      const int sb1 = plane_side(pa, b1);
      const int sb2 = plane_side(pa, b2);
      if (sb1 != 0 && sb1 == sb2) return false;
      const Vec3& a1 = at(ta[(va + 1) % 3]);
      const Vec3& a2 = at(ta[(va + 2) % 3]);
      const Vec3& b0 = at(tb[0]);
      const Vec3& b1o = at(tb[1]);
      const Vec3& b2o = at(tb[2]);
      const Plane pb = plane_of(b0, b1o, b2o);
      const int sa1 = plane_side(pb, a1);
      const int sa2 = plane_side(pb, a2);
      if (sa1 != 0 && sa1 == sa2) return false;
      if (sb1 != 0 && sb2 != 0 && sa1 != 0 && sa2 != 0) {
        // Both opposite edges cross the other's plane strictly; the triangles meet beyond
        // the shared vertex iff one of these edges passes through the other triangle.
        const int ha = crossing_segment_hits(a1, a2, b0, b1o, b2o);
        if (ha == 1) return true;
        if (ha == 0) {
          const int hb = crossing_segment_hits(b1, b2, at(ta[0]), at(ta[1]), at(ta[2]));
          if (hb >= 0) return hb == 1;
        }
      }
    } else if (shared == 0) {
      const Vec3& b0 = at(tb[0]);
      const Vec3& b1 = at(tb[1]);
      const Vec3& b2 = at(tb[2]);
      const int s0 = plane_side(pa, b0);
      if (s0 != 0 && s0 == plane_side(pa, b1) && s0 == plane_side(pa, b2)) return false;
      const Plane pb = plane_of(b0, b1, b2);
      const int r0 = plane_side(pb, at(ta[0]));
      if (r0 != 0 && r0 == plane_side(pb, at(ta[1])) && r0 == plane_side(pb, at(ta[2]))) return false;
    }
  }
  return pair_intersects(vertices, ta, tb);
}

/// A triangle's bounding box rounded outward to floats, and the grid cell of its lower corner.
struct CellBox {
  std::array<float, 3> lo;
  std::array<float, 3> hi;
  std::array<std::uint16_t, 3> cell_lo;
};

/// The next float below @p f (finite, not the lowest float), by its bit pattern.
inline float float_below(float f) {
  if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>(f > 0.0f ? bits - 1u : bits + 1u);
}
/// The largest float ≤ x and the smallest float ≥ x (|x| well inside the float range).
inline float round_down(double x) {
  const auto f = static_cast<float>(x);
  return static_cast<double>(f) > x ? float_below(f) : f;
}
inline float round_up(double x) {
  const auto f = static_cast<float>(x);
  return static_cast<double>(f) < x ? -float_below(-f) : f;
}

/// A uniform grid over the mesh's bounding box (cells of side h, at most 65 535 per axis).
struct Grid {
  std::array<double, 3> origin{};
  double inv_h = 0.0;
  std::array<std::uint32_t, 3> dims{};
  std::size_t cells = 0;

  [[nodiscard]] std::uint16_t cell(float x, int k) const {
    // Clamped first, so truncation is floor (and the map stays monotone in x).
    const double c = (static_cast<double>(x) - origin[static_cast<std::size_t>(k)]) * inv_h;
    return static_cast<std::uint16_t>(
        std::clamp(c, 0.0, static_cast<double>(dims[static_cast<std::size_t>(k)] - 1)));
  }
  [[nodiscard]] std::size_t key(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
    return (static_cast<std::size_t>(z) * dims[1] + y) * dims[0] + x;
  }
};

/// Chooses the grid: cell side 2× the mean (sampled) largest box extent of the triangles,
/// enlarged if the grid would exceed about 4 cells per triangle. Returns false when no
/// sensible grid exists (zero-size mesh box, coordinates beyond float range): the caller then
/// uses the BVH.
bool plan_grid(const TriangleMesh& mesh, Grid& grid) {
  const std::size_t n = mesh.triangles.size();
  Aabb all;
  for (const Vec3& v : mesh.vertices) all.extend(v);
  if (all.min.cwiseAbs().maxCoeff() > 1e30 || all.max.cwiseAbs().maxCoeff() > 1e30) return false;
  const std::size_t samples = std::min<std::size_t>(n, 2048);
  double mean_extent = 0.0;
  for (std::size_t s = 0; s < samples; ++s) {
    const Tri& t = mesh.triangles[s * n / samples];
    const Aabb b = Aabb::of_triangle(mesh.vertices[static_cast<std::size_t>(t[0])],
                                     mesh.vertices[static_cast<std::size_t>(t[1])],
                                     mesh.vertices[static_cast<std::size_t>(t[2])]);
    mean_extent += b.extent().maxCoeff();
  }
  mean_extent /= static_cast<double>(samples);
  // (Float boxes may reach a float step beyond the mesh box: cell() clamps, which keeps it
  // monotone, all the owner rule needs.)
  const Vec3 lo = all.min;
  const Vec3 ext = all.max - lo;
  double h = 2.0 * mean_extent;
  const double max_cells = 4.0 * static_cast<double>(n) + 4096.0;
  const double volume = std::max(ext.x(), 1e-300) * std::max(ext.y(), 1e-300) * std::max(ext.z(), 1e-300);
  if (!(h > 0.0) || !std::isfinite(h)) h = std::cbrt(volume / max_cells);
  for (int guard = 0; guard < 64; ++guard) {
    const Vec3 d = (ext / h).array().floor() + 1.0;
    if (d.prod() <= max_cells && d.maxCoeff() <= 65535.0) {
      grid.origin = {lo.x(), lo.y(), lo.z()};
      grid.inv_h = 1.0 / h;
      grid.dims = {static_cast<std::uint32_t>(d.x()), static_cast<std::uint32_t>(d.y()),
                   static_cast<std::uint32_t>(d.z())};
      grid.cells = static_cast<std::size_t>(d.prod());
      return std::isfinite(grid.inv_h) && grid.inv_h > 0.0;
    }
    h *= 1.25;
  }
  return false;
}

CellBox cell_box(const Grid& grid, const Vec3& a, const Vec3& b, const Vec3& c) {
  CellBox r{};
  for (int k = 0; k < 3; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    r.lo[ks] = round_down(std::min({a[k], b[k], c[k]}));
    r.hi[ks] = round_up(std::max({a[k], b[k], c[k]}));
    r.cell_lo[ks] = grid.cell(r.lo[ks], k);
  }
  return r;
}

inline bool boxes_overlap(const CellBox& p, const CellBox& q) {
  return p.lo[0] <= q.hi[0] && q.lo[0] <= p.hi[0] && p.lo[1] <= q.hi[1] && q.lo[1] <= p.hi[1] &&
         p.lo[2] <= q.hi[2] && q.lo[2] <= p.hi[2];
}

/// Work limits after which the grid gives up for the BVH (very uneven triangle sizes). The
/// entry limit also keeps entry indices (+ 1) within 32 bits.
std::size_t entry_budget(std::size_t n) { return std::min<std::size_t>(32 * n + 4096, 0xffff'0000u); }
std::size_t visit_budget(std::size_t n) { return 256 * n + (std::size_t{1} << 22); }

/// The cells of a box: [lo, hi] per axis.
struct CellRange {
  std::array<std::uint32_t, 3> lo;
  std::array<std::uint32_t, 3> hi;
};

CellRange cell_range(const Grid& grid, const CellBox& b) {
  return {{b.cell_lo[0], b.cell_lo[1], b.cell_lo[2]},
          {grid.cell(b.hi[0], 0), grid.cell(b.hi[1], 1), grid.cell(b.hi[2], 2)}};
}

/// Calls @p f(key) for every cell of @p r until it returns true; returns whether it did.
template <class F>
bool any_cell(const Grid& grid, const CellRange& r, F&& f) {
  for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z)
    for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y)
      for (std::uint32_t x = r.lo[0]; x <= r.hi[0]; ++x)
        if (f(grid.key(x, y, z))) return true;
  return false;
}

/// The owner rule that makes each overlapping pair count once: a pair shares every cell that
/// both boxes cover, and is taken only in the cell of the lower corner of the boxes'
/// intersection, max(lower cell of t, lower cell of u) per axis. In a cell (x, y, z) of t, a
/// triangle u of that cell passes when its lower cell equals the cell's coordinate on every
/// axis where the cell lies beyond t's lower cell (elsewhere it cannot exceed it).
struct OwnerTest {
  std::uint32_t x, y, z;
  bool need_x, need_y, need_z;
  [[nodiscard]] bool passes(const CellBox& bu) const {
    return !((need_x && bu.cell_lo[0] != x) || (need_y && bu.cell_lo[1] != y) ||
             (need_z && bu.cell_lo[2] != z));
  }
};

/// Linked lists of triangles per grid cell, filled incrementally: head[cell] is the last
/// entry inserted into the cell (index + 1; 0 for none), each entry links to the one before.
class CellLists {
 public:
  CellLists(const Grid& grid, std::size_t expected_entries) : m_head(grid.cells, 0) {
    m_entries.reserve(expected_entries);
  }

  /// Appends to @p candidates every triangle u of the lists whose float box overlaps @p bt
  /// (cells @p r) and whose pair with t is owned by the cell where it is seen (so each pair
  /// once). With kInsert, also inserts triangle @p t into every cell of @p r. Returns the
  /// number of list entries visited.
  template <bool kInsert>
  std::size_t visit(const Grid& grid, const std::vector<CellBox>& boxes, const CellBox& bt,
                    const CellRange& r, std::int32_t t, std::vector<std::int32_t>& candidates) {
    std::size_t visits = 0;
    for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z) {
      for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) {
        for (std::uint32_t x = r.lo[0]; x <= r.hi[0]; ++x) {
          const OwnerTest owner{x, y, z, x != r.lo[0], y != r.lo[1], z != r.lo[2]};
          std::uint32_t& cell_head = m_head[grid.key(x, y, z)];
          for (std::uint32_t e = cell_head; e != 0;) {
            const Entry entry = m_entries[e - 1];
            e = entry.next;
            ++visits;
            const CellBox& bu = boxes[static_cast<std::size_t>(entry.triangle)];
            if (owner.passes(bu) && boxes_overlap(bt, bu)) candidates.push_back(entry.triangle);
          }
          if constexpr (kInsert) {
            m_entries.push_back({cell_head, t});
            cell_head = static_cast<std::uint32_t>(m_entries.size());
          }
        }
      }
    }
    return visits;
  }

  /// Inserts triangle @p t into every cell of @p r, without visiting the lists.
  void insert(const Grid& grid, const CellRange& r, std::int32_t t) {
    any_cell(grid, r, [&](std::size_t key) {
      m_entries.push_back({m_head[key], t});
      m_head[key] = static_cast<std::uint32_t>(m_entries.size());
      return false;
    });
  }

  [[nodiscard]] std::size_t entries() const { return m_entries.size(); }

 private:
  struct Entry {
    std::uint32_t next;  // index + 1 of the cell's previous entry; 0: none
    std::int32_t triangle;
  };
  std::vector<std::uint32_t> m_head;
  std::vector<Entry> m_entries;
};

/// Shared state of one search: the mesh, the grid, every triangle's box, the stop flags.
struct Search {
  const TriangleMesh& mesh;
  const Grid& grid;
  bool first_only;
  std::vector<CellBox> boxes;
  std::atomic<bool> stop{false};      // first_only and a pair was found
  std::atomic<bool> gave_up{false};   // a work budget was exceeded: use the BVH instead
  std::size_t max_entries;            // per block
  std::size_t max_visits;             // per block pass

  [[nodiscard]] bool halted() const {
    return gave_up.load(std::memory_order_relaxed) ||
           (first_only && stop.load(std::memory_order_relaxed));
  }

  /// Narrow phase of t against @p candidates (all lower-numbered); appends hits (u, t).
  void test(std::int32_t t, const std::vector<std::int32_t>& candidates, Pairs& hits) {
    const auto& vertices = mesh.vertices;
    const Tri& tri = mesh.triangles[static_cast<std::size_t>(t)];
    const Plane pt = plane_of(vertices[static_cast<std::size_t>(tri[0])],
                              vertices[static_cast<std::size_t>(tri[1])],
                              vertices[static_cast<std::size_t>(tri[2])]);
    for (const std::int32_t u : candidates) {
      if (filtered_pair_intersects(vertices, tri, pt, mesh.triangles[static_cast<std::size_t>(u)])) {
        hits.emplace_back(u, t);
        if (first_only) {
          stop.store(true, std::memory_order_relaxed);
          return;
        }
      }
    }
  }

  /// Incremental pass over triangles [begin, end): each is boxed, tested against the block's
  /// earlier triangles in the cells of its box, then inserted there.
  void block_pass(CellLists& lists, std::size_t begin, std::size_t end, Pairs& hits) {
    std::vector<std::int32_t> candidates;
    std::size_t visits = 0;
    const auto& vertices = mesh.vertices;
    for (std::size_t ts = begin; ts < end; ++ts) {
      if ((ts & 255) == 0 && halted()) return;
      const Tri& tri = mesh.triangles[ts];
      const CellBox bt = cell_box(grid, vertices[static_cast<std::size_t>(tri[0])],
                                  vertices[static_cast<std::size_t>(tri[1])],
                                  vertices[static_cast<std::size_t>(tri[2])]);
      boxes[ts] = bt;
      candidates.clear();
      const auto t = static_cast<std::int32_t>(ts);
      visits += lists.visit<true>(grid, boxes, bt, cell_range(grid, bt), t, candidates);
      if (lists.entries() > max_entries || visits > max_visits) {
        gave_up.store(true, std::memory_order_relaxed);
        return;
      }
      if (!candidates.empty()) {
        test(t, candidates, hits);
        if (first_only && !hits.empty()) return;
      }
    }
  }

  /// Triangles [begin, end) (boxes known) against the finished lists of an earlier block.
  void cross_pass(const std::vector<CellLists*>& earlier, std::size_t begin, std::size_t end,
                  Pairs& hits) {
    std::vector<std::int32_t> candidates;
    std::size_t visits = 0;
    for (std::size_t ts = begin; ts < end; ++ts) {
      if ((ts & 255) == 0 && halted()) return;
      const CellBox& bt = boxes[ts];
      const CellRange r = cell_range(grid, bt);
      const auto t = static_cast<std::int32_t>(ts);
      candidates.clear();
      for (CellLists* lists : earlier) visits += lists->visit<false>(grid, boxes, bt, r, t, candidates);
      if (visits > max_visits) {
        gave_up.store(true, std::memory_order_relaxed);
        return;
      }
      if (!candidates.empty()) {
        test(t, candidates, hits);
        if (first_only && !hits.empty()) return;
      }
    }
  }
};

/// The search on the grid. Single-threaded: one incremental pass over all triangles (with
/// first_only it stops at the first intersecting pair, having touched only the triangles
/// before it). Threaded: the triangles are cut into one index block per worker; each block
/// runs its own incremental pass in parallel, then every block's triangles are tested against
/// the finished lists of the blocks before it, in parallel chunks. Returns false (out
/// untouched) when the grid gives up. Only the first @p n triangles take part.
bool grid_pairs(const TriangleMesh& mesh, const Grid& grid, bool threaded, bool first_only,
                std::size_t n, Pairs& out) {
  std::size_t blocks = 1;
  if (threaded) {
    const auto workers = static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
    blocks = std::clamp<std::size_t>(n / 8192, 1, workers);
  }
  Search search{mesh, grid, first_only, std::vector<CellBox>(n), {}, {}, entry_budget(n / blocks + 1),
                visit_budget(n / blocks + 1)};
  auto block_begin = [&](std::size_t b) { return b * n / blocks; };
  std::vector<std::unique_ptr<CellLists>> lists(blocks);
  std::vector<Pairs> hits(blocks);
  parallel_for(
      blocks,
      [&](std::size_t b) {
        lists[b] = std::make_unique<CellLists>(grid, 4 * (block_begin(b + 1) - block_begin(b)));
        search.block_pass(*lists[b], block_begin(b), block_begin(b + 1), hits[b]);
      },
      threaded, 1);
  Pairs found;
  for (const Pairs& h : hits) found.insert(found.end(), h.begin(), h.end());
  if (blocks > 1 && !search.halted()) {
    // Cross pass: block j (j ≥ 1) against blocks 0 … j − 1, in chunks of its triangles.
    constexpr std::size_t kChunk = 2048;
    struct Chunk {
      std::size_t block, begin, end;
    };
    std::vector<Chunk> chunks;
    for (std::size_t j = 1; j < blocks; ++j) {
      for (std::size_t b = block_begin(j); b < block_begin(j + 1); b += kChunk) {
        chunks.push_back({j, b, std::min(b + kChunk, block_begin(j + 1))});
      }
    }
    std::vector<Pairs> cross(chunks.size());
    parallel_for(
        chunks.size(),
        [&](std::size_t c) {
          std::vector<CellLists*> earlier;
          for (std::size_t i = 0; i < chunks[c].block; ++i) earlier.push_back(lists[i].get());
          search.cross_pass(earlier, chunks[c].begin, chunks[c].end, cross[c]);
        },
        threaded, 1);
    for (const Pairs& h : cross) found.insert(found.end(), h.begin(), h.end());
  }
  if (search.gave_up.load()) return false;
  std::sort(found.begin(), found.end());
  out = std::move(found);
  return true;
}

/// Whether consecutive triangles of the mesh tend to lie near each other (as from a
/// subdivision, a marching-cubes sweep or a strip-wise parameterisation): over a sample of
/// consecutive pairs, the share whose first corners are at most one cell apart per axis.
bool index_order_is_local(const TriangleMesh& mesh, const Grid& grid) {
  const std::size_t n = mesh.triangles.size();
  const std::size_t samples = std::min<std::size_t>(n - 1, 1024);
  auto cell_of = [&](std::size_t t, int k) {
    const Vec3& v = mesh.vertices[static_cast<std::size_t>(mesh.triangles[t][0])];
    return static_cast<int>(grid.cell(static_cast<float>(v[k]), k));
  };
  std::size_t near = 0;
  for (std::size_t s = 0; s < samples; ++s) {
    const std::size_t t = s * (n - 1) / samples;
    near += std::abs(cell_of(t, 0) - cell_of(t + 1, 0)) <= 1 && std::abs(cell_of(t, 1) - cell_of(t + 1, 1)) <= 1 &&
            std::abs(cell_of(t, 2) - cell_of(t + 1, 2)) <= 1;
  }
  return 2 * near >= samples;
}

/// A copy of @p mesh (vertices and triangles only) with the triangles in grid-cell order
/// (row-major cell of the first corner, a counting sort) and the vertices renumbered in order
/// of first use, so that the search walks memory in order; order[s] is the original id of
/// triangle s. Sharing of vertex indices is unchanged (the renumbering is a bijection on the
/// used vertices).
TriangleMesh spatially_sorted(const TriangleMesh& mesh, const Grid& grid, std::vector<std::int32_t>& order) {
  const std::size_t n = mesh.triangles.size();
  std::vector<std::uint32_t> key(n);
  std::vector<std::uint32_t> start(grid.cells + 1, 0);
  for (std::size_t t = 0; t < n; ++t) {
    const Vec3& v = mesh.vertices[static_cast<std::size_t>(mesh.triangles[t][0])];
    key[t] = static_cast<std::uint32_t>(grid.key(grid.cell(static_cast<float>(v.x()), 0),
                                                 grid.cell(static_cast<float>(v.y()), 1),
                                                 grid.cell(static_cast<float>(v.z()), 2)));
    ++start[key[t] + 1];
  }
  for (std::size_t c = 0; c < grid.cells; ++c) start[c + 1] += start[c];
  order.assign(n, 0);
  for (std::size_t t = 0; t < n; ++t) order[start[key[t]]++] = static_cast<std::int32_t>(t);
  TriangleMesh sorted;
  sorted.triangles.resize(n);
  std::vector<std::int32_t> new_id(mesh.vertices.size(), -1);
  sorted.vertices.reserve(mesh.vertices.size());
  for (std::size_t s = 0; s < n; ++s) {
    const Tri& t = mesh.triangles[static_cast<std::size_t>(order[s])];
    for (std::size_t k = 0; k < 3; ++k) {
      std::int32_t& id = new_id[static_cast<std::size_t>(t[k])];
      if (id < 0) {
        id = static_cast<std::int32_t>(sorted.vertices.size());
        sorted.vertices.push_back(mesh.vertices[static_cast<std::size_t>(t[k])]);
      }
      sorted.triangles[s][k] = id;
    }
  }
  return sorted;
}

Pairs find_pairs(const TriangleMesh& mesh, const SelfIntersectionOptions& options, bool first_only) {
  validate_mesh(mesh);
  Pairs out;
  if (mesh.triangles.size() < 2) return out;
  Grid grid;
  if (plan_grid(mesh, grid)) {
    const std::size_t n = mesh.triangles.size();
    if (index_order_is_local(mesh, grid)) {
      if (grid_pairs(mesh, grid, options.threaded, first_only, n, out)) return out;
    } else {
      // Without index locality the search runs on a spatially sorted copy. An early-exit
      // query first probes a prefix in input order (a sixteenth of the triangles, cheap while
      // the grid is sparse): a mesh with many intersecting pairs shows one there, before the
      // sort is paid for.
      if (first_only && grid_pairs(mesh, grid, false, true, n / 16, out) && !out.empty()) return out;
      out.clear();
      std::vector<std::int32_t> order;
      const TriangleMesh sorted = spatially_sorted(mesh, grid, order);
      if (grid_pairs(sorted, grid, options.threaded, first_only, n, out)) {
        for (auto& [u, t] : out) {
          u = order[static_cast<std::size_t>(u)];
          t = order[static_cast<std::size_t>(t)];
          if (u > t) std::swap(u, t);
        }
        std::sort(out.begin(), out.end());
        return out;
      }
    }
  }
  auto accept = [&](std::int32_t i, std::int32_t j) {
    return pair_intersects(mesh.vertices, mesh.triangles[static_cast<std::size_t>(i)],
                           mesh.triangles[static_cast<std::size_t>(j)]);
  };
  const TriangleBvh bvh(mesh);
  if (first_only) {
    if (bvh.any_self_pair(accept, options.threaded)) out.emplace_back(-1, -1);
    return out;
  }
  return bvh.self_pairs(accept, options.threaded);
}

/// The pairs with at least one flagged triangle, on the grid: every triangle is boxed, the
/// cells the flagged ones cover are marked, and the triangles that reach a marked cell are
/// inserted (no visits); then each flagged triangle visits the cells of its box, taking an
/// unflagged neighbour always and a flagged one only when its index is higher (so each pair
/// once; the owner rule keeps a pair to one cell). Returns false when the grid gives up.
bool grid_pairs_touching(const TriangleMesh& mesh, const Grid& grid, const std::vector<std::uint8_t>& changed,
                         bool threaded, Pairs& out) {
  const std::size_t n = mesh.triangles.size();
  const auto& vertices = mesh.vertices;
  std::vector<CellBox> boxes(n);
  parallel_for(
      n,
      [&](std::size_t ts) {
        const Tri& tri = mesh.triangles[ts];
        boxes[ts] = cell_box(grid, vertices[static_cast<std::size_t>(tri[0])],
                             vertices[static_cast<std::size_t>(tri[1])], vertices[static_cast<std::size_t>(tri[2])]);
      },
      threaded, 4096);
  std::vector<std::int32_t> flagged;
  std::vector<std::uint8_t> marked(grid.cells, 0);
  for (std::size_t ts = 0; ts < n; ++ts) {
    if (!changed[ts]) continue;
    flagged.push_back(static_cast<std::int32_t>(ts));
    any_cell(grid, cell_range(grid, boxes[ts]), [&](std::size_t key) {
      marked[key] = 1;
      return false;
    });
  }
  CellLists lists(grid, 4 * flagged.size() + 4096);
  for (std::size_t ts = 0; ts < n; ++ts) {
    const CellRange r = cell_range(grid, boxes[ts]);
    if (!changed[ts] && !any_cell(grid, r, [&](std::size_t key) { return marked[key] != 0; })) continue;
    lists.insert(grid, r, static_cast<std::int32_t>(ts));
    if (lists.entries() > entry_budget(n)) return false;
  }
  constexpr std::size_t kChunk = 256;
  const std::size_t chunks = (flagged.size() + kChunk - 1) / kChunk;
  std::vector<Pairs> hits(chunks);
  std::atomic<std::size_t> visits{0};
  const std::size_t max_visits = visit_budget(n);
  parallel_for(
      chunks,
      [&](std::size_t c) {
        std::vector<std::int32_t> candidates;
        std::size_t local_visits = 0;
        for (std::size_t f = c * kChunk; f < std::min(flagged.size(), (c + 1) * kChunk); ++f) {
          const std::int32_t t = flagged[f];
          const auto ts = static_cast<std::size_t>(t);
          candidates.clear();
          local_visits += lists.visit<false>(grid, boxes, boxes[ts], cell_range(grid, boxes[ts]), t, candidates);
          const Tri& tri = mesh.triangles[ts];
          const Plane pt = plane_of(vertices[static_cast<std::size_t>(tri[0])], vertices[static_cast<std::size_t>(tri[1])],
                                    vertices[static_cast<std::size_t>(tri[2])]);
          for (const std::int32_t u : candidates) {
            if (u == t || (changed[static_cast<std::size_t>(u)] && u < t)) continue;
            if (filtered_pair_intersects(vertices, tri, pt, mesh.triangles[static_cast<std::size_t>(u)]))
              hits[c].emplace_back(std::min(u, t), std::max(u, t));
          }
        }
        visits += local_visits;
      },
      threaded, 1);
  if (visits.load() > max_visits) return false;
  Pairs found;
  for (const Pairs& h : hits) found.insert(found.end(), h.begin(), h.end());
  std::sort(found.begin(), found.end());
  out = std::move(found);
  return true;
}

}  // namespace

std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections(
    const TriangleMesh& mesh, const SelfIntersectionOptions& options) {
  return find_pairs(mesh, options, false);
}

std::vector<std::pair<std::int32_t, std::int32_t>> self_intersections_touching(
    const TriangleMesh& mesh, const std::vector<std::uint8_t>& changed, const SelfIntersectionOptions& options) {
  if (changed.size() != mesh.triangles.size())
    throw InvalidInput("self intersections: one changed flag per triangle is needed (" +
                       std::to_string(mesh.triangles.size()) + "), got " + std::to_string(changed.size()));
  validate_mesh(mesh);
  Pairs out;
  if (mesh.triangles.size() < 2 || std::none_of(changed.begin(), changed.end(), [](std::uint8_t c) { return c != 0; }))
    return out;
  Grid grid;
  if (plan_grid(mesh, grid) && grid_pairs_touching(mesh, grid, changed, options.threaded, out)) return out;
  // No sensible grid: the whole search, keeping the pairs with a flagged triangle.
  out = find_pairs(mesh, options, false);
  std::erase_if(out, [&](const auto& p) {
    return !changed[static_cast<std::size_t>(p.first)] && !changed[static_cast<std::size_t>(p.second)];
  });
  return out;
}

bool has_self_intersections(const TriangleMesh& mesh, const SelfIntersectionOptions& options) {
  return !find_pairs(mesh, options, true).empty();
}

}  // namespace ido::geometry

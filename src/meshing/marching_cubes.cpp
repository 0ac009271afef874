// SPDX-License-Identifier: Apache-2.0
// Topologically consistent marching cubes; the project's own implementation.
//
// The case table is generated at start-up (Bloomenthal 1994 walks face segments into
// polygons; Lorensen & Cline 1987 for the cube-case idea). The extraction runs in three
// data-parallel passes over rows of a one-voxel padded grid, in the spirit of Flying Edges
// (Schroeder, Maynard & Geveci 2015): (A) classify voxels inside/outside and record each
// row's inside range, (B) count vertices per voxel row and triangles per cube row, (C) after
// prefix sums, write vertex positions and triangles at precomputed offsets. A vertex's id
// is its rank among the cut edges of its row (edges ordered by i, then axis x, y, z), so
// vertices are welded by construction and the output does not depend on threading.
#include "ido/meshing/marching_cubes.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "ido/core/error.h"
#include "ido/core/parallel.h"

namespace ido::meshing {
namespace {

// ---- case table -------------------------------------------------------------------------
// Corner c sits at (c&1, (c>>1)&1, (c>>2)&1). Edge e = 4·axis + n joins corner
// kEdgeCorner[e] (whose bit `axis` is clear) to kEdgeCorner[e] | (1 << axis).

struct EdgeDef {
  int corner;
  int axis;
};

constexpr std::array<EdgeDef, 12> make_edges() {
  std::array<EdgeDef, 12> e{};
  int n = 0;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 8; ++c)
      if (!((c >> a) & 1)) e[static_cast<std::size_t>(n++)] = {c, a};
  return e;
}
constexpr std::array<EdgeDef, 12> kEdges = make_edges();

int edge_between(int c0, int c1) {
  const int diff = c0 ^ c1;
  const int axis = diff == 1 ? 0 : diff == 2 ? 1 : 2;
  const int lo = std::min(c0, c1);
  for (int e = 0; e < 12; ++e)
    if (kEdges[static_cast<std::size_t>(e)].corner == lo && kEdges[static_cast<std::size_t>(e)].axis == axis) return e;
  throw std::logic_error("marching cubes: corners are not adjacent");
}

/// True when cube edges @p e1 and @p e2 lie in a common cube face.
bool share_face(int e1, int e2) {
  const EdgeDef a = kEdges[static_cast<std::size_t>(e1)], b = kEdges[static_cast<std::size_t>(e2)];
  for (int ax = 0; ax < 3; ++ax) {
    if (ax == a.axis || ax == b.axis) continue;
    if (((a.corner >> ax) & 1) == ((b.corner >> ax) & 1)) return true;
  }
  return false;
}

struct CaseTable {
  std::array<std::uint16_t, 257> begin{};          // triangles of case c: [begin[c], begin[c+1])
  std::vector<std::array<std::uint8_t, 3>> tris;   // cube-edge triples, CCW from outside
  std::array<std::uint16_t, 256> edge_mask{};      // cut edges of each case
};

Eigen::Vector3d edge_midpoint(int e) {
  const EdgeDef d = kEdges[static_cast<std::size_t>(e)];
  Eigen::Vector3d p(d.corner & 1, (d.corner >> 1) & 1, (d.corner >> 2) & 1);
  p[d.axis] += 0.5;
  return p;
}

Eigen::Vector3d corner_pos(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

/// Triangulates polygon @p p (cube-edge ids in order) without any diagonal joining two
/// edges of one cube face; appends to @p out. Returns false if impossible.
bool triangulate(const std::vector<int>& p, std::vector<std::array<std::uint8_t, 3>>& out) {
  const std::size_t m = p.size();
  if (m == 3) {
    out.push_back({std::uint8_t(p[0]), std::uint8_t(p[1]), std::uint8_t(p[2])});
    return true;
  }
  // Triangle (p0, pk, p_{m-1}) plus the two sub-polygons on either side.
  for (std::size_t k = 1; k + 1 < m; ++k) {
    if (k > 1 && share_face(p[0], p[k])) continue;
    if (k + 2 < m && share_face(p[k], p[m - 1])) continue;
    std::vector<std::array<std::uint8_t, 3>> trial;
    trial.push_back({std::uint8_t(p[0]), std::uint8_t(p[k]), std::uint8_t(p[m - 1])});
    bool ok = true;
    if (k > 1) ok = triangulate(std::vector<int>(p.begin(), p.begin() + std::ptrdiff_t(k) + 1), trial);
    if (ok && k + 2 < m) ok = triangulate(std::vector<int>(p.begin() + std::ptrdiff_t(k), p.end()), trial);
    if (ok) {
      out.insert(out.end(), trial.begin(), trial.end());
      return true;
    }
  }
  return false;
}

CaseTable build_table() {
  CaseTable t;
  for (int cs = 0; cs < 256; ++cs) {
    t.begin[static_cast<std::size_t>(cs)] = static_cast<std::uint16_t>(t.tris.size());
    auto in = [cs](int c) { return ((cs >> c) & 1) != 0; };
    std::array<std::array<int, 2>, 12> nb;
    for (auto& x : nb) x = {-1, -1};
    auto link = [&nb](int e1, int e2) {
      for (int rep = 0; rep < 2; ++rep) {
        auto& slot = nb[static_cast<std::size_t>(e1)];
        (slot[0] < 0 ? slot[0] : slot[1]) = e2;
        std::swap(e1, e2);
      }
    };
    std::uint16_t mask = 0;
    for (int e = 0; e < 12; ++e) {
      const EdgeDef d = kEdges[static_cast<std::size_t>(e)];
      if (in(d.corner) != in(d.corner | (1 << d.axis))) mask = std::uint16_t(mask | (1u << e));
    }
    t.edge_mask[static_cast<std::size_t>(cs)] = mask;
    // Face segments.
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < 2; ++s) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        int q[4];
        for (int m = 0; m < 4; ++m) q[m] = (s << a) | (uv[m][0] << b) | (uv[m][1] << c);
        int fe[4];
        bool cut[4];
        int ncut = 0;
        for (int m = 0; m < 4; ++m) {
          fe[m] = edge_between(q[m], q[(m + 1) % 4]);
          cut[m] = in(q[m]) != in(q[(m + 1) % 4]);
          ncut += cut[m];
        }
        if (ncut == 2) {
          int first = -1;
          for (int m = 0; m < 4; ++m)
            if (cut[m]) {
              if (first < 0) first = fe[m];
              else link(first, fe[m]);
            }
        } else if (ncut == 4) {
          // Ambiguous face: cut off each inside corner on its own (inside separated).
          for (int m = 0; m < 4; ++m)
            if (in(q[m])) link(fe[(m + 3) % 4], fe[m]);
        }
      }
    // Walk the segments into cycles, orient them, triangulate.
    std::array<bool, 12> seen{};
    for (int e0 = 0; e0 < 12; ++e0) {
      if (!((mask >> e0) & 1) || seen[static_cast<std::size_t>(e0)]) continue;
      std::vector<int> poly;
      int prev = -1, cur = e0;
      do {
        poly.push_back(cur);
        seen[static_cast<std::size_t>(cur)] = true;
        const auto& n = nb[static_cast<std::size_t>(cur)];
        const int next = n[0] != prev ? n[0] : n[1];
        prev = cur;
        cur = next;
        if (cur < 0) throw std::logic_error("marching cubes table: open polygon");
      } while (cur != e0);
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      for (std::size_t k = 0; k < poly.size(); ++k)
        normal += edge_midpoint(poly[k]).cross(edge_midpoint(poly[(k + 1) % poly.size()]));
      double side = 0.0;
      for (int e : poly) {
        const EdgeDef d = kEdges[static_cast<std::size_t>(e)];
        const int c0 = d.corner, c1 = d.corner | (1 << d.axis);
        const int inside = in(c0) ? c0 : c1, outside = in(c0) ? c1 : c0;
        side += (corner_pos(outside) - corner_pos(inside)).dot(normal);
      }
      if (std::abs(side) < 1e-9) throw std::logic_error("marching cubes table: unorientable polygon");
      if (side < 0) std::reverse(poly.begin(), poly.end());
      if (!triangulate(poly, t.tris)) throw std::logic_error("marching cubes table: no valid triangulation");
    }
  }
  t.begin[256] = static_cast<std::uint16_t>(t.tris.size());
  return t;
}

const CaseTable& table() {
  static const CaseTable t = build_table();
  return t;
}

// ---- extraction -------------------------------------------------------------------------

/// Number of set bits of a 3-bit edge mask (no popcnt instruction is assumed).
constexpr int pop3(unsigned v) { return int((0xE994u >> (2u * (v & 7u))) & 3u); }
static_assert(pop3(0) == 0 && pop3(5) == 2 && pop3(7) == 3 && pop3(4) == 1);

/// Extraction over a field of voxel type T. `Inside(v)` classifies a voxel value,
/// `Crossing(v0, v1)` gives the edge parameter t ∈ (0,1) from the first voxel.
template <class T, class Inside, class Crossing>
geometry::TriangleMesh extract(const image::Volume<T>& field, bool threaded, Inside inside_of,
                               Crossing crossing) {
  geometry::TriangleMesh mesh;
  if (field.empty()) return mesh;
  const CaseTable& tab = table();
  const std::int64_t nx = field.size(0), ny = field.size(1), nz = field.size(2);
  const std::int64_t X = nx + 2, Y = ny + 2, Z = nz + 2;  // padded grid
  const std::size_t rows = static_cast<std::size_t>(Y * Z);
  // One extra zero slice and row at the end so that neighbour reads past the padded grid
  // (edges leaving it) see "outside" and never count as cut.
  std::vector<std::uint8_t> in(static_cast<std::size_t>(X * Y * (Z + 1) + X + 2), 0);
  std::vector<std::int32_t> lo(rows, INT_MAX / 2), hi(rows, -1);  // inside range per row
  const T* f = field.data().data();

  // Pass A: classification.
  parallel_for_ranges(
      rows,
      [&](std::size_t b, std::size_t e) {
        for (std::size_t r = b; r < e; ++r) {
          const std::int64_t y = std::int64_t(r) % Y, z = std::int64_t(r) / Y;
          if (y == 0 || z == 0 || y == Y - 1 || z == Z - 1) continue;
          const T* src = f + field.linear_index(0, y - 1, z - 1);
          std::uint8_t* dst = in.data() + r * std::size_t(X) + 1;
          // Local copies of the classifier and the bound: stores through uint8_t* may alias
          // anything, so values read through references would be reloaded every voxel.
          const Inside cls = inside_of;
          const std::int64_t count = nx;
          for (std::int64_t i = 0; i < count; ++i) dst[i] = cls(src[i]) ? 1 : 0;  // vectorises
          std::int32_t rl = INT_MAX / 2, rh = -1;
          if (const void* first = std::memchr(dst, 1, std::size_t(nx))) {
            rl = std::int32_t(static_cast<const std::uint8_t*>(first) - dst) + 1;
            rh = std::int32_t(static_cast<const std::uint8_t*>(memrchr(dst, 1, std::size_t(nx))) - dst) + 1;
          }
          lo[r] = rl;
          hi[r] = rh;
        }
      },
      threaded, 64);

  const std::size_t dy = std::size_t(X), dz = std::size_t(X * Y);
  auto ebits = [&](std::size_t r, std::int64_t x) -> unsigned {
    const std::uint8_t* p = in.data() + r * dy + std::size_t(x);
    return unsigned(p[0] ^ p[1]) | unsigned(p[0] ^ p[dy]) << 1 | unsigned(p[0] ^ p[dz]) << 2;
  };
  auto empty_row = [&](std::int64_t y, std::int64_t z) {
    return y >= Y || z >= Z || lo[std::size_t(y + Y * z)] > hi[std::size_t(y + Y * z)];
  };
  // Range of x whose owned edges may be cut in row (y, z).
  auto edge_range = [&](std::int64_t y, std::int64_t z, std::int64_t& a, std::int64_t& b) {
    a = INT_MAX / 2;
    b = -1;
    const std::int64_t ys[3] = {y, y + 1, y}, zs[3] = {z, z, z + 1};
    for (int n = 0; n < 3; ++n) {
      if (empty_row(ys[n], zs[n])) continue;
      const std::size_t rr = std::size_t(ys[n] + Y * zs[n]);
      a = std::min<std::int64_t>(a, lo[rr] - (n == 0 ? 1 : 0));
      b = std::max<std::int64_t>(b, hi[rr]);
    }
  };
  // Range of cube x for cube row (y, z).
  auto cube_range = [&](std::int64_t y, std::int64_t z, std::int64_t& a, std::int64_t& b) {
    a = INT_MAX / 2;
    b = -1;
    if (y >= Y - 1 || z >= Z - 1) return;
    for (int n = 0; n < 4; ++n) {
      const std::int64_t yy = y + (n & 1), zz = z + (n >> 1);
      if (empty_row(yy, zz)) continue;
      const std::size_t rr = std::size_t(yy + Y * zz);
      a = std::min<std::int64_t>(a, lo[rr] - 1);
      b = std::max<std::int64_t>(b, hi[rr]);
    }
    b = std::min<std::int64_t>(b, X - 2);
  };

  // Pass B: counts. Cube cases are read in a column-major bit order, qcase = q(x) | q(x+1)<<4
  // with q(x) = r00 | r10<<1 | r01<<2 | r11<<3, and mapped to the table's order by to_case.
  std::array<std::uint8_t, 256> to_case{}, qtri{};
  for (unsigned qc = 0; qc < 256; ++qc) {
    unsigned cs = 0;
    for (unsigned bit = 0; bit < 8; ++bit)
      if ((qc >> bit) & 1u) cs |= 1u << ((bit >> 2) + 2 * (bit & 3u));  // corner cx + 2·(cy + 2cz)
    to_case[qc] = std::uint8_t(cs);
    qtri[qc] = std::uint8_t(tab.begin[cs + 1] - tab.begin[cs]);
  }
  // q(x) of a cube row over [a0, a1 + 1].
  auto fill_q = [&](std::size_t r, std::int64_t a0, std::int64_t a1, std::uint8_t* q) {
    const std::uint8_t* r00 = in.data() + r * dy;
    const std::uint8_t *r10 = r00 + dy, *r01 = r00 + dz, *r11 = r00 + dy + dz;
    for (std::int64_t x = a0; x <= a1 + 1; ++x)
      q[x - a0] = std::uint8_t(r00[x] | r10[x] << 1 | r01[x] << 2 | r11[x] << 3);
  };
  // Cut-edge bits of voxel row r over [a0, a1].
  auto fill_e = [&](std::size_t r, std::int64_t a0, std::int64_t a1, std::uint8_t* out) {
    const std::uint8_t* p = in.data() + r * dy;
    const std::uint8_t *py = p + dy, *pz = p + dz;
    for (std::int64_t x = a0; x <= a1; ++x)
      out[x - a0] = std::uint8_t((p[x] ^ p[x + 1]) | (p[x] ^ py[x]) << 1 | (p[x] ^ pz[x]) << 2);
  };
  std::vector<std::int64_t> vcount(rows + 1, 0), tcount(rows + 1, 0);
  parallel_for_ranges(
      rows,
      [&](std::size_t b, std::size_t e) {
        std::vector<std::uint8_t> q(std::size_t(X) + 2);
        for (std::size_t r = b; r < e; ++r) {
          const std::int64_t y = std::int64_t(r) % Y, z = std::int64_t(r) / Y;
          std::int64_t a0, a1;
          edge_range(y, z, a0, a1);
          const std::uint8_t* p = in.data() + r * dy;
          const std::uint8_t *py = p + dy, *pz = p + dz;
          std::uint32_t nv = 0;
          for (std::int64_t x = a0; x <= a1; ++x) nv += unsigned(p[x] ^ p[x + 1]) + unsigned(p[x] ^ py[x]) + unsigned(p[x] ^ pz[x]);
          vcount[r] = nv;
          cube_range(y, z, a0, a1);
          if (a0 > a1) continue;
          fill_q(r, a0, a1, q.data());
          std::int64_t nt = 0;
          for (std::int64_t x = 0; x <= a1 - a0; ++x) nt += qtri[unsigned(q[std::size_t(x)]) | unsigned(q[std::size_t(x) + 1]) << 4];
          tcount[r] = nt;
        }
      },
      threaded, 64);
  // Exclusive prefix sums.
  std::int64_t vs = 0, ts = 0;
  for (std::size_t r = 0; r <= rows; ++r) {
    const std::int64_t v = vcount[r], t = tcount[r];
    vcount[r] = vs;
    tcount[r] = ts;
    vs += v;
    ts += t;
  }
  if (vs > INT32_MAX) throw InvalidInput("marching_cubes: surface has too many vertices for 32-bit ids");
  mesh.vertices.resize(std::size_t(vs));
  mesh.triangles.resize(std::size_t(ts));

  const Mat3 m = field.index_to_world_matrix();
  const Vec3 origin = field.origin();
  const bool flip = m.determinant() < 0.0;
  const std::int64_t dgrid[3] = {1, nx, nx * ny};

  // Pass C: vertices and triangles.
  parallel_for_ranges(
      rows,
      [&](std::size_t b, std::size_t e) {
        std::vector<std::uint8_t> q(std::size_t(X) + 2), eb[4];
        for (auto& v : eb) v.resize(std::size_t(X) + 2);
        for (std::size_t r = b; r < e; ++r) {
          const std::int64_t y = std::int64_t(r) % Y, z = std::int64_t(r) / Y;
          std::int64_t a0, a1;
          edge_range(y, z, a0, a1);
          std::int64_t id = vcount[r];
          if (a0 <= a1) fill_e(r, a0, a1, eb[0].data());
          for (std::int64_t x = a0; x <= a1; ++x) {
            const unsigned bits = eb[0][std::size_t(x - a0)];
            if (!bits) continue;
            const Vec3 p(double(x - 1), double(y - 1), double(z - 1));  // grid index
            const bool p_in_grid = x >= 1 && x <= nx && y >= 1 && y <= ny && z >= 1 && z <= nz;
            for (int ax = 0; ax < 3; ++ax) {
              if (!((bits >> ax) & 1)) continue;
              double t = 0.5;
              const std::int64_t qq[3] = {x + (ax == 0), y + (ax == 1), z + (ax == 2)};
              const bool q_in_grid = qq[0] <= nx && qq[1] <= ny && qq[2] <= nz;
              if (p_in_grid && q_in_grid) {
                const std::size_t lp = field.linear_index(x - 1, y - 1, z - 1);
                t = crossing(f[lp], f[lp + std::size_t(dgrid[ax])]);
              }
              Vec3 idx = p;
              idx[ax] += t;
              mesh.vertices[std::size_t(id++)] = origin + m * idx;
            }
          }
          // Triangles of cube row (y, z).
          cube_range(y, z, a0, a1);
          if (a0 > a1) continue;
          const std::size_t rows4[4] = {r, r + 1, r + std::size_t(Y), r + std::size_t(Y) + 1};
          std::int64_t cnt[4];
          for (int n = 0; n < 4; ++n) {
            // Rank of the first edge at x = a0 in each of the four voxel rows.
            std::int64_t ra0, ra1;
            edge_range((y + (n & 1)), z + (n >> 1), ra0, ra1);
            cnt[n] = vcount[rows4[n]];
            for (std::int64_t x = ra0; x < a0 && x <= ra1; ++x) cnt[n] += pop3(ebits(rows4[n], x));
            fill_e(rows4[n], a0, a1 + 1, eb[std::size_t(n)].data());
          }
          fill_q(r, a0, a1, q.data());
          std::size_t tout = std::size_t(tcount[r]);
          for (std::int64_t x = a0; x <= a1; ++x) {
            const std::size_t u = std::size_t(x - a0);
            const unsigned qc = unsigned(q[u]) | unsigned(q[u + 1]) << 4;
            if (qtri[qc]) {
              const unsigned cs = to_case[qc];
              std::int32_t eid[12];
              const unsigned mask = tab.edge_mask[cs];
              for (int ce = 0; ce < 12; ++ce) {
                if (!((mask >> ce) & 1)) continue;
                const EdgeDef d = kEdges[std::size_t(ce)];
                const int n = (d.corner >> 1) & 3;
                const bool xo = d.corner & 1;
                const unsigned lo_bits = eb[std::size_t(n)][u], hi_bits = eb[std::size_t(n)][u + 1];
                const unsigned below = (1u << d.axis) - 1u;
                eid[ce] = std::int32_t(cnt[n] + (xo ? pop3(lo_bits) : 0) +
                                       pop3((xo ? hi_bits : lo_bits) & below));
              }
              for (unsigned k = tab.begin[cs]; k < tab.begin[cs + 1]; ++k) {
                const auto& tri = tab.tris[k];
                Tri out{eid[tri[0]], eid[tri[1]], eid[tri[2]]};
                if (flip) std::swap(out[1], out[2]);
                mesh.triangles[tout++] = out;
              }
            }
            for (int n = 0; n < 4; ++n) cnt[n] += pop3(unsigned(eb[std::size_t(n)][u]));
          }
        }
      },
      threaded, 64);
  return mesh;
}

}  // namespace

geometry::TriangleMesh marching_cubes(const image::Volume<float>& field,
                                      const MarchingCubesOptions& options) {
  const float iso = options.iso_value;
  if (std::isnan(iso)) throw InvalidInput("marching_cubes: iso value is NaN");
  return extract(
      field, options.threaded, [iso](float v) { return v < iso; },
      [iso](float v0, float v1) {
        const double t = (double(iso) - double(v0)) / (double(v1) - double(v0));
        return std::isfinite(t) ? std::clamp(t, 0.001, 0.999) : 0.5;
      });
}

geometry::TriangleMesh marching_cubes_mask(const image::Volume<std::uint8_t>& mask, bool threaded) {
  return extract(
      mask, threaded, [](std::uint8_t v) { return v != 0; },
      [](std::uint8_t, std::uint8_t) { return 0.5; });
}

int marching_cubes_case_triangle_count(int cube_case) {
  if (cube_case < 0 || cube_case > 255) throw InvalidInput("marching cubes case must be in [0, 255]");
  const auto& t = table();
  return t.begin[std::size_t(cube_case) + 1] - t.begin[std::size_t(cube_case)];
}

}  // namespace ido::meshing

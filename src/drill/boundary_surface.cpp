// SPDX-License-Identifier: Apache-2.0
// Hand-written: the project's v_list extraction across hierarchy levels and conforming assembly.
#include "ido/drill/boundary_surface.h"

#include <algorithm>
#include <cmath>
#include <atomic>
#include <limits>
#include <string>
#include <thread>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "ido/core/error.h"
#include "point_index.h"

namespace ido::drill {
namespace {

// Outward face vertex order of a positively oriented tetrahedron: face f is opposite f.
constexpr int kFaceVerts[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// Unordered pair code of a child vertex (parent vertex indices a, b).
int pair_code(int a, int b) { return a < b ? a * 4 + b : b * 4 + a; }

// What lies across face f of node n. For a neighbour at the same depth, vmap[k] gives, for
// each vertex k ≠ f of n, the index of the same point among the neighbour's vertices.
struct Across {
  bool boundary = false;
  NodeRef node;
  int face = -1;
  std::array<int, 4> vmap{-1, -1, -1, -1};
  std::uint32_t word = TetHierarchy::kErased;  ///< storage word of `node` (boundary: erased)
};


// Child c of a node with vertex-pair codes `codes` (3 pairs in the node's local indices, on
// the node's face g): finds the child slot, its face on g, and its local index per code.
bool find_child_face_search(int g, const std::array<int, 3>& codes, int& child, int& child_face,
                            std::array<int, 3>& local) {
  const TreeTable& t = TreeTable::get();
  for (int c = 0; c < 8; ++c)
    for (int cg = 0; cg < 4; ++cg) {
      if (t.face_link[static_cast<std::size_t>(c)][static_cast<std::size_t>(cg)].parent_face != g) continue;
      bool all = true;
      for (std::size_t i = 0; i < 3 && all; ++i) {
        int found = -1;
        for (int k = 0; k < 4; ++k) {
          if (k == cg) continue;
          const auto& e = t.vertex[static_cast<std::size_t>(c)][static_cast<std::size_t>(k)];
          if (pair_code(e[0], e[1]) == codes[i]) found = k;
        }
        local[i] = found;
        all = found >= 0;
      }
      if (all) {
        child = c;
        child_face = cg;
        return true;
      }
    }
  return false;
}

// find_child_face_search tabulated once over every (face, code, code, code) combination
// (pair codes are < 16), so the v_list walk does a single look-up.
struct ChildFaceTable {
  struct Entry {
    std::int8_t child = -1, child_face = -1;
    std::array<std::int8_t, 3> local{};
  };
  std::vector<Entry> e;
  ChildFaceTable() : e(4 * 16 * 16 * 16) {
    for (int g = 0; g < 4; ++g)
      for (int a = 0; a < 16; ++a)
        for (int b = 0; b < 16; ++b)
          for (int c = 0; c < 16; ++c) {
            int ch = -1, cf = -1;
            std::array<int, 3> loc{};
            if (!find_child_face_search(g, {a, b, c}, ch, cf, loc)) continue;
            auto& x = e[static_cast<std::size_t>(((g * 16 + a) * 16 + b) * 16 + c)];
            x.child = static_cast<std::int8_t>(ch);
            x.child_face = static_cast<std::int8_t>(cf);
            for (std::size_t i = 0; i < 3; ++i) x.local[i] = static_cast<std::int8_t>(loc[i]);
          }
  }
};

const ChildFaceTable& child_face_table() {
  static const ChildFaceTable table;
  return table;
}

bool find_child_face(const ChildFaceTable& table, int g, const std::array<int, 3>& codes, int& child, int& child_face,
                     std::array<int, 3>& local) {
  if (g < 0 || g > 3) return false;
  for (const int c : codes)
    if (c < 0 || c > 15) return false;
  const auto& x = table.e[static_cast<std::size_t>(((g * 16 + codes[0]) * 16 + codes[1]) * 16 + codes[2])];
  if (x.child < 0) return false;
  child = x.child;
  child_face = x.child_face;
  for (std::size_t i = 0; i < 3; ++i) local[i] = x.local[i];
  return true;
}

bool find_child_face(int g, const std::array<int, 3>& codes, int& child, int& child_face, std::array<int, 3>& local) {
  return find_child_face(child_face_table(), g, codes, child, child_face, local);
}

}  // namespace

namespace {

// For each (slot, face) with a sibling across, the sibling's local index of each of our
// vertices (−1 for the vertex opposite the face); tabulated once.
const std::array<std::array<std::array<int, 4>, 4>, 8>& sibling_map() {
  static const auto kMap = [] {
    std::array<std::array<std::array<int, 4>, 4>, 8> m{};
    const TreeTable& tt = TreeTable::get();
    for (std::size_t c = 0; c < 8; ++c)
      for (std::size_t g = 0; g < 4; ++g) {
        m[c][g] = {-1, -1, -1, -1};
        const int sib = tt.face_link[c][g].sibling;
        if (sib < 0) continue;
        const auto s2 = static_cast<std::size_t>(sib);
        for (std::size_t k = 0; k < 4; ++k) {
          if (k == g) continue;
          const int code = pair_code(tt.vertex[c][k][0], tt.vertex[c][k][1]);
          for (std::size_t k2 = 0; k2 < 4; ++k2)
            if (pair_code(tt.vertex[s2][k2][0], tt.vertex[s2][k2][1]) == code) m[c][g][k] = static_cast<int>(k2);
        }
      }
    return m;
  }();
  return kMap;
}

// What lies across face f of root n.
Across root_across(const TetHierarchy& h, std::uint32_t r, int f) {
  const auto nb = h.root_neighbor(r, f);
  if (nb.root < 0) return {true, {}, -1, {}};
  Across a{false, NodeRef{static_cast<std::uint32_t>(nb.root), 0, 0}, nb.face, {-1, -1, -1, -1}};
  const Tet& mine = h.root_tet(r);
  const Tet& other = h.root_tet(static_cast<std::size_t>(nb.root));
  for (std::size_t k = 0; k < 4; ++k)
    for (std::size_t k2 = 0; k2 < 4; ++k2)
      if (mine[k] == other[k2]) a.vmap[k] = static_cast<int>(k2);
  a.word = h.root_word(static_cast<std::size_t>(nb.root));
  return a;
}

// Face maps: how the 3 vertices of a node's face f correspond to those of the face g of the
// node across, as one id = 6 g + p, p the index of the bijection between our face's
// vertices and g's (both in increasing order). The v_list walk carries the id instead of a
// vertex map, and steps from a node's neighbours to its children's with one table look-up.
// Tabulated once from the vertex-map rules (sibling_map, find_child_face), so they agree.
constexpr int kFaceMaps = 24;
constexpr int kPerm3[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};

struct FaceMapTables {
  // vmap[f][id]: our vertex k ≠ f → the neighbour's local index (−1 at k = f).
  std::array<std::array<std::array<std::int8_t, 4>, kFaceMaps>, 4> vmap{};
  // A child face on its parent's face, across a neighbour refined like the parent: the
  // neighbour's child holding the face, that child's face index and the map (child < 0:
  // no such child, non-conforming input).
  struct Step {
    std::int8_t child = -1, map = -1;
  };
  // step[s][f][id of the parent's map on face_link[s][f].parent_face]
  std::array<std::array<std::array<Step, kFaceMaps>, 4>, 8> step{};
  std::array<std::array<std::int8_t, 4>, 8> sibling{};  // map id of sibling faces: sibling[s][f]
  // A face being split against a finer neighbour is given by its 3 vertices in emission
  // order; its map to the neighbour's face is the id of vertex map {loc0, loc1, loc2, −1} of
  // face 3 (position i ↦ the neighbour's local index). lead[f][id][flipped]: that id for
  // face f of a leaf with face map id (vertex order kFaceVerts[f], 1 and 2 swapped when
  // flipped). split[id][i]: sub-face i of emit_against's kSub against the neighbour's child
  // holding it, and the sub-face's id against that child.
  std::array<std::array<std::array<std::int8_t, 2>, kFaceMaps>, 4> lead{};
  std::array<std::array<Step, 4>, kFaceMaps> split{};

  // The id of vertex map v of our face f (−1 when it is no bijection onto one face).
  static int id_of(int f, const std::array<int, 4>& v) {
    std::array<int, 3> ours{}, theirs{};
    int n = 0, used = 0;
    for (int k = 0; k < 4; ++k) {
      if (k == f) continue;
      const int w = v[static_cast<std::size_t>(k)];
      if (w < 0 || w > 3 || ((used >> w) & 1) != 0) return -1;
      used |= 1 << w;
      ours[static_cast<std::size_t>(n++)] = w;
    }
    int g = -1;
    for (int k = 0; k < 4; ++k)
      if (((used >> k) & 1) == 0) g = k;
    n = 0;
    for (int k = 0; k < 4; ++k)
      if (k != g) theirs[static_cast<std::size_t>(n++)] = k;
    for (int p = 0; p < 6; ++p) {
      bool same = true;
      for (std::size_t i = 0; i < 3; ++i) same = same && ours[i] == theirs[static_cast<std::size_t>(kPerm3[p][i])];
      if (same) return g * 6 + p;
    }
    return -1;
  }

  FaceMapTables() {
    for (int f = 0; f < 4; ++f)
      for (int id = 0; id < kFaceMaps; ++id) {
        const int g = id / 6, p = id % 6;
        std::array<int, 3> theirs{};
        int n = 0;
        for (int k = 0; k < 4; ++k)
          if (k != g) theirs[static_cast<std::size_t>(n++)] = k;
        auto& v = vmap[static_cast<std::size_t>(f)][static_cast<std::size_t>(id)];
        v = {-1, -1, -1, -1};
        n = 0;
        for (int k = 0; k < 4; ++k)
          if (k != f) v[static_cast<std::size_t>(k)] = static_cast<std::int8_t>(theirs[static_cast<std::size_t>(kPerm3[p][n++])]);
      }
    const TreeTable& t = TreeTable::get();
    const auto& sib = sibling_map();
    for (std::size_t s = 0; s < 8; ++s)
      for (std::size_t f = 0; f < 4; ++f) {
        const auto link = t.face_link[s][f];
        if (link.sibling >= 0) {
          sibling[s][f] = static_cast<std::int8_t>(id_of(static_cast<int>(f), sib[s][f]));
          continue;
        }
        const auto pf = static_cast<std::size_t>(link.parent_face);
        for (std::size_t id = 0; id < static_cast<std::size_t>(kFaceMaps); ++id) {
          const auto& pv = vmap[pf][id];
          std::array<int, 3> codes{};
          std::array<std::size_t, 3> ks{};
          int i = 0;
          for (std::size_t k = 0; k < 4; ++k) {
            if (k == f) continue;
            codes[static_cast<std::size_t>(i)] = pair_code(pv[t.vertex[s][k][0]], pv[t.vertex[s][k][1]]);
            ks[static_cast<std::size_t>(i++)] = k;
          }
          int c = -1, cg = -1;
          std::array<int, 3> local{};
          if (!find_child_face(static_cast<int>(id) / 6, codes, c, cg, local)) continue;
          std::array<int, 4> cv{-1, -1, -1, -1};
          for (std::size_t j = 0; j < 3; ++j) cv[ks[j]] = local[j];
          const int cid = id_of(static_cast<int>(f), cv);
          if (cid < 0 || cid / 6 != cg) continue;
          step[s][f][id] = {static_cast<std::int8_t>(c), static_cast<std::int8_t>(cid)};
        }
      }
    for (int f = 0; f < 4; ++f)
      for (int id = 0; id < kFaceMaps; ++id)
        for (int fl = 0; fl < 2; ++fl) {
          std::array<int, 3> order{kFaceVerts[f][0], kFaceVerts[f][1], kFaceVerts[f][2]};
          if (fl != 0) std::swap(order[1], order[2]);
          const auto& v = vmap[static_cast<std::size_t>(f)][static_cast<std::size_t>(id)];
          lead[static_cast<std::size_t>(f)][static_cast<std::size_t>(id)][static_cast<std::size_t>(fl)] =
              static_cast<std::int8_t>(id_of(3, {v[static_cast<std::size_t>(order[0])], v[static_cast<std::size_t>(order[1])],
                                                 v[static_cast<std::size_t>(order[2])], -1}));
        }
    static constexpr int kSub[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {3, 4, 5}};
    for (std::size_t id = 0; id < static_cast<std::size_t>(kFaceMaps); ++id) {
      const auto& loc = vmap[3][id];
      auto code_of = [&](int v) {
        if (v < 3) return pair_code(loc[static_cast<std::size_t>(v)], loc[static_cast<std::size_t>(v)]);
        const int e = v - 3;
        return pair_code(loc[static_cast<std::size_t>(e)], loc[static_cast<std::size_t>((e + 1) % 3)]);
      };
      for (std::size_t i = 0; i < 4; ++i) {
        const std::array<int, 3> codes{code_of(kSub[i][0]), code_of(kSub[i][1]), code_of(kSub[i][2])};
        int c = -1, cg = -1;
        std::array<int, 3> local{};
        if (!find_child_face(static_cast<int>(id) / 6, codes, c, cg, local)) continue;
        const int cid = id_of(3, {local[0], local[1], local[2], -1});
        if (cid < 0 || cid / 6 != cg) continue;
        split[id][i] = {static_cast<std::int8_t>(c), static_cast<std::int8_t>(cid)};
      }
    }
  }
};

const FaceMapTables& face_map_tables() {
  static const FaceMapTables kTables;
  return kTables;
}

// What the v_list walk keeps of what lies across a face: the node's storage word, depth and
// face map (Across without the node's root and path, which the walk never reads, and with
// the vertex map as an id): 8 bytes, so a node's four are made and copied cheaply. No
// default member values: the walk's per-child arrays are filled by child_across, and
// zero-filling them first was 3 % of the surface update's instructions.
struct WalkAcross {
  std::uint32_t word;  ///< storage word of the node across (boundary: erased)
  std::uint8_t depth;  ///< its depth
  std::int8_t map;     ///< face map id (FaceMapTables); its face is map / 6
  bool boundary;
};

WalkAcross walk_across(const Across& a, int f) {
  WalkAcross w{TetHierarchy::kErased, 0, -1, false};
  w.word = a.word;
  w.depth = a.node.depth;
  w.boundary = a.boundary;
  if (!a.boundary) {
    w.map = static_cast<std::int8_t>(FaceMapTables::id_of(f, a.vmap));
    if (w.map < 0 || w.map / 6 != a.face) w = WalkAcross{TetHierarchy::kErased, 0, -1, true};  // non-conforming
  }
  return w;
}

// The tables the v_list walk reads for every node, fetched once per walk (each accessor
// is a function-local static).
struct WalkTables {
  const TreeTable& tree = TreeTable::get();
  const FaceMapTables& maps = face_map_tables();
};

// The child words of an internal node (decoded once per node of the walk,
// TetHierarchy::child_words) and of the internal nodes across its faces at its own depth
// (decoded when a child first looks across that face), for its 8 children's 32 look-ups.
struct WalkChildren {
  std::array<std::uint32_t, 8> own;
  std::array<std::array<std::uint32_t, 8>, 4> across;  // [f]: decoded on first use (bit f of `ready`)
  unsigned ready = 0;
  // Bit f: the node across face f is internal at the node's own depth, so a child face on
  // f looks at one of its children; otherwise the child sees that node itself (the mesh
  // boundary or a coarser or same-depth leaf). Set by init(), once per node, not per child.
  unsigned descend = 0;

  void init(const TetHierarchy& h, std::uint32_t word, int depth, const std::array<WalkAcross, 4>& acr) {
    own = h.child_words(word);
    for (unsigned f = 0; f < 4; ++f) {
      const WalkAcross& a = acr[f];
      const bool refined = !a.boundary && a.depth >= depth && TetHierarchy::state_of_word(a.word) == NodeState::Internal;
      descend |= (refined ? 1U : 0U) << f;
    }
  }
};


// What lies across face f of child slot s of an internal node at depth pdepth, given what
// lies across each face of the node (`pacr`) and the decoded child words `wc`; written into
// @p out field by field (a returned temporary, built piecewise on the stack and copied, cost
// a store-forwarding stall per call in the walk's inner loop).
void child_across(const TetHierarchy& h, const WalkTables& wt, int pdepth, WalkChildren& wc, int s, int f,
                  const std::array<WalkAcross, 4>& pacr, WalkAcross& out) {
  const auto su = static_cast<std::size_t>(s);
  const auto fu = static_cast<std::size_t>(f);
  const auto& link = wt.tree.face_link[su][fu];  // a reference: a copy went through the stack
  if (link.sibling >= 0) {
    out.word = wc.own[static_cast<std::size_t>(link.sibling)];
    out.depth = static_cast<std::uint8_t>(pdepth + 1);
    out.map = wt.maps.sibling[su][fu];
    out.boundary = false;
    return;
  }
  const WalkAcross& pa = pacr[static_cast<std::size_t>(link.parent_face)];
  if (((wc.descend >> link.parent_face) & 1U) == 0) {
    out = pa;  // the mesh boundary or a coarser leaf
    return;
  }
  // Same depth as the parent and refined: the child of the node across holding our face.
  const auto st = wt.maps.step[su][fu][static_cast<std::size_t>(pa.map)];
  if (st.child < 0) {  // non-conforming input
    out = WalkAcross{TetHierarchy::kErased, 0, -1, true};
    return;
  }
  const auto pf = static_cast<std::size_t>(link.parent_face);
  if (((wc.ready >> pf) & 1U) == 0) {
    wc.across[pf] = h.child_words(pa.word);
    wc.ready |= 1U << pf;
  }
  out.word = wc.across[pf][static_cast<std::size_t>(st.child)];
  out.depth = static_cast<std::uint8_t>(pa.depth + 1);
  out.map = st.map;
  out.boundary = false;
}

// What lies across face f of child slot s of node p when every node is taken as refined:
// the node at the same depth sharing the face (the "virtual" neighbour; it exists in the
// tree or lies below a coarser leaf), given the same for p's faces.
Across virtual_child_across(const NodeRef& p, int s, int f, const std::array<Across, 4>& pacr) {
  const TreeTable& t = TreeTable::get();
  const auto su = static_cast<std::size_t>(s);
  const auto link = t.face_link[su][static_cast<std::size_t>(f)];
  if (link.sibling >= 0)
    return Across{false, p.child(link.sibling), link.sibling_face, sibling_map()[su][static_cast<std::size_t>(f)]};
  const Across& pa = pacr[static_cast<std::size_t>(link.parent_face)];
  if (pa.boundary) return pa;
  std::array<int, 3> codes{};
  std::array<std::size_t, 3> ks{};
  int i = 0;
  for (std::size_t k = 0; k < 4; ++k) {
    if (static_cast<int>(k) == f) continue;
    codes[static_cast<std::size_t>(i)] = pair_code(pa.vmap[t.vertex[su][k][0]], pa.vmap[t.vertex[su][k][1]]);
    ks[static_cast<std::size_t>(i++)] = k;
  }
  int c = -1, cg = -1;
  std::array<int, 3> local{};
  if (!find_child_face(pa.face, codes, c, cg, local)) return {true, {}, -1, {}};
  Across a{false, pa.node.child(c), cg, {-1, -1, -1, -1}};
  for (std::size_t j = 0; j < 3; ++j) a.vmap[ks[j]] = local[j];
  return a;
}

// A root's mesh vertex ids in increasing order and their root vertex slots, found once per
// root, so a face costs a pass over its corners' 4 coordinates (the same keys as
// point_key(), which sorts the (vertex, weight) pairs per call).
struct RootKeys {
  std::array<std::int32_t, 4> id{};    // mesh vertex indices in increasing order
  std::array<std::uint8_t, 4> slot{};  // their root vertex slots
  RootKeys(const TetHierarchy& h, std::size_t r) {
    const Tet& t = h.root_tet(r);
    std::array<std::uint8_t, 4> o{0, 1, 2, 3};
    std::sort(o.begin(), o.end(), [&](std::uint8_t a, std::uint8_t b) { return t[a] < t[b]; });
    for (std::size_t i = 0; i < 4; ++i) {
      slot[i] = o[i];
      id[i] = t[o[i]];
    }
  }
};

// Appends the face of root barycentric keys a, b, c to out.
void push_face(const RootKeys& rk, const BaryKey& a, const BaryKey& b, const BaryKey& c, std::vector<SurfaceFace>& out) {
  std::array<BaryKey, 3> w;  // the corners' weights in increasing vertex id order
  for (std::size_t i = 0; i < 4; ++i) {
    w[0][i] = a[rk.slot[i]];
    w[1][i] = b[rk.slot[i]];
    w[2][i] = c[rk.slot[i]];
  }
  out.emplace_back(rk.id, w);
}

// Emits the parts of face `b` (root barycentric keys in our root, outward from our side)
// bordering erased material, where node m (storage word mword) lies across it at the same
// level; @p id is the face's map to m's face (FaceMapTables::lead / split). The sub-face corners are integer midpoints of b (exact: m is
// internal, so its children's vertices are at depth ≤ kMaxDepth).
// NOLINTNEXTLINE(misc-no-recursion): depth ≤ kMaxDepth
void emit_against(const TetHierarchy& h, const FaceMapTables& fm, const RootKeys& rk, const std::array<BaryKey, 3>& b,
                  int id, std::uint32_t mword, std::vector<SurfaceFace>& out) {
  const NodeState st = TetHierarchy::state_of_word(mword);
  if (st == NodeState::Full) return;
  if (st == NodeState::Erased) {
    push_face(rk, b[0], b[1], b[2], out);
    return;
  }
  // Sub-face vertices: 0..2 = corners, 3 + e = midpoint of edge e (e: 0-1, 1-2, 2-0).
  std::array<BaryKey, 6> v;
  for (std::size_t e = 0; e < 3; ++e) {
    const std::size_t e1 = (e + 1) % 3;
    v[e] = b[e];
    for (std::size_t j = 0; j < 4; ++j) v[3 + e][j] = (b[e][j] + b[e1][j]) / 2;
  }
  static constexpr int kSub[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {3, 4, 5}};
  for (std::size_t i = 0; i < 4; ++i) {
    const auto sub = fm.split[static_cast<std::size_t>(id)][i];
    if (sub.child < 0) continue;  // non-conforming input
    const std::uint32_t cw = h.child_word(mword, sub.child);
    if (cw == TetHierarchy::kFull) continue;
    emit_against(h, fm, rk,
                 {v[static_cast<std::size_t>(kSub[i][0])], v[static_cast<std::size_t>(kSub[i][1])],
                  v[static_cast<std::size_t>(kSub[i][2])]},
                 sub.map, cw, out);
  }
}

}  // namespace

SurfaceFace::SurfaceFace(const std::array<std::int32_t, 4>& vertex_ids, const std::array<BaryKey, 3>& corner) noexcept
    : m_vertex(vertex_ids) {
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t e = 3 * c + i;
      m_weight[e < 5 ? 0 : 1] |= static_cast<std::uint64_t>(corner[c][i] & 0xFFF) << (12 * (e < 5 ? e : e - 5));
    }
}

PointKey SurfaceFace::key(std::size_t c) const noexcept {
  std::array<std::int32_t, 4> w{};
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t e = 3 * c + i;
    w[i] = static_cast<std::int32_t>((m_weight[e < 5 ? 0 : 1] >> (12 * (e < 5 ? e : e - 5))) & 0xFFF);
  }
  w[3] = kBaryScale - w[0] - w[1] - w[2];
  // Without a branch per coordinate: every pair is written at the next free slot and the
  // slot advances only for a non-zero weight, so a zero-weight pair is overwritten by the
  // next kept one or, at the end, is (−1, 0) like the untouched slots after it.
  PointKey k;
  std::size_t n = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    k.id[n] = w[i] != 0 ? m_vertex[i] : -1;
    k.weight[n] = w[i];
    n += w[i] != 0 ? 1U : 0U;
  }
  return k;
}

PointKey point_key(const TetHierarchy& hierarchy, std::size_t r, const BaryKey& key) noexcept {
  const Tet& t = hierarchy.root_tet(r);
  std::array<std::pair<std::int32_t, std::int32_t>, 4> p{};
  int n = 0;
  for (std::size_t i = 0; i < 4; ++i)
    if (key[i] != 0) p[static_cast<std::size_t>(n++)] = {t[i], key[i]};
  for (int i = 1; i < n; ++i)  // insertion sort of at most 4 pairs
    for (int j = i; j > 0 && p[static_cast<std::size_t>(j - 1)] > p[static_cast<std::size_t>(j)]; --j)
      std::swap(p[static_cast<std::size_t>(j - 1)], p[static_cast<std::size_t>(j)]);
  PointKey k;
  for (int i = 0; i < n; ++i) {
    k.id[static_cast<std::size_t>(i)] = p[static_cast<std::size_t>(i)].first;
    k.weight[static_cast<std::size_t>(i)] = p[static_cast<std::size_t>(i)].second;
  }
  return k;
}

Vec3 point_position(const PointKey& key, std::span<const Vec3> vertices_mm) noexcept {
  Vec3 p = Vec3::Zero();
  for (std::size_t i = 0; i < 4; ++i)
    if (key.id[i] >= 0) p += static_cast<double>(key.weight[i]) * vertices_mm[static_cast<std::size_t>(key.id[i])];
  return p / static_cast<double>(kBaryScale);
}

namespace {

// Geometry of child slot @p s of a node of geometry @p g: the same integer midpoints and
// parity as TetHierarchy::geometry derives along the path, one level at a time.
NodeGeometry child_geometry(const TreeTable& t, const NodeGeometry& g, std::size_t s) noexcept {
  NodeGeometry c;
  for (std::size_t k = 0; k < 4; ++k) {
    const auto& a = g.vertex[t.vertex[s][k][0]];
    const auto& b = g.vertex[t.vertex[s][k][1]];
    for (std::size_t j = 0; j < 4; ++j) c.vertex[k][j] = (a[j] + b[j]) / 2;
  }
  c.flipped = g.flipped != (t.parity[s] != 0);
  return c;
}

// Emits the visible faces of the full leaf of geometry g (face neighbours acr).
void emit_leaf(const TetHierarchy& h, const WalkTables& wt, const RootKeys& rk, const NodeGeometry& g,
               const std::array<WalkAcross, 4>& acr, std::vector<SurfaceFace>& out) {
  for (int f = 0; f < 4; ++f) {
    const auto fu = static_cast<std::size_t>(f);
    const WalkAcross& a = acr[fu];
    if (a.word == TetHierarchy::kFull) continue;
    std::array<int, 3> order{kFaceVerts[f][0], kFaceVerts[f][1], kFaceVerts[f][2]};
    if (g.flipped) std::swap(order[1], order[2]);
    const BaryKey& b0 = g.vertex[static_cast<std::size_t>(order[0])];
    const BaryKey& b1 = g.vertex[static_cast<std::size_t>(order[1])];
    const BaryKey& b2 = g.vertex[static_cast<std::size_t>(order[2])];
    if (a.word == TetHierarchy::kErased) {
      push_face(rk, b0, b1, b2, out);  // the keys straight from the geometry, not a copied face
    } else {
      emit_against(h, wt.maps, rk, {b0, b1, b2}, wt.maps.lead[fu][static_cast<std::size_t>(a.map)][g.flipped ? 1 : 0],
                   a.word, out);
    }
  }
}

// Emits the visible faces of the full leaves of the subtree of n (storage word `word`,
// geometry g, face neighbours acr), walking top-down so every node's neighbours, their
// states and its geometry come from its parent's in O(1). Erased children and full
// children with four full neighbours cost one visit each and no further work.
// NOLINTNEXTLINE(misc-no-recursion): depth ≤ kMaxDepth
void visit(const TetHierarchy& h, const WalkTables& wt, const RootKeys& rk, int depth, std::uint32_t word,
           const NodeGeometry& g, const std::array<WalkAcross, 4>& acr, std::vector<SurfaceFace>& out,
           std::size_t& visits) {
  ++visits;
  const NodeState st = TetHierarchy::state_of_word(word);
  if (st == NodeState::Erased) return;
  if (st == NodeState::Full) {
    emit_leaf(h, wt, rk, g, acr, out);
    return;
  }
  WalkChildren wc;
  wc.init(h, word, depth, acr);
  for (int c = 0; c < 8; ++c) {
    const std::uint32_t cw = wc.own[static_cast<std::size_t>(c)];
    if (cw == TetHierarchy::kErased) {
      ++visits;
      continue;
    }
    std::array<WalkAcross, 4> cacr;
    for (int f = 0; f < 4; ++f) child_across(h, wt, depth, wc, c, f, acr, cacr[static_cast<std::size_t>(f)]);
    const auto cu = static_cast<std::size_t>(c);
    if (cw == TetHierarchy::kFull) {
      ++visits;
      bool exposed = false;
      for (const WalkAcross& a : cacr) exposed = exposed || a.word != TetHierarchy::kFull;
      if (exposed) emit_leaf(h, wt, rk, child_geometry(wt.tree, g, cu), cacr, out);
      continue;
    }
    visit(h, wt, rk, depth + 1, cw, child_geometry(wt.tree, g, cu), cacr, out, visits);
  }
}

}  // namespace

namespace {

// Chunk indices [lo, hi) at chunk level L covered by node n: the first min(depth, L) slots of
// its path, most significant first (depth-first order).
std::pair<std::uint32_t, std::uint32_t> chunk_range(const NodeRef& n, int level) {
  std::uint32_t idx = 0;
  const int d = std::min<int>(n.depth, level);
  for (int l = 1; l <= d; ++l) idx = idx * 8U + static_cast<std::uint32_t>(n.slot(l));
  const std::uint32_t span = 1U << (3 * (level - d));
  return {idx * span, idx * span + span};
}

std::array<Across, 4> root_acr(const TetHierarchy& h, std::uint32_t r) {
  std::array<Across, 4> acr;
  for (int f = 0; f < 4; ++f) acr[static_cast<std::size_t>(f)] = root_across(h, r, f);
  return acr;
}

}  // namespace

BoundarySurface::BoundarySurface(const TetHierarchy& hierarchy, const BoundarySurfaceOptions& options)
    : m_options(options) {
  if (options.chunk_level < 0 || options.chunk_level > 4) {
    throw InvalidInput("boundary surface: chunk level must be between 0 and 4, got " + std::to_string(options.chunk_level));
  }
  if (options.threads < 0) {
    throw InvalidInput("boundary surface: threads must be 0 (all) or positive, got " + std::to_string(options.threads));
  }
  m_full_chunks = 1U << (3 * options.chunk_level);
  rebuild_all(hierarchy);
}
BoundarySurface::~BoundarySurface() = default;
BoundarySurface::BoundarySurface(BoundarySurface&&) noexcept = default;
BoundarySurface& BoundarySurface::operator=(BoundarySurface&&) noexcept = default;

std::size_t BoundarySurface::face_count() const noexcept {
  std::size_t n = 0;
  for (const auto& root : m_chunks)
    for (const auto& c : root) n += c ? c->size() : 0;
  return n;
}

std::size_t BoundarySurface::memory_bytes() const noexcept {
  std::size_t n = m_chunks.capacity() * sizeof(std::vector<ChunkList>) + m_flat.capacity() * sizeof(std::vector<SurfaceFace>);
  for (const auto& root : m_chunks) {
    n += root.capacity() * sizeof(ChunkList);
    for (const auto& c : root) n += c ? sizeof(std::vector<SurfaceFace>) + 16 + c->capacity() * sizeof(SurfaceFace) : 0;
  }
  for (const auto& flat : m_flat) n += flat.capacity() * sizeof(SurfaceFace);
  return n;
}

const std::vector<SurfaceFace>& BoundarySurface::v_list(std::size_t r) const {
  if (m_flat_stale[r]) {
    auto& flat = m_flat[r];
    flat.clear();
    for (const auto& c : m_chunks[r])
      if (c) flat.insert(flat.end(), c->begin(), c->end());
    m_flat_stale[r] = 0;
  }
  return m_flat[r];
}

const std::vector<std::vector<SurfaceFace>>& BoundarySurface::v_lists() const {
  for (const std::uint32_t r : m_stale_roots) (void)v_list(r);
  m_stale_roots.clear();
  return m_flat;
}

std::vector<std::vector<SurfaceFace>> BoundarySurface::take_v_lists() {
  // The chunk lists are small blocks spread over the heap, so the memory they leave is in
  // pieces too small for a root's list: each root's list would come on top of it. Every few
  // MB freed, the free pages go back to the system, so the faces are held about once.
  detail::FreedPages pages;
  std::vector<std::vector<SurfaceFace>> out(m_chunks.size());
  for (std::size_t r = 0; r < m_chunks.size(); ++r) {
    if (!m_flat_stale[r] && !m_flat[r].empty()) {
      out[r] = std::move(m_flat[r]);
    } else {
      std::size_t n = 0;
      for (const auto& c : m_chunks[r]) n += c ? c->size() : 0;
      out[r].reserve(n);
      for (const auto& c : m_chunks[r])
        if (c) out[r].insert(out[r].end(), c->begin(), c->end());
      for (const auto& c : m_chunks[r]) pages.freed(c && c.use_count() == 1 ? c->capacity() * sizeof(SurfaceFace) : 0U);
    }
    std::vector<SurfaceFace>().swap(m_flat[r]);  // (= {} would keep the capacity)
    m_flat_stale[r] = 0;
    std::fill(m_chunks[r].begin(), m_chunks[r].end(), nullptr);
  }
  m_stale_roots.clear();
  return out;
}

void BoundarySurface::rebuild_all(const TetHierarchy& hierarchy) {
  const std::size_t n = hierarchy.root_count();
  m_chunks.assign(n, std::vector<ChunkList>(1));
  m_flat.assign(n, {});
  m_flat_stale.assign(n, 0);
  m_stale_roots.clear();
  m_mark.assign(n, 0);
  m_rebuilt.clear();
  m_rebuilt_chunks.clear();
  m_dirty.clear();
  for (std::size_t r = 0; r < n; ++r) mark_root(static_cast<std::uint32_t>(r));
  rebuild_ranges(hierarchy);
}

void BoundarySurface::mark_root(std::uint32_t r) { m_dirty.push_back({r, 0, m_full_chunks}); }

namespace {

// For child slot s and a mask of its faces, the mask of the parent faces that those of them
// lying on the parent's boundary are on (faces shared with a sibling drop out); a child's
// faces lie on distinct parent faces, so the map works on masks. Tabulated once.
const std::array<std::array<std::uint8_t, 16>, 8>& parent_face_masks() {
  static const auto kMasks = [] {
    std::array<std::array<std::uint8_t, 16>, 8> m{};
    const TreeTable& t = TreeTable::get();
    for (std::size_t s = 0; s < 8; ++s)
      for (std::size_t mask = 0; mask < 16; ++mask) {
        unsigned up = 0;
        for (std::size_t f = 0; f < 4; ++f) {
          if (((mask >> f) & 1U) == 0 || t.face_link[s][f].sibling >= 0) continue;
          up |= 1U << t.face_link[s][f].parent_face;
        }
        m[s][mask] = static_cast<std::uint8_t>(up);
      }
    return m;
  }();
  return kMasks;
}

}  // namespace

// Marks the chunks of `node` and, for each of its faces on the boundary of its ancestor y at
// the chunk level (or of the node itself when shallower), records (y, face) in m_face_marks
// for mark_faces(). A range or mark equal to the previous one is not repeated (changed nodes
// come in traversal order, so neighbours in the list share their chunk).
void BoundarySurface::mark_node(const TetHierarchy& /*h*/, const NodeRef& node) {
  const int level = m_options.chunk_level;
  const auto [lo, hi] = chunk_range(node, level);
  if (m_dirty.empty() || m_dirty.back().root != node.root || m_dirty.back().lo != lo || m_dirty.back().hi != hi)
    m_dirty.push_back({node.root, lo, hi});
  const auto& up = parent_face_masks();
  unsigned mask = 0xF;
  NodeRef y = node;
  if (node.depth > level) {
    for (int d = node.depth; d > level && mask != 0; --d) mask = up[static_cast<std::size_t>(node.slot(d))][mask];
    y.depth = static_cast<std::uint8_t>(level);
    y.path = node.path & ((1U << (3 * level)) - 1U);
  }
  if (mask == 0) return;
  if (!m_face_marks.empty() && m_face_marks.back().node == y) {
    m_face_marks.back().faces = static_cast<std::uint8_t>(m_face_marks.back().faces | mask);
  } else {
    m_face_marks.push_back({y, static_cast<std::uint8_t>(mask)});
  }
}

// Marks the chunks across the recorded faces: one top-down walk per distinct node.
void BoundarySurface::mark_faces(const TetHierarchy& h) {
  std::sort(m_face_marks.begin(), m_face_marks.end(), [](const FaceMark& a, const FaceMark& b) {
    return std::tie(a.node.root, a.node.depth, a.node.path) < std::tie(b.node.root, b.node.depth, b.node.path);
  });
  const int level = m_options.chunk_level;
  std::size_t i = 0;
  while (i < m_face_marks.size()) {
    const NodeRef y = m_face_marks[i].node;
    std::uint8_t mask = 0;
    for (; i < m_face_marks.size() && m_face_marks[i].node == y; ++i) mask = static_cast<std::uint8_t>(mask | m_face_marks[i].faces);
    // Virtual neighbours of y's faces, top-down from the root.
    std::array<Across, 4> acr = root_acr(h, y.root);
    NodeRef p{y.root, 0, 0};
    for (int l = 1; l <= y.depth; ++l) {
      const int s = y.slot(l);
      std::array<Across, 4> cacr;
      for (int k = 0; k < 4; ++k) cacr[static_cast<std::size_t>(k)] = virtual_child_across(p, s, k, acr);
      acr = cacr;
      p = p.child(s);
    }
    for (int g = 0; g < 4; ++g) {
      if (((mask >> g) & 1U) == 0) continue;
      const Across& a = acr[static_cast<std::size_t>(g)];
      if (a.boundary) continue;
      const auto [nlo, nhi] = chunk_range(a.node, level);
      m_dirty.push_back({a.node.root, nlo, nhi});
    }
  }
  m_face_marks.clear();
}

void BoundarySurface::update(const TetHierarchy& hierarchy, std::span<const std::uint32_t> changed_roots) {
  const std::vector<std::uint8_t> all(changed_roots.size(), 0xF);
  update(hierarchy, changed_roots, all);
}

void BoundarySurface::update(const TetHierarchy& hierarchy, std::span<const std::uint32_t> changed_roots,
                             std::span<const std::uint8_t> changed_faces) {
  m_dirty.clear();
  for (std::size_t i = 0; i < changed_roots.size(); ++i) {
    const std::uint32_t r = changed_roots[i];
    mark_root(r);
    for (int f = 0; f < 4; ++f) {
      if (i < changed_faces.size() && ((changed_faces[i] >> f) & 1U) == 0) continue;
      const auto nb = hierarchy.root_neighbor(r, f);
      if (nb.root >= 0) mark_root(static_cast<std::uint32_t>(nb.root));
    }
  }
  rebuild_ranges(hierarchy);
}

void BoundarySurface::update(const TetHierarchy& hierarchy, std::span<const NodeRef> changed_nodes) {
  update(hierarchy, changed_nodes, 0);
}

void BoundarySurface::update(const TetHierarchy& hierarchy, std::span<const NodeRef> changed_nodes,
                             std::size_t max_node_visits) {
  m_face_marks.clear();
  for (const NodeRef& n : changed_nodes) mark_node(hierarchy, n);
  mark_faces(hierarchy);
  rebuild_ranges(hierarchy, max_node_visits);
}

// The node visits of one update, shared by its workers: each adds a unit's visits when it has
// walked it, and a worker takes no new piece, and stops inside one, once they reach max.
struct BoundarySurface::Budget {
  std::atomic<std::size_t> visits{0};
  std::size_t max = 0;  // 0 = unlimited
  [[nodiscard]] bool spent() const noexcept { return max > 0 && visits.load(std::memory_order_relaxed) >= max; }
};

void BoundarySurface::rebuild_ranges(const TetHierarchy& hierarchy, std::size_t max_node_visits) {
  m_rebuilt.clear();
  m_rebuilt_chunks.clear();
  m_visits = 0;
  // A root kept as one list that is now refined gets its chunk lists here, before any worker
  // indexes them, and all of them are rebuilt.
  const std::size_t marked = m_dirty.size();
  for (std::size_t i = 0; i < marked; ++i) {
    const std::uint32_t r = m_dirty[i].root;
    auto& ch = m_chunks[r];
    if (ch.size() == 1 && m_full_chunks > 1 && TetHierarchy::state_of_word(hierarchy.root_word(r)) == NodeState::Internal) {
      ch.resize(m_full_chunks);
      m_dirty.push_back({r, 0, m_full_chunks});
    }
  }
  std::sort(m_dirty.begin(), m_dirty.end(),
            [](const Range& a, const Range& b) { return a.root != b.root ? a.root < b.root : a.lo < b.lo; });
  // Merge overlapping (and adjacent) ranges of a root, then cut them at the boundaries of
  // the level-(chunk_level − 1) sub-trees ("blocks"). A unit of rebuild_range (the node at
  // the chunk level on a chunk's path, or the shallower leaf covering it) lies within one
  // block unless it is the root itself. The pieces of one block (of one root, for a root
  // kept whole or no longer refined) form a group, which one worker rebuilds in order, so no
  // two workers ever write the same unit's list. Workers take groups in order.
  m_pieces.clear();
  m_groups.clear();
  const std::uint32_t block = m_full_chunks > 1 ? m_full_chunks / 8 : 1;
  constexpr std::uint32_t kWholeRoot = std::numeric_limits<std::uint32_t>::max();  // block of a root rebuilt as one unit
  auto group_key = [](std::uint32_t root, std::uint32_t b) { return (static_cast<std::uint64_t>(root) << 32) | b; };
  std::uint64_t last_key = std::numeric_limits<std::uint64_t>::max();
  auto add = [&](const Range& d, std::uint32_t b) {
    const std::uint64_t key = group_key(d.root, b);
    if (key != last_key) m_groups.push_back(static_cast<std::uint32_t>(m_pieces.size()));
    last_key = key;
    m_pieces.push_back(d);
  };
  auto cut = [&](const Range& d) {
    if (m_chunks[d.root].size() == 1 ||
        TetHierarchy::state_of_word(hierarchy.root_word(d.root)) != NodeState::Internal) {
      // One unit, the root: its ranges are rebuilt once, as one piece.
      if (!m_pieces.empty() && last_key == group_key(d.root, kWholeRoot)) {
        m_pieces.back().hi = std::max(m_pieces.back().hi, d.hi);
      } else {
        add(d, kWholeRoot);
      }
      return;
    }
    for (std::uint32_t lo = d.lo; lo < d.hi;) {
      const std::uint32_t hi = std::min(d.hi, (lo / block + 1) * block);
      add({d.root, lo, hi}, lo / block);
      lo = hi;
    }
  };
  Range run{};
  bool open = false;
  for (const Range& d : m_dirty) {
    if (open && run.root == d.root && d.lo <= run.hi) {
      run.hi = std::max(run.hi, d.hi);
      continue;
    }
    if (open) cut(run);
    run = d;
    open = true;
  }
  if (open) cut(run);
  m_groups.push_back(static_cast<std::uint32_t>(m_pieces.size()));
  m_dirty.clear();

  constexpr std::uint32_t kNotStarted = std::numeric_limits<std::uint32_t>::max();
  m_stop.assign(m_pieces.size(), kNotStarted);
  Budget budget;
  budget.max = max_node_visits;
  const std::size_t groups = m_groups.size() - 1;
  std::atomic<std::size_t> next{0};
  auto work = [&](std::vector<ChunkId>& rebuilt) {
    for (;;) {
      const std::size_t g = next.fetch_add(1, std::memory_order_relaxed);
      if (g >= groups) return;
      for (std::uint32_t i = m_groups[g]; i < m_groups[g + 1]; ++i) {
        if (budget.spent()) return;
        const Range& d = m_pieces[i];
        m_stop[i] = rebuild_range(hierarchy, d.root, d.lo, d.hi, budget, rebuilt);
      }
    }
  };
  const int threads = m_options.threads > 0 ? m_options.threads : tbb::this_task_arena::max_concurrency();
  const std::size_t workers = std::min<std::size_t>(groups, static_cast<std::size_t>(threads));
  if (workers <= 1) {
    work(m_rebuilt_chunks);
  } else {
    if (m_worker_chunks.size() < workers) m_worker_chunks.resize(workers);
    auto worker = [&](std::size_t k) {
      m_worker_chunks[k].clear();
      work(m_worker_chunks[k]);
    };
#if defined(__SANITIZE_THREAD__)
    // ThreadSanitizer cannot see oneTBB's happens-before edges (Debian's libtbb is not
    // instrumented; see ido/core/parallel.h). Plain threads, started per update, let it check
    // the workers' own reads and writes instead.
    std::vector<std::thread> others;
    for (std::size_t k = 1; k < workers; ++k) others.emplace_back(worker, k);
    worker(0);
    for (std::thread& t : others) t.join();
#else
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, workers, 1),
        [&](const tbb::blocked_range<std::size_t>& w) {
          for (std::size_t k = w.begin(); k != w.end(); ++k) worker(k);
        },
        tbb::simple_partitioner());
#endif
    for (std::size_t k = 0; k < workers; ++k)
      m_rebuilt_chunks.insert(m_rebuilt_chunks.end(), m_worker_chunks[k].begin(), m_worker_chunks[k].end());
  }
  m_visits = budget.visits.load(std::memory_order_relaxed);
  // What is left waits for the next update: pieces not started, and the rest of those a
  // worker stopped in.
  for (std::size_t i = 0; i < m_pieces.size(); ++i) {
    const Range& d = m_pieces[i];
    if (m_stop[i] == kNotStarted) {
      m_dirty.push_back(d);
      continue;
    }
    if (!m_mark[d.root]) {
      m_mark[d.root] = 1;
      m_rebuilt.push_back(d.root);
    }
    if (m_stop[i] < d.hi) m_dirty.push_back({d.root, m_stop[i], d.hi});
  }
  for (const std::uint32_t r : m_rebuilt) {
    m_mark[r] = 0;
    if (!m_flat_stale[r]) {
      m_flat_stale[r] = 1;
      m_stale_roots.push_back(r);
    }
  }
  std::sort(m_rebuilt_chunks.begin(), m_rebuilt_chunks.end());
  m_rebuilt_chunks.erase(std::unique(m_rebuilt_chunks.begin(), m_rebuilt_chunks.end()), m_rebuilt_chunks.end());
}

// Rebuilds the units (the node on each chunk's path at the chunk level, or the shallower
// leaf covering it) meeting chunks [lo, hi) of root r, appending the lists it rewrites to
// @p rebuilt; stops early (returning the first chunk not rebuilt) once the update's budget is
// spent. Returns hi when done. Reads the tree and writes only the units' own lists, so
// workers may run it on distinct pieces at once.
std::uint32_t BoundarySurface::rebuild_range(const TetHierarchy& h, std::uint32_t r, std::uint32_t lo, std::uint32_t hi,
                                             Budget& budget, std::vector<ChunkId>& rebuilt) {
  auto& ch = m_chunks[r];
  const std::uint32_t root_word = h.root_word(r);
  const int level = ch.size() == 1 ? 0 : m_options.chunk_level;
  const std::uint32_t requested_hi = hi;
  if (level == 0) {
    lo = 0;
    hi = 1;
  }
  hi = std::min<std::uint32_t>(hi, static_cast<std::uint32_t>(ch.size()));
  std::array<WalkAcross, 4> racr;
  for (int f = 0; f < 4; ++f) racr[static_cast<std::size_t>(f)] = walk_across(root_across(h, r, f), f);
  const WalkTables wt;
  const RootKeys rk(h, r);
  std::uint32_t c = lo;
  while (c < hi) {
    NodeRef node{r, 0, 0};
    std::uint32_t word = root_word;
    std::array<WalkAcross, 4> acr = racr;
    int d = 0;
    while (d < level && TetHierarchy::state_of_word(word) == NodeState::Internal) {
      const int s = static_cast<int>((c >> (3 * (level - d - 1))) & 7U);
      std::array<WalkAcross, 4> cacr;
      WalkChildren wc;
      wc.init(h, word, d, acr);
      for (int f = 0; f < 4; ++f) child_across(h, wt, d, wc, s, f, acr, cacr[static_cast<std::size_t>(f)]);
      node = node.child(s);
      word = wc.own[static_cast<std::size_t>(s)];
      acr = cacr;
      ++d;
    }
    const std::uint32_t span = 1U << (3 * (level - d));
    const std::uint32_t ulo = c & ~(span - 1U);
    // The faces are collected in a per-thread scratch list and copied into a new list of
    // their exact count (a cleared list kept its capacity and growth doubled it: over a
    // session the slack of thousands of small chunk lists, and of chunks the cut had emptied,
    // was most of the v_lists' memory; docs/drilling.md, "Session end and memory"). A new
    // list, never the old one rewritten: the render consumer may still hold the old one.
    thread_local std::vector<SurfaceFace> scratch;
    scratch.clear();
    std::size_t visits = 0;
    visit(h, wt, rk, node.depth, word, h.geometry(node), acr, scratch, visits);
    ch[ulo] = scratch.empty() ? nullptr : std::make_shared<const std::vector<SurfaceFace>>(scratch.begin(), scratch.end());
    budget.visits.fetch_add(visits, std::memory_order_relaxed);
    rebuilt.push_back({r, ulo});
    for (std::uint32_t k = ulo + 1; k < ulo + span; ++k) {
      if (!ch[k]) continue;
      ch[k] = nullptr;
      rebuilt.push_back({r, k});
    }
    c = ulo + span;
    if (budget.spent() && c < hi) return c;
  }
  return std::max(requested_hi, hi);
}

}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

std::array<double, 4> barycentric(const std::array<Vec3, 4>& x, const Vec3& p) {
  Mat3 e;
  for (int k = 0; k < 3; ++k) e.col(k) = x[static_cast<std::size_t>(k + 1)] - x[0];
  const Vec3 l = e.inverse() * (p - x[0]);
  return {1.0 - l.sum(), l.x(), l.y(), l.z()};
}

// Bytes of page storage handed out: node storage without the root words and page table.
std::size_t page_bytes(const TetHierarchy& h) { return h.live_group_bytes() + h.free_bytes(); }
// Bytes of the pages allocated, padding included.
std::size_t page_capacity(const TetHierarchy& h) {
  return h.page_count() * (TetHierarchy::kPageBytes + TetHierarchy::kPagePad);
}

TEST(TetHierarchy, RefineEraseMergeAndReuseMemory) {
  TetHierarchy h(make_cube12(10.0));
  EXPECT_EQ(h.root_count(), 12U);
  EXPECT_TRUE(test::rel_near(h.total_volume(), 1000.0, 1e-12));
  EXPECT_TRUE(test::rel_near(h.material_volume(), 1000.0, 1e-12));
  const NodeRef root{3, 0, 0};
  ASSERT_TRUE(h.refine(root));
  EXPECT_FALSE(h.refine(root));  // not a leaf any more
  EXPECT_EQ(h.state(root), NodeState::Internal);
  // A node whose children are all leaves is a mask word: no group storage at all.
  EXPECT_EQ(h.root_word(3), TetHierarchy::kMaskBase | 0xFFU);
  EXPECT_EQ(h.live_groups(), 0U);
  ASSERT_TRUE(h.refine(root.child(5)));
  EXPECT_EQ(h.internal_nodes(), 2U);
  EXPECT_EQ(h.node_count(), 12U + 16U);
  // The root now has an internal child: a group of 2 code bytes + 1 mask byte (4 allocated).
  EXPECT_EQ(h.live_groups(), 1U);
  EXPECT_EQ(h.live_group_bytes(), 4U);
  EXPECT_EQ(h.child_word(h.root_word(3), 5), TetHierarchy::kMaskBase | 0xFFU);
  EXPECT_LE(h.bytes_per_node(), 4.0);
  h.erase(root.child(5).child(2));
  EXPECT_EQ(h.child_word(h.root_word(3), 5), TetHierarchy::kMaskBase | (0xFFU & ~(1U << 2)));
  EXPECT_TRUE(test::rel_near(h.material_volume(), 1000.0 - h.root_volume(3) / 64.0, 1e-12));
  // Erase the remaining grandchildren: the block merges into an erased child, and the root's
  // group (no internal child left) becomes a mask again and goes to the free list.
  for (int s = 0; s < 8; ++s) h.erase(root.child(5).child(s));
  EXPECT_EQ(h.state(root.child(5)), NodeState::Erased);
  EXPECT_EQ(h.internal_nodes(), 1U);
  EXPECT_EQ(h.live_groups(), 0U);
  EXPECT_EQ(h.free_bytes(), 4U);
  EXPECT_EQ(h.root_word(3), TetHierarchy::kMaskBase | (0xFFU & ~(1U << 5)));
  // The freed group is reused.
  const std::size_t storage = h.node_storage_bytes();
  ASSERT_TRUE(h.refine(root.child(1)));
  EXPECT_EQ(h.free_bytes(), 0U);
  EXPECT_EQ(h.node_storage_bytes(), storage);
  EXPECT_EQ(h.internal_nodes(), 2U);
  EXPECT_TRUE(h.coarsen(root.child(1)));
  EXPECT_EQ(h.state(root.child(1)), NodeState::Full);
  EXPECT_FALSE(h.coarsen(root));  // child 5 is erased: not 8 full leaves
  // Erasing all children merges up to an erased root.
  for (int s = 0; s < 8; ++s) h.erase(root.child(s));
  EXPECT_EQ(h.state(root), NodeState::Erased);
  EXPECT_EQ(h.root_word(3), TetHierarchy::kErased);
  EXPECT_EQ(h.internal_nodes(), 0U);
  EXPECT_EQ(h.live_group_bytes(), 0U);
  EXPECT_TRUE(test::rel_near(h.material_volume(), 1000.0 - h.root_volume(3), 1e-12));
}

// Refines every leaf of root r down to `depth`.
void refine_all(TetHierarchy& h, std::uint32_t r, int depth) {
  std::vector<NodeRef> leaves;
  for (int d = 0; d < depth; ++d) {
    leaves.clear();
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      if (s == NodeState::Full) leaves.push_back(n);
    });
    for (const NodeRef& n : leaves) ASSERT_TRUE(h.refine(n));
  }
}

TEST(TetHierarchy, GroupsSpanningSeveralPagesKeepTheirWordsThroughErasureReuseAndCopy) {
  // 12 roots refined to depth 5: per root 4681 internal nodes; groups of 34 bytes (8 group
  // children) at depths 0–2 and 10 bytes (8 mask children) at depth 3, 7602 bytes per root,
  // 91 224 in all: beyond the first pages of 16 KiB.
  TetHierarchy h(make_cube12(10.0));
  for (std::uint32_t r = 0; r < 12; ++r) refine_all(h, r, 5);
  ASSERT_EQ(h.internal_nodes(), 12U * 4681U);
  EXPECT_EQ(h.node_count(), 12U + 8U * 12U * 4681U);
  EXPECT_EQ(h.live_group_bytes(), 12U * 7602U);
  EXPECT_EQ(h.live_groups(), 12U * (1U + 8U + 64U + 512U));
  EXPECT_GT(page_bytes(h), 5U * TetHierarchy::kPageBytes);
  // Every page byte handed out is a live group or on a free list.
  EXPECT_EQ(h.node_storage_bytes() - page_bytes(h), h.node_storage_capacity_bytes() - page_capacity(h));
  std::size_t leaves = 0;
  double sum = 0.0;
  for (std::size_t r = 0; r < h.root_count(); ++r)
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      EXPECT_EQ(s, NodeState::Full);
      EXPECT_EQ(n.depth, 5);
      ++leaves;
      sum += h.node_volume(n);
    });
  EXPECT_EQ(leaves, 12U * 32768U);
  EXPECT_TRUE(test::rel_near(sum, 1000.0, 1e-10));
  const TetHierarchy copy = h;
  // Erase root 11's leaves (its groups lie in the last pages): each erase reports the
  // topmost node that became an erased leaf, the last one the root itself.
  std::vector<NodeRef> last;
  h.for_each_leaf(11, [&](const NodeRef& n, NodeState) { last.push_back(n); });
  std::size_t merged_to_root = 0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    const NodeRef top = h.erase(last[i]);
    if (i % 8 != 7) {
      EXPECT_EQ(top, last[i]);  // siblings left: nothing merges
    } else {
      EXPECT_LT(top.depth, last[i].depth);
      EXPECT_EQ(h.state(top), NodeState::Erased);
      if (top.depth > 0) {
        EXPECT_EQ(h.state(top.parent()), NodeState::Internal);
      }
    }
    if (top.depth == 0) ++merged_to_root;
  }
  EXPECT_EQ(merged_to_root, 1U);
  EXPECT_EQ(h.state({11, 0, 0}), NodeState::Erased);
  EXPECT_EQ(h.internal_nodes(), 11U * 4681U);
  EXPECT_EQ(h.live_group_bytes(), 11U * 7602U);
  EXPECT_GE(h.free_bytes(), 7602U);
  EXPECT_TRUE(test::rel_near(h.material_volume(), 1000.0 - h.root_volume(11), 1e-10));
  EXPECT_EQ(h.node_storage_bytes() - page_bytes(h), h.node_storage_capacity_bytes() - page_capacity(h));
  // The copy kept its own words.
  EXPECT_TRUE(test::rel_near(copy.material_volume(), 1000.0, 1e-10));
  EXPECT_EQ(copy.internal_nodes(), 12U * 4681U);
  EXPECT_EQ(copy.live_group_bytes(), 12U * 7602U);
  std::size_t copy_leaves = 0;
  copy.for_each_leaf(11, [&](const NodeRef& n, NodeState s) {
    EXPECT_EQ(s, NodeState::Full);
    EXPECT_EQ(n.depth, 5);
    ++copy_leaves;
  });
  EXPECT_EQ(copy_leaves, 32768U);
  // Root 10's leaves refined once more: its depth-4 nodes become groups of 8 masks (10 bytes)
  // and its depth-3 groups grow to 34 bytes — 53 248 bytes more — taking root 11's freed
  // groups where the sizes match; the others' leaves are untouched.
  const TetHierarchy before = h;
  refine_all(h, 10, 1);
  EXPECT_EQ(h.live_group_bytes(), 11U * 7602U + 53248U);
  EXPECT_LT(h.free_bytes(), before.free_bytes());
  for (std::uint32_t r = 0; r < 10; ++r) {
    std::vector<std::pair<NodeRef, NodeState>> la, lb;
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { la.emplace_back(n, s); });
    before.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { lb.emplace_back(n, s); });
    ASSERT_EQ(la, lb) << "root " << r;
  }
  std::size_t deep = 0;
  h.for_each_leaf(10, [&](const NodeRef& n, NodeState s) {
    EXPECT_EQ(s, NodeState::Full);
    deep += n.depth == 6 ? 1 : 0;
  });
  EXPECT_EQ(deep, 262144U);
}

// A reference tree written from the rules alone: explicit nodes, no encoding.
struct ModelNode {
  NodeState state = NodeState::Full;
  std::vector<ModelNode> child;  // 8 when internal
};

ModelNode* model_find(ModelNode& root, const NodeRef& n) {
  ModelNode* m = &root;
  for (int level = 1; level <= n.depth; ++level) {
    if (m->state != NodeState::Internal) return nullptr;
    m = &m->child[static_cast<std::size_t>(n.slot(level))];
  }
  return m;
}

void model_leaves(const ModelNode& m, const NodeRef& n, std::vector<std::pair<NodeRef, NodeState>>& out) {
  if (m.state != NodeState::Internal) {
    out.emplace_back(n, m.state);
    return;
  }
  for (int s = 0; s < 8; ++s) model_leaves(m.child[static_cast<std::size_t>(s)], n.child(s), out);
}

void model_nodes(const ModelNode& m, const NodeRef& n, std::vector<NodeRef>& out) {
  out.push_back(n);
  if (m.state == NodeState::Internal)
    for (int s = 0; s < 8; ++s) model_nodes(m.child[static_cast<std::size_t>(s)], n.child(s), out);
}

// Internal nodes and the group bytes the encoding must hold for the model: a node with an
// internal child takes max(4, 2 + 1 per child with 8 leaf children + 4 per other internal child).
void model_census(const ModelNode& m, std::size_t& internal, std::size_t& group_bytes, std::size_t& groups) {
  if (m.state != NodeState::Internal) return;
  ++internal;
  std::size_t size = 2;
  for (const ModelNode& c : m.child) {
    if (c.state != NodeState::Internal) continue;
    const bool leaf_children =
        std::all_of(c.child.begin(), c.child.end(), [](const ModelNode& g) { return g.state != NodeState::Internal; });
    size += leaf_children ? 1 : 4;
    model_census(c, internal, group_bytes, groups);
  }
  if (size > 2) {
    group_bytes += std::max<std::size_t>(size, 4);
    ++groups;
  }
}

TEST(TetHierarchy, RandomRefineEraseCoarsenEqualTheReferenceTree) {
  // 3000 random operations on 12 roots (refine a full leaf, erase a random node — leaf or
  // internal, alone or after its siblings — through erase(node) or erase(node, ancestor words), coarsen a random node):
  // after each, the hierarchy's answers, leaves, counts and group bytes equal the
  // reference tree's, and the page bytes are the live groups plus the free lists.
  TetHierarchy h(make_cube12(10.0));
  std::array<ModelNode, 12> model;
  std::mt19937 rng(7);
  std::size_t merges = 0, coarsened = 0, refined = 0, with_words = 0;
  for (int op = 0; op < 3000; ++op) {
    std::vector<std::uint32_t> live;
    for (std::uint32_t q = 0; q < 12; ++q)
      if (model[q].state != NodeState::Erased) live.push_back(q);
    ASSERT_FALSE(live.empty());
    const auto r = live[rng() % live.size()];
    ModelNode& root = model[r];
    std::vector<NodeRef> nodes;
    model_nodes(root, NodeRef{r, 0, 0}, nodes);
    const int kind = static_cast<int>(rng() % 10);
    if (kind < 7) {  // refine a full leaf (biased to deep ones so the tree grows)
      std::vector<NodeRef> full;
      for (const NodeRef& n : nodes)
        if (model_find(root, n)->state == NodeState::Full && n.depth < 5) full.push_back(n);
      if (full.empty()) continue;
      std::sort(full.begin(), full.end(), [](const NodeRef& a, const NodeRef& b) { return a.depth > b.depth; });
      const NodeRef n = full[rng() % std::min<std::size_t>(full.size(), 1 + rng() % 40)];
      ASSERT_TRUE(h.refine(n));
      ModelNode* m = model_find(root, n);
      m->state = NodeState::Internal;
      m->child.assign(8, ModelNode{});
      ++refined;
    } else if (kind < 9) {  // erase a node (a root rarely), or it and its siblings (20 %)
      NodeRef n = nodes[rng() % nodes.size()];
      if (n.depth == 0 && rng() % 50 != 0) continue;
      if (n.depth > 0 && model_find(root, n)->state != NodeState::Erased && rng() % 3 == 0) {
        // Erase its non-erased siblings first (through the same operation below), so sibling
        // groups empty and merge.
        for (int sib = 0; sib < 8; ++sib) {
          const NodeRef o = n.parent().child(sib);
          if (o == n || model_find(root, o) == nullptr || model_find(root, o)->state == NodeState::Erased) continue;
          const NodeRef t = h.erase(o);
          ModelNode* m = model_find(root, o);
          m->state = NodeState::Erased;
          m->child.clear();
          ASSERT_EQ(t, o) << "op " << op;  // n is not erased yet: nothing merges
        }
      }
      NodeRef top;
      if (rng() % 2 == 0 && n.depth > 0) {
        std::vector<std::uint32_t> words;
        std::uint32_t w = h.root_word(r);
        for (int d = 0; d < n.depth; ++d) {
          words.push_back(w);
          w = h.child_word(w, n.slot(d + 1));
        }
        top = h.erase(n, words);
        ++with_words;
      } else {
        top = h.erase(n);
      }
      ModelNode* m = model_find(root, n);
      m->state = NodeState::Erased;
      m->child.clear();
      NodeRef t = n;
      while (t.depth > 0) {
        ModelNode* p = model_find(root, t.parent());
        if (!std::all_of(p->child.begin(), p->child.end(), [](const ModelNode& c) { return c.state == NodeState::Erased; }))
          break;
        p->state = NodeState::Erased;
        p->child.clear();
        t = t.parent();
      }
      ASSERT_EQ(top, t) << "op " << op;
      if (t.depth < n.depth) ++merges;
    } else {  // coarsen
      const NodeRef n = nodes[rng() % nodes.size()];
      ModelNode* m = model_find(root, n);
      const bool can = m->state == NodeState::Internal &&
                       std::all_of(m->child.begin(), m->child.end(), [](const ModelNode& c) { return c.state == NodeState::Full; });
      ASSERT_EQ(h.coarsen(n), can) << "op " << op;
      if (can) {
        m->state = NodeState::Full;
        m->child.clear();
        ++coarsened;
      }
    }
    std::size_t internal = 0, group_bytes = 0, groups = 0;
    for (std::uint32_t q = 0; q < 12; ++q) {
      std::vector<std::pair<NodeRef, NodeState>> lm, lh;
      model_leaves(model[q], NodeRef{q, 0, 0}, lm);
      h.for_each_leaf(q, [&](const NodeRef& n, NodeState s) { lh.emplace_back(n, s); });
      ASSERT_EQ(lh, lm) << "op " << op << " root " << q;
      model_census(model[q], internal, group_bytes, groups);
    }
    ASSERT_EQ(h.internal_nodes(), internal) << "op " << op;
    ASSERT_EQ(h.live_group_bytes(), group_bytes) << "op " << op;
    ASSERT_EQ(h.live_groups(), groups) << "op " << op;
    ASSERT_EQ(h.node_storage_bytes() - page_bytes(h), h.node_storage_capacity_bytes() - page_capacity(h))
        << "op " << op;
    for (const NodeRef& n : nodes) {
      const ModelNode* m = model_find(root, n);
      if (m != nullptr) {
        ASSERT_EQ(h.state(n), m->state) << "op " << op;
      }
    }
  }
  EXPECT_GT(refined, 1000U);
  EXPECT_GT(merges, 30U);
  EXPECT_GT(coarsened, 10U);
  EXPECT_GT(with_words, 200U);
}

TEST(TetHierarchy, RepeatedRefineAndEraseReusesTheFreedMemory) {
  // Roots 1–5 in turn: refined to depth 4 (946 bytes of groups), then every leaf erased (the
  // groups merge away to an erased root). The same operations on an identical root ask for
  // the same group sizes in the same order, and every byte the first cycle handed out is on
  // the free lists afterwards: the later cycles take nothing new.
  TetHierarchy h(make_cube12(10.0));
  refine_all(h, 0, 2);  // another root's group (10 bytes) stays live throughout
  std::size_t first = 0;
  for (std::uint32_t r = 1; r <= 5; ++r) {
    refine_all(h, r, 4);
    EXPECT_EQ(h.internal_nodes(), 9U + 585U);
    EXPECT_EQ(h.live_group_bytes(), 10U + 946U);
    std::vector<NodeRef> leaves;
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState) { leaves.push_back(n); });
    for (const NodeRef& n : leaves) h.erase(n);
    EXPECT_EQ(h.state({r, 0, 0}), NodeState::Erased);
    EXPECT_EQ(h.internal_nodes(), 9U);
    EXPECT_EQ(h.live_group_bytes(), 10U);
    EXPECT_GE(h.free_bytes(), 946U);
    if (r == 1) first = h.node_storage_bytes();
    EXPECT_EQ(h.node_storage_bytes(), first) << "root " << r;
  }
  EXPECT_TRUE(test::rel_near(h.material_volume(), 1000.0 - h.root_volume(1) - h.root_volume(2) - h.root_volume(3) -
                                                     h.root_volume(4) - h.root_volume(5),
                             1e-12));
}

TEST(TetHierarchy, EraseWithAncestorWordsEqualsEraseFromTheRoot) {
  // Two copies refined alike; the sibling groups of random leaves erased in one through
  // erase(node) and in the other through erase(node, ancestor words read top-down): same
  // merged nodes, same trees.
  TetHierarchy a(make_cube12(10.0));
  for (std::uint32_t r = 0; r < 12; ++r) refine_all(a, r, 3);
  TetHierarchy b = a;
  std::mt19937 rng(11);
  std::size_t merges = 0, erased = 0;
  auto erase_both = [&](const NodeRef& n) {
    std::vector<std::uint32_t> words;
    std::uint32_t w = b.root_word(n.root);
    for (int d = 0; d < n.depth; ++d) {
      words.push_back(w);
      w = b.child_word(w, n.slot(d + 1));
    }
    const NodeRef ta = a.erase(n);
    const NodeRef tb = b.erase(n, words);
    ASSERT_EQ(ta, tb);
    ++erased;
    if (ta.depth < n.depth) ++merges;
  };
  for (int i = 0; i < 300; ++i) {
    const auto r = static_cast<std::uint32_t>(rng() % 12);
    std::vector<NodeRef> full;
    a.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      if (s == NodeState::Full && n.depth > 0) full.push_back(n);
    });
    if (full.empty()) continue;
    const NodeRef p = full[rng() % full.size()].parent();
    for (int s = 0; s < 8; ++s)
      if (a.state(p.child(s)) == NodeState::Full && rng() % 8 != 0) erase_both(p.child(s));
  }
  EXPECT_GT(erased, 1000U);
  EXPECT_GT(merges, 50U);
  EXPECT_EQ(a.internal_nodes(), b.internal_nodes());
  EXPECT_EQ(a.live_group_bytes(), b.live_group_bytes());
  for (std::uint32_t r = 0; r < 12; ++r) {
    std::vector<std::pair<NodeRef, NodeState>> la, lb;
    a.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { la.emplace_back(n, s); });
    b.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { lb.emplace_back(n, s); });
    ASSERT_EQ(la, lb) << "root " << r;
  }
}

TEST(TetHierarchy, ChangesOnHeldPathWordsEqualChangesFromTheRoot) {
  // Random refine / erase / coarsen on two copies: in one through refine(node), erase(node)
  // and coarsen(node), in the other through the *_on_path calls with the path words read
  // top-down. Same results, same trees, same storage; the path words handed back are the
  // ones a fresh walk reads, and child_words() agrees with child_word().
  TetHierarchy a(make_cube12(10.0));
  for (std::uint32_t r = 0; r < 12; ++r) refine_all(a, r, 2);
  TetHierarchy b = a;
  std::mt19937 rng(23);
  std::size_t ops[3] = {0, 0, 0}, merges = 0;
  auto path_of = [](const TetHierarchy& h, const NodeRef& n) {
    TetHierarchy::PathWords w{};
    w[0] = h.root_word(n.root);
    for (int d = 1; d <= n.depth; ++d) {
      const auto du = static_cast<std::size_t>(d);
      w[du] = h.child_word(w[du - 1], n.slot(d));
    }
    return w;
  };
  for (int i = 0; i < 4000; ++i) {
    const auto r = static_cast<std::uint32_t>(rng() % 12);
    std::vector<std::pair<NodeRef, NodeState>> leaves;
    a.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { leaves.emplace_back(n, s); });
    const auto [leaf, st] = leaves[rng() % leaves.size()];
    TetHierarchy::PathWords w = path_of(b, leaf);
    const int op = static_cast<int>(rng() % 3);
    if (op == 0 && st == NodeState::Full && leaf.depth < 6) {
      ASSERT_TRUE(a.refine(leaf));
      ASSERT_TRUE(b.refine_on_path(leaf, w));
    } else if (op == 1 && st == NodeState::Full) {
      // The leaf, and half the time its full siblings after it (so blocks merge).
      std::vector<NodeRef> go{leaf};
      if (leaf.depth > 0 && rng() % 2 == 0)
        for (int c = 0; c < 8; ++c)
          if (leaf.parent().child(c) != leaf && a.state(leaf.parent().child(c)) == NodeState::Full)
            go.push_back(leaf.parent().child(c));
      for (const NodeRef& n : go) {
        TetHierarchy::PathWords wn = path_of(b, n);
        const NodeRef ta = a.erase(n);
        ASSERT_EQ(b.erase_on_path(n, wn), ta);
        if (ta.depth < n.depth) ++merges;
        const TetHierarchy::PathWords fresh = path_of(b, n);
        for (int d = 0; d <= ta.depth; ++d)
          ASSERT_EQ(wn[static_cast<std::size_t>(d)], fresh[static_cast<std::size_t>(d)]);
        for (int d = ta.depth; d <= n.depth; ++d) ASSERT_EQ(wn[static_cast<std::size_t>(d)], TetHierarchy::kErased);
      }
      ++ops[op];
      continue;
    } else if (op == 2 && leaf.depth > 0) {
      const NodeRef p = leaf.parent();
      w = path_of(b, p);
      const bool can = a.coarsen(p);
      ASSERT_EQ(b.coarsen_on_path(p, w), can);
      if (!can) continue;
      ASSERT_EQ(w, path_of(b, p));
      ++ops[2];
      continue;
    } else {
      continue;
    }
    ++ops[op];
    // The words handed back are the current ones (kErased below a merged node).
    const TetHierarchy::PathWords fresh = path_of(b, leaf);
    for (int d = 0; d <= leaf.depth; ++d) {
      const auto du = static_cast<std::size_t>(d);
      ASSERT_EQ(w[du], fresh[du]) << "op " << i << " depth " << d;
      if (fresh[du] == TetHierarchy::kErased) break;
    }
  }
  EXPECT_GT(ops[0], 300U);
  EXPECT_GT(ops[1], 300U);
  EXPECT_GT(ops[2], 20U);
  EXPECT_GT(merges, 10U);
  EXPECT_EQ(a.internal_nodes(), b.internal_nodes());
  EXPECT_EQ(a.live_group_bytes(), b.live_group_bytes());
  EXPECT_EQ(a.free_bytes(), b.free_bytes());
  EXPECT_EQ(a.node_storage_bytes(), b.node_storage_bytes());
  for (std::uint32_t r = 0; r < 12; ++r) {
    std::vector<std::pair<NodeRef, NodeState>> la, lb;
    a.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { la.emplace_back(n, s); });
    b.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { lb.emplace_back(n, s); });
    ASSERT_EQ(la, lb) << "root " << r;
    // child_words() against child_word() on every internal node.
    struct Item {
      NodeRef node;
      std::uint32_t word;
    };
    std::vector<Item> stack{{NodeRef{r, 0, 0}, b.root_word(r)}};
    while (!stack.empty()) {
      const Item it = stack.back();
      stack.pop_back();
      if (TetHierarchy::state_of_word(it.word) != NodeState::Internal) continue;
      const auto words = b.child_words(it.word);
      for (int c = 0; c < 8; ++c) {
        ASSERT_EQ(words[static_cast<std::size_t>(c)], b.child_word(it.word, c));
        stack.push_back({it.node.child(c), words[static_cast<std::size_t>(c)]});
      }
    }
  }
}

TEST(TetHierarchy, LeafVolumesSumToRootAfterDeepRefinement) {
  TetHierarchy h(make_block({2, 2, 2}, 2.0));
  std::mt19937 rng(5);
  for (int i = 0; i < 400; ++i) {
    const Vec3 p(2.0 * std::uniform_real_distribution<double>(0, 1)(rng), 2.0 * std::uniform_real_distribution<double>(0, 1)(rng),
                 2.0 * std::uniform_real_distribution<double>(0, 1)(rng));
    const auto loc = h.locate(p);
    ASSERT_TRUE(loc.inside_mesh);
    if (loc.leaf.depth < 7) h.refine(loc.leaf);
  }
  double sum = 0.0, geometric = 0.0;
  for (std::size_t r = 0; r < h.root_count(); ++r)
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState) {
      sum += h.node_volume(n);
      const auto x = h.world_vertices(n);
      const double v = signed_volume(x[0], x[1], x[2], x[3]);
      EXPECT_EQ(v < 0.0, h.geometry(n).flipped);
      geometric += std::abs(v);
    });
  EXPECT_TRUE(test::rel_near(sum, 8.0, 1e-12));
  EXPECT_TRUE(test::rel_near(geometric, 8.0, 1e-12));
  EXPECT_LE(h.bytes_per_node(), 4.0);
}

TEST(TetHierarchy, LocateFindsTheLeafContainingThePoint) {
  TetHierarchy h(make_block({4.0, 3.0, 2.0}, 1.0));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const auto loc = h.locate(Vec3(4 * u(rng), 3 * u(rng), 2 * u(rng)));
    if (loc.leaf.depth < 4) h.refine(loc.leaf);
  }
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p(4 * u(rng), 3 * u(rng), 2 * u(rng));
    const auto loc = h.locate(p);
    ASSERT_TRUE(loc.inside_mesh);
    const auto l = barycentric(h.world_vertices(loc.leaf), p);
    EXPECT_GE(*std::min_element(l.begin(), l.end()), -1e-9);
    EXPECT_NE(h.state(loc.leaf), NodeState::Internal);
  }
  EXPECT_FALSE(h.locate(Vec3(5.0, 1.0, 1.0)).inside_mesh);
  EXPECT_FALSE(h.locate(Vec3(-0.01, 1.0, 1.0)).inside_mesh);
}

TEST(TetHierarchy, LocateWithBoxRejectionsAgreesWithTestingEveryRoot) {
  // locate() skips points outside the mesh box and candidate roots whose box does not hold
  // the point; the slow path tests the barycentric coordinates of every root. Points are
  // spread over a box 30 % larger than the block (air on every side) and pushed onto root
  // faces and vertices now and then; only points within 1e-9 of a root boundary, where two
  // roots tie, are left out of the comparison of roots.
  TetHierarchy h(make_block({4.0, 3.0, 2.0}, 1.0));
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-0.15, 1.15);
  for (int i = 0; i < 300; ++i) {
    const auto loc = h.locate(Vec3(4 * std::clamp(u(rng), 0.0, 1.0), 3 * std::clamp(u(rng), 0.0, 1.0), 2 * std::clamp(u(rng), 0.0, 1.0)));
    if (loc.inside_mesh && loc.leaf.depth < 4) h.refine(loc.leaf);
  }
  std::size_t outside = 0, inside = 0, hinted = 0;
  std::int32_t hint = -1;
  for (int i = 0; i < 20000; ++i) {
    Vec3 p(4 * u(rng), 3 * u(rng), 2 * u(rng));
    if (i % 5 == 0) p = p.cwiseMax(Vec3::Zero()).cwiseMin(Vec3(4.0, 3.0, 2.0));  // on the block's faces
    if (i % 7 == 0) p = p.array().round();                                         // on mesh vertices
    std::int32_t best = -1;
    double best_min = -std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < h.root_count(); ++r) {
      const auto l = h.root_barycentric(r, p);
      const double m = *std::min_element(l.begin(), l.end());
      if (m > best_min) {
        best_min = m;
        best = static_cast<std::int32_t>(r);
      }
    }
    // Several hints (a wrong root, a repeat, none, the last inside root), as collide() passes.
    const auto wrong = static_cast<std::int32_t>(static_cast<std::size_t>(i) % h.root_count());
    const std::array<std::int32_t, 4> hints{wrong, -1, wrong, hint};
    for (int variant = 0; variant < 3; ++variant) {
      const std::int32_t hr = variant == 1 ? hint : -1;
      const Location loc = variant == 0 ? h.locate(p) : variant == 1 ? h.locate(p, hint) : h.locate(p, std::span<const std::int32_t>(hints));
      if (best_min < -1e-9) {
        ASSERT_FALSE(loc.inside_mesh) << "point " << i;
        ++outside;
        continue;
      }
      if (best_min < -1e-12) continue;  // within rounding of the mesh boundary
      ASSERT_TRUE(loc.inside_mesh) << "point " << i;
      if (best_min > 1e-9) {
        EXPECT_EQ(static_cast<std::int32_t>(loc.leaf.root), best) << "point " << i;
        ++inside;
      }
      const auto l = barycentric(h.world_vertices(loc.leaf), p);
      EXPECT_GE(*std::min_element(l.begin(), l.end()), -1e-9) << "point " << i;
      EXPECT_EQ(loc.state, h.state(loc.leaf));
      if (hr >= 0 || variant == 2) ++hinted;
    }
    if (best_min > 1e-9) hint = best;
  }
  EXPECT_GT(outside, 2000U);
  EXPECT_GT(inside, 10000U);
  EXPECT_GT(hinted, 20000U);
}

TEST(TetHierarchy, RootOrderMaximisesWorstDescendantQuality) {
  geometry::TetMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0.2, 1, 0), Vec3(0.1, 0.3, 0.7)};
  m.tets = {{0, 1, 2, 3}};
  auto worst = [](const TetHierarchy& h) {
    TetHierarchy copy = h;
    double q = 1.0;
    copy.refine({0, 0, 0});
    for (int s = 0; s < 8; ++s) {
      copy.refine(NodeRef{0, 0, 0}.child(s));
      for (int g = 0; g < 8; ++g) q = std::min(q, tet_mean_ratio(copy.world_vertices(NodeRef{0, 0, 0}.child(s).child(g))));
    }
    return q;
  };
  const TetHierarchy kept(m, {.reorder_roots = false});
  const TetHierarchy chosen(m, {.reorder_roots = true});
  EXPECT_GE(worst(chosen), worst(kept) - 1e-12);
  EXPECT_TRUE(test::rel_near(chosen.root_volume(0), kept.root_volume(0), 1e-12));
}

TEST(TetHierarchy, RejectsBadMeshes) {
  geometry::TetMesh m;
  EXPECT_THROW(TetHierarchy{m}, InvalidInput);
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  m.tets = {{0, 1, 2, 3}};
  EXPECT_THROW(TetHierarchy{m}, InvalidInput);  // flat
  m.tets = {{0, 1, 2, 7}};
  EXPECT_THROW(TetHierarchy{m}, InvalidInput);  // index out of range
  EXPECT_THROW((void)make_shape("block:1,2"), InvalidInput);
  EXPECT_THROW((void)make_shape("sphere"), InvalidInput);
}

}  // namespace
}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
// Erosion: the Eroder leaves exactly the tree a reference written from the rules leaves, with
// or without its work budget; the force threshold, the removal rate and density, the backlog,
// a resting burr and the node limit behave as documented.
#include "ido/drill/erosion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/geometry/mesh_checks.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

// Reference erosion written from the rules alone, the slow way: node states read from the
// root (TetHierarchy::state) and geometry from the path (world_vertices) at every node, and
// only the bounding-sphere rejection. It must leave exactly the tree the Eroder leaves
// (states carried down the traversal, face-plane rejection, resumable budgeted passes).
// A tetrahedron against the burr (centre c, radius r): its centroid, the largest distance of a
// corner from it, and whether every corner lies inside the burr.
struct BurrCover {
  Vec3 centroid;
  double reach = 0.0;
  bool all_inside = true;
};
BurrCover burr_cover(const std::array<Vec3, 4>& x, const Vec3& c, double r) {
  BurrCover b{0.25 * (x[0] + x[1] + x[2] + x[3])};
  for (const auto& v : x) {
    b.reach = std::max(b.reach, (v - b.centroid).norm());
    b.all_inside = b.all_inside && (v - c).squaredNorm() <= r * r;
  }
  return b;
}

bool reference_would_remove(const std::array<Vec3, 4>& x, int depth, int finest, const Vec3& c, double r) {
  const auto [centroid, reach, all_inside] = burr_cover(x, c, r);
  if ((c - centroid).norm() > r + reach) return false;
  if (all_inside) return true;
  if (depth >= finest) return (centroid - c).squaredNorm() <= r * r;
  for (const auto& ch : red_children(x))
    if (reference_would_remove(ch, depth + 1, finest, c, r)) return true;
  return false;
}

void reference_erode(TetHierarchy& h, const NodeRef& n, int finest, const Vec3& c, double r) {
  const NodeState st = h.state(n);
  if (st == NodeState::Erased) return;
  const auto x = h.world_vertices(n);
  const auto [centroid, reach, all_inside] = burr_cover(x, c, r);
  if ((c - centroid).norm() > r + reach) return;
  if (all_inside || n.depth >= finest) {
    if (all_inside || (centroid - c).squaredNorm() <= r * r) h.erase(n);
    return;
  }
  if (st == NodeState::Full) {
    if (!reference_would_remove(x, n.depth, finest, c, r)) return;
    ASSERT_TRUE(h.refine(n));
  }
  for (int s = 0; s < 8; ++s) reference_erode(h, n.child(s), finest, c, r);
  (void)h.coarsen(n);  // a refinement that removed nothing is undone
}

std::vector<std::pair<std::uint64_t, NodeState>> leaves(const TetHierarchy& h) {
  std::vector<std::pair<std::uint64_t, NodeState>> out;
  for (std::size_t r = 0; r < h.root_count(); ++r)
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState st) {
      out.emplace_back((static_cast<std::uint64_t>(n.root) << 40) | (static_cast<std::uint64_t>(n.depth) << 32) | n.path, st);
    });
  return out;
}

TEST(Erosion, TreeEqualsAReferenceEroderWithAndWithoutBudget) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 2; ++trial) {
    const int finest = 4 + trial;
    TetHierarchy ref(make_block({10, 8, 6}, 2.0));
    TetHierarchy fast(make_block({10, 8, 6}, 2.0));
    TetHierarchy budgeted(make_block({10, 8, 6}, 2.0));
    Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = finest, .max_node_visits = 0});
    Eroder slow_passes({.removal_rate_mm3_per_s = 0.0, .max_depth = finest, .max_node_visits = 0, .backlog_spacing = 0.0});
    std::size_t passes = 0;
    Vec3 c(10 * u(rng), 8 * u(rng), 3 + 3 * u(rng));
    for (int step = 0; step < 16; ++step) {
      // A wandering burr, so later spheres cut through refined and merged regions.
      c += Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 1.5;
      const double r = 0.8 + 1.2 * u(rng);
      for (std::size_t root = 0; root < ref.root_count(); ++root)
        reference_erode(ref, NodeRef{static_cast<std::uint32_t>(root), 0, 0}, finest, c, r);
      (void)eroder.erode(fast, c, r, 1.0, 0.01);
      slow_passes.enqueue(c, r, 1.0, 0.01);
      while (slow_passes.has_pending()) {
        (void)slow_passes.run(budgeted, 150);
        ++passes;
      }
      ASSERT_TRUE(leaves(fast) == leaves(ref)) << "trial " << trial << " step " << step;
      ASSERT_TRUE(leaves(budgeted) == leaves(ref)) << "trial " << trial << " step " << step;
    }
    EXPECT_GT(passes, 100U);  // the budget interrupted the traversal many times
    EXPECT_LT(ref.material_volume(), ref.total_volume() - 10.0);
  }
}

TEST(Erosion, BelowTheThresholdNothingGoesAndRateLimitsRemoval) {
  TetHierarchy h(make_block({10, 10, 10}, 2.5));
  Eroder eroder({.force_threshold_n = 1.0, .removal_rate_mm3_per_s = 10.0, .max_depth = 5, .max_node_visits = 0});
  const double before = h.material_volume();
  auto stats = eroder.erode(h, Vec3(5, 5, 10), 2.0, 0.5, 0.01);
  EXPECT_EQ(stats.nodes_removed, 0U);
  EXPECT_TRUE(test::rel_near(h.material_volume(), before, 1e-12));
  double removed = 0.0;
  for (int i = 0; i < 10; ++i) removed += eroder.erode(h, Vec3(5, 5, 10), 2.0, 2.0, 0.01).removed_volume_mm3;
  EXPECT_LE(removed, 10.0 * 0.1 + 1e-9);  // rate × time
  EXPECT_GT(removed, 0.5);                // most of the budget is used
  EXPECT_TRUE(test::rel_near(before - h.material_volume(), removed, 1e-9));
  // Denser material erodes more slowly.
  TetHierarchy dense(make_block({10, 10, 10}, 2.5));
  for (std::size_t r = 0; r < dense.root_count(); ++r) dense.set_density(r, 2.0F);
  Eroder e2({.force_threshold_n = 1.0, .removal_rate_mm3_per_s = 10.0, .max_depth = 5, .max_node_visits = 0});
  double removed_dense = 0.0;
  for (int i = 0; i < 10; ++i) removed_dense += e2.erode(dense, Vec3(5, 5, 10), 2.0, 2.0, 0.01).removed_volume_mm3;
  EXPECT_LE(removed_dense, 0.5 * 10.0 * 0.1 + 1e-9);
}

// Leaf states of every root, depth-first: equal trees give equal lists.
std::vector<std::pair<std::uint64_t, int>> leaves_of(const TetHierarchy& h) {
  std::vector<std::pair<std::uint64_t, int>> out;
  for (std::size_t r = 0; r < h.root_count(); ++r)
    h.for_each_leaf(r, [&](const NodeRef& n, NodeState s) {
      out.emplace_back((static_cast<std::uint64_t>(n.root) << 40) | (static_cast<std::uint64_t>(n.depth) << 32) | n.path,
                       static_cast<int>(s));
    });
  return out;
}

// @p count random burr centres inside the 10 × 8 × 6 mm test block, 1 mm from its faces.
std::vector<Vec3> burr_centres_in_block(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> centres;
  for (int i = 0; i < count; ++i) centres.emplace_back(1 + 8 * u(rng), 1 + 6 * u(rng), 1 + 4 * u(rng));
  return centres;
}

TEST(Erosion, VisitBudgetSplitsTheWorkButNotTheResult) {
  // The same burr positions with no budget and with a budget of 400 visits per pass (v_list rebuilds 300) (and
  // no coalescing): every pass does at most the budget plus one dry run, the work carries
  // over, and once finished the trees are identical. Meanwhile the chunked v_lists rebuilt
  // from the changed nodes equal a full rebuild (after flushing) every 40 passes, at chunk levels 0, 2, 3.
  const std::vector<Vec3> centres = burr_centres_in_block(16, 5);
  TetHierarchy reference(make_block({10, 8, 6}, 2.0));
  Eroder full({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 0});
  for (const auto& c : centres) full.erode(reference, c, 1.2, 1.0, 0.01);
  for (const int level : {0, 2, 3}) {
    TetHierarchy h(make_block({10, 8, 6}, 2.0));
    BoundarySurface surface(h, {.chunk_level = level});
    Eroder budgeted({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 400, .backlog_spacing = 0.0});
    std::size_t passes = 0, carried = 0;
    auto pass = [&](const ErosionStats& st) {
      ++passes;
      carried += st.work_pending ? 1 : 0;
      // One dry run may overshoot the budget: at most the nodes below a depth-0 leaf.
      EXPECT_LE(st.nodes_visited, 400U + 8U * 8U * 8U * 8U * 2U);
      // The v_list rebuild has a budget too: chunks left over wait for a later update.
      surface.update(h, budgeted.changed_nodes(), 300);
      budgeted.clear_changed_roots();
      if (passes % 40 != 0) return;
      surface.flush(h);
      EXPECT_FALSE(surface.has_pending());
      const BoundarySurface fresh(h, {.chunk_level = level});
      for (std::size_t r = 0; r < h.root_count(); ++r)
        ASSERT_TRUE(fresh.v_list(r) == surface.v_list(r)) << "level " << level << " pass " << passes << " root " << r;
    };
    for (const auto& c : centres) pass(budgeted.erode(h, c, 1.2, 1.0, 0.01));
    while (budgeted.has_pending()) pass(budgeted.run(h, 400));
    surface.flush(h);
    EXPECT_GT(carried, 10U) << "the budget never ran out: the test does not test it";
    std::printf("chunk level %d: %zu passes, %zu carried over\n", level, passes, carried);
    EXPECT_EQ(h.node_count(), reference.node_count());
    EXPECT_EQ(h.material_volume(), reference.material_volume());
    EXPECT_TRUE(leaves_of(h) == leaves_of(reference));
    const BoundarySurface fresh(h, {.chunk_level = level});
    for (std::size_t r = 0; r < h.root_count(); ++r) ASSERT_TRUE(fresh.v_list(r) == surface.v_list(r));
    const auto mesh = assemble_surface(surface.v_lists(), h.vertices());
    const auto check = geometry::check_mesh(mesh);
    EXPECT_EQ(check.boundary_edges, 0U);
    EXPECT_TRUE(test::rel_near(check.signed_volume_mm3, h.material_volume(), 1e-9));
  }
}

// Sibling blocks of root r's tree: (8 full leaves, 8 erased leaves, others).
std::array<std::size_t, 3> uniform_leaf_blocks(const TetHierarchy& h, std::size_t r) {
  std::array<std::size_t, 3> n{};
  std::vector<std::uint32_t> stack{h.root_word(r)};
  while (!stack.empty()) {
    const std::uint32_t w = stack.back();
    stack.pop_back();
    if (TetHierarchy::state_of_word(w) != NodeState::Internal) continue;
    int full = 0, erased = 0;
    for (int s = 0; s < 8; ++s) {
      const std::uint32_t c = h.child_word(w, s);
      full += c == TetHierarchy::kFull ? 1 : 0;
      erased += c == TetHierarchy::kErased ? 1 : 0;
      stack.push_back(c);
    }
    ++n[full == 8 ? 0 : erased == 8 ? 1 : 2];
  }
  return n;
}

TEST(Erosion, LeavesNoSiblingBlockOfEightFullOrEightErasedLeaves) {
  // What bench BM_BlockCensus measures (bench/drill/drill_update_bench.cpp): after erosion,
  // with or without a visit budget and with the volume budget running out (frames dropped),
  // no block holds 8 full leaves (a partly covered leaf is refined only when the dry run
  // finds a descendant that goes, and an idle refinement is undone on leaving its node:
  // disabling both fails this test, either one alone does not) or 8 erased leaves (merged
  // into the parent), so merging all-full blocks back into their parent has nothing to merge.
  const std::vector<Vec3> centres = burr_centres_in_block(24, 11);
  const std::vector<ErosionOptions> options{
      {.removal_rate_mm3_per_s = 0.0, .max_depth = 5, .max_node_visits = 0},
      {.removal_rate_mm3_per_s = 0.0, .max_depth = 5, .max_node_visits = 300},
      {.removal_rate_mm3_per_s = 5.0, .max_depth = 5, .max_node_visits = 300}};
  for (std::size_t k = 0; k < options.size(); ++k) {
    TetHierarchy h(make_block({10, 8, 6}, 2.0));
    Eroder eroder(options[k]);
    ErosionStats last;
    bool limited = false;
    for (const auto& c : centres) {
      last = eroder.erode(h, c, 1.3, 1.0, 0.01);
      limited = limited || last.rate_limited;
    }
    limited = eroder.finish(h).rate_limited || limited;
    EXPECT_FALSE(eroder.has_pending());
    if (k == 2) {
      EXPECT_TRUE(limited) << "the volume budget never ran out: the drop path is not tested";
    }
    std::array<std::size_t, 3> total{};
    for (std::size_t r = 0; r < h.root_count(); ++r) {
      const auto n = uniform_leaf_blocks(h, r);
      for (std::size_t i = 0; i < 3; ++i) total[i] += n[i];
    }
    EXPECT_EQ(total[0], 0U) << "options " << k;
    EXPECT_EQ(total[1], 0U) << "options " << k;
    EXPECT_EQ(total[2], h.internal_nodes()) << "options " << k;
    EXPECT_GT(total[2], 100U) << "options " << k << ": too little refined to test anything";
  }
  // The census sees an all-full block where one exists: a refinement made by hand.
  TetHierarchy h(make_block({10, 8, 6}, 2.0));
  ASSERT_TRUE(h.refine(NodeRef{3, 0, 0}));
  EXPECT_EQ(uniform_leaf_blocks(h, 3)[0], 1U);
}

TEST(Erosion, BacklogKeepsPositionsAtMostTheSpacingApart) {
  // With a tiny budget the queue would grow by one position per call; coalescing keeps
  // only positions ≥ spacing · radius apart (plus the newest).
  TetHierarchy h(make_block({20, 8, 6}, 2.0));
  Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 1, .backlog_spacing = 0.25});
  for (int i = 0; i <= 200; ++i) e.erode(h, Vec3(2 + 0.05 * i, 4, 6), 1.0, 1.0, 1e-3);
  // 10 mm at spacing 0.25 mm: about 40 positions, far fewer than the 200 calls.
  EXPECT_LE(e.queued(), 45U);
  EXPECT_GE(e.queued(), 25U);
  EXPECT_TRUE(e.has_pending());
  const auto st = e.finish(h);
  EXPECT_FALSE(e.has_pending());
  EXPECT_GT(st.removed_volume_mm3, 0.0);
}

TEST(Erosion, RestingBurrAddsNoWork) {
  // Once a position is processed, the same position again removes nothing: it is not queued,
  // so a burr held still in contact leaves the backlog empty (the session can end).
  TetHierarchy h(make_block({8, 8, 6}, 2.0));
  Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = 5, .max_node_visits = 500});
  const Vec3 c(4, 4, 5.5);
  e.erode(h, c, 1.5, 1.0, 1e-3);
  (void)e.finish(h);
  const double after_first = h.material_volume();
  for (int i = 0; i < 1000; ++i) {
    e.enqueue(c, 1.5, 1.0, 1e-3);
    // What a scripted hold gives between two equal keyframes: (1 − a) c + a c.
    const double a = 0.001 * i;
    e.enqueue((1.0 - a) * c + a * c, 1.5, 1.0, 1e-3);
    ASSERT_FALSE(e.has_pending()) << i;
  }
  EXPECT_EQ(h.material_volume(), after_first);
  // A position that moved is new work.
  e.enqueue(c + Vec3(0, 0, -0.2), 1.5, 1.0, 1e-3);
  EXPECT_TRUE(e.has_pending());
  EXPECT_GT(e.finish(h).removed_volume_mm3, 0.0);
  // After a pass cut short by the volume budget the same position is queued again.
  TetHierarchy g(make_block({8, 8, 6}, 2.0));
  Eroder limited({.removal_rate_mm3_per_s = 10.0, .max_depth = 4});
  const double full = g.material_volume();
  for (int i = 0; i < 200; ++i) limited.erode(g, c, 1.5, 1.0, 1e-2);
  (void)limited.finish(g);
  // 2 s at 10 mm³/s: everything the burr covers (< 8 mm³ here) goes in the end.
  TetHierarchy ref(make_block({8, 8, 6}, 2.0));
  Eroder unlimited({.removal_rate_mm3_per_s = 0.0, .max_depth = 4});
  unlimited.erode(ref, c, 1.5, 1.0, 0.0);
  (void)unlimited.finish(ref);
  EXPECT_TRUE(test::rel_near(full - g.material_volume(), full - ref.material_volume(), 1e-9));
}

TEST(Erosion, NodeLimitBoundsTheTree) {
  // A fine level on a long path would refine without bound: max_nodes keeps the tree within it.
  for (const std::size_t limit : {std::size_t(0), std::size_t(3000)}) {
    TetHierarchy h(make_block({12, 8, 6}, 2.0));
    Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = 7, .max_node_visits = 0, .max_nodes = limit});
    bool reached = false;
    for (int i = 0; i <= 40; ++i) reached = e.erode(h, Vec3(2 + 0.2 * i, 4, 6), 1.2, 1.0, 1e-3).node_limit_reached || reached;
    if (limit == 0) {
      EXPECT_GT(h.node_count(), 3000U);  // the limit below does bind
      EXPECT_FALSE(reached);
    } else {
      EXPECT_LE(h.node_count(), limit);
      EXPECT_TRUE(reached);
    }
  }
}
TEST(Erosion, OptionsOutsideTheirRangeAreRefused) {
  for (const int depth : {-1, kMaxDepth + 1}) {
    try {
      Eroder e({.max_depth = depth});
      FAIL() << depth << " accepted";
    } catch (const InvalidInput& err) {
      EXPECT_NE(std::string(err.what()).find("max depth"), std::string::npos) << err.what();
      EXPECT_NE(std::string(err.what()).find(std::to_string(kMaxDepth)), std::string::npos) << err.what();
    }
  }
  EXPECT_NO_THROW(Eroder({.max_depth = 0}));
  EXPECT_NO_THROW(Eroder({.max_depth = kMaxDepth}));
  EXPECT_THROW(Eroder({.min_size_mm = -0.1}), InvalidInput);
  EXPECT_THROW(Eroder({.min_size_mm = std::nan("")}), InvalidInput);
}

TEST(Erosion, UnlimitedRemovalTakesWhatTheBurrCoversAndReportsIt) {
  // Everything inside the sphere goes: the removed volume is the ball's part inside the block,
  // approached from below by finer levels (the finest leaves go by their centroid), and the
  // stats add up to the hierarchy's change.
  const Vec3 c(5, 5, 5);
  const double r = 2.0, ball = 4.0 / 3.0 * kPi * r * r * r;
  double last_error = 1e9;
  for (const int depth : {2, 3, 5}) {
    TetHierarchy h(make_block({10, 10, 10}, 2.5));
    const double before = h.material_volume();
    Eroder e({.removal_rate_mm3_per_s = 0.0, .max_depth = depth, .max_node_visits = 0});
    const ErosionStats st = e.erode(h, c, r, 1.0, 0.01);
    EXPECT_FALSE(st.rate_limited);
    EXPECT_FALSE(st.work_pending);
    EXPECT_GT(st.nodes_removed, 0U);
    EXPECT_TRUE(test::rel_near(st.removed_volume_mm3, before - h.material_volume(), 1e-9));
    const double error = std::abs(st.removed_volume_mm3 - ball) / ball;
    EXPECT_LT(error, last_error) << "depth " << depth;
    last_error = error;
    // Every remaining full leaf whose corners all lie in the ball would have gone.
    for (std::size_t root = 0; root < h.root_count(); ++root)
      h.for_each_leaf(root, [&](const NodeRef& n, NodeState s) {
        if (s != NodeState::Full) return;
        bool all_in = true;
        for (const Vec3& x : h.world_vertices(n)) all_in = all_in && (x - c).norm() <= r;
        EXPECT_FALSE(all_in);
      });
    // Changed roots are listed once each.
    auto roots = e.changed_roots();
    std::sort(roots.begin(), roots.end());
    EXPECT_TRUE(std::adjacent_find(roots.begin(), roots.end()) == roots.end());
    EXPECT_FALSE(roots.empty());
    e.clear_changed_roots();
    EXPECT_TRUE(e.changed_roots().empty());
    EXPECT_TRUE(e.changed_nodes().empty());
  }
  EXPECT_LT(last_error, 0.05);
}

}  // namespace
}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "ido/core/math.h"
#include "ido/drill/tet_hierarchy.h"

namespace ido::drill {

namespace detail {
/// Implementation detail of Eroder: the 8 children of a node for one burr sphere, with the
/// per-node tests that need no face plane done for all 8 when the node is entered.
struct ErosionChildren {
  std::array<Vec3, 10> point;            ///< the node's vertices and edge midpoints (mm) the children are made of
  std::array<double, 8> d2{};             ///< squared distance (mm²) from the sphere centre to each centroid
  std::array<bool, 8> beyond{};           ///< the sphere misses the child's vertex bounding sphere
  std::array<std::uint8_t, 8> inside{};   ///< bit k: vertex k lies in the sphere
};
}  // namespace detail

/// How the burr removes material.
struct ErosionOptions {
  /// Pressing force (N) above which the burr cuts.
  double force_threshold_n = 0.2;
  /// Volume removed per second (mm³/s) at relative density 1 while cutting; a node of
  /// volume V in a root of relative density ρ costs V·ρ. ≤ 0: unlimited (everything the
  /// burr covers goes at once).
  double removal_rate_mm3_per_s = 40.0;
  /// Finest level (0 … kMaxDepth) used when min_size_mm is 0.
  int max_depth = 6;
  /// > 0: the finest level of each root is the first whose leaves' longest edge is
  /// ≤ min_size_mm (capped at kMaxDepth); overrides max_depth.
  double min_size_mm = 0.0;
  /// Work budget of one erosion pass (Eroder::erode, Eroder::run): nodes visited (each a
  /// sphere–tetrahedron test, dry-run visits included). When it runs out the pass stops;
  /// the interrupted traversal and the queued burr positions carry over to the next pass,
  /// so one pass costs O(budget) whatever the depth while the removed volume still
  /// converges (Eroder::finish completes the backlog). 0 = unlimited. Default 6000 visits
  /// (≈ 0.2 ms on the reference machine, bench/results/drill.md).
  std::size_t max_node_visits = 6000;
  /// While work is carried over, a newly queued burr position replaces the last queued
  /// (not yet started) one when the position before that is within backlog_spacing ×
  /// radius of it: the backlog keeps positions at most that far apart, the same rule as the
  /// simulator's sub-steps (radius / 4), so the swept volume stays covered. ≤ 0: keep all.
  double backlog_spacing = 0.25;
  /// Most nodes the hierarchy may hold (TetHierarchy::node_count()): a partly covered leaf
  /// whose refinement would pass it stays whole, and ErosionStats::node_limit_reached says
  /// so. Bounds the memory of a fine leaf size on a long path (nodes ≤ 4 bytes each, plus
  /// about 100 bytes per boundary face of the v_lists). 0 = no limit. Default 2^23
  /// (8 388 608 nodes; a depth-8 session on the reference traces uses ≈ 300 000).
  std::size_t max_nodes = std::size_t(1) << 23;
};

/// What one erosion call did.
struct ErosionStats {
  double removed_volume_mm3 = 0.0;
  std::size_t nodes_removed = 0;
  std::size_t nodes_refined = 0;
  bool rate_limited = false;  ///< the volume budget ran out before the burr's region was done
  std::size_t nodes_visited = 0;  ///< sphere tests made (work done)
  bool work_pending = false;      ///< the visit budget ran out: work carried over
  bool node_limit_reached = false;  ///< a leaf was left whole at ErosionOptions::max_nodes
};

/// Removes material covered by a spherical burr (Turini et al. 2007: nodes in contact are
/// eroded when the tool presses hard enough, partly covered nodes are refined down to a
/// minimum size). Per call: nodes entirely inside the sphere go whole; partly covered full
/// leaves are refined until the finest level, where a leaf goes when its centroid is inside
/// the sphere; a partly covered full leaf is refined only when a dry run on its derived
/// geometry finds a descendant that will go (so only the cut's boundary becomes fine, and
/// nothing is refined and then undone). The volume budget grows by removal_rate · dt while the pressing force is at
/// least the threshold (capped at 0.1 s worth) and carries over between calls; when it runs
/// out, the current burr position and the queued ones are dropped.
///
/// Bounded work (as haptic drilling systems bound one collision update): burr positions are
/// queued and processed first in, first out by an explicit depth-first traversal that stops
/// after ErosionOptions::max_node_visits node visits and resumes there on the next pass.
/// Processing order and decisions do not depend on the budget, so when no positions are
/// coalesced (see backlog_spacing) the final tree is the same with or without it.
class Eroder {
 public:
  /// @throws ido::InvalidInput for max_depth outside [0, kMaxDepth] or a negative size.
  explicit Eroder(const ErosionOptions& options = {});

  /// One erosion step with the burr centred at @p centre_mm of radius @p radius_mm:
  /// enqueue() then run() with the options' visit budget.
  ErosionStats erode(TetHierarchy& hierarchy, const Vec3& centre_mm, double radius_mm, double pressing_force_n,
                     double dt_s);
  /// Queues a burr position (mm) when @p pressing_force_n reaches the threshold (and adds
  /// rate · dt to the volume budget); otherwise does nothing. A position that repeats the
  /// last one taken (same radius, centre within kRepeatTolerance × radius) is not queued
  /// again: that sphere, once processed, removed everything it covers, so a burr resting in
  /// contact adds no work (a session's backlog drains while the tool holds still). After a
  /// pass cut short by the volume budget, or after the hierarchy's vertices moved
  /// (TetHierarchy::set_vertex_positions; call forget_last_position()), a repeat is queued.
  void enqueue(const Vec3& centre_mm, double radius_mm, double pressing_force_n, double dt_s);
  /// Relative distance (× radius) under which a new burr position repeats the last one.
  static constexpr double kRepeatTolerance = 1e-9;
  /// Makes the next position be queued even if it repeats the last one (the material under
  /// it may have moved).
  void forget_last_position() noexcept { m_have_last = false; }
  /// Processes queued work until the queue is empty or @p max_node_visits nodes were
  /// visited (0 = unlimited); what is left carries over.
  ErosionStats run(TetHierarchy& hierarchy, std::size_t max_node_visits);
  /// Processes all queued work (run with no budget).
  ErosionStats finish(TetHierarchy& hierarchy) { return run(hierarchy, 0); }
  /// True when queued or interrupted work is waiting.
  [[nodiscard]] bool has_pending() const noexcept { return m_active || m_queue_head < m_queue.size(); }
  /// Burr positions waiting (not counting the one in progress).
  [[nodiscard]] std::size_t queued() const noexcept { return m_queue.size() - m_queue_head; }
  /// Burr positions not finished: waiting, plus the one in progress.
  [[nodiscard]] std::size_t unfinished() const noexcept { return queued() + (m_active ? 1U : 0U); }

  /// Nodes changed (erased — the topmost merged ancestor —, refined, or coarsened back)
  /// since the last clear_changed_roots(), possibly repeated; for
  /// BoundarySurface::update(hierarchy, nodes), which rebuilds only the affected sub-trees.
  [[nodiscard]] const std::vector<NodeRef>& changed_nodes() const noexcept { return m_changed_nodes; }

  /// Roots whose nodes changed since the last clear_changed_roots() (each listed once).
  [[nodiscard]] const std::vector<std::uint32_t>& changed_roots() const noexcept { return m_changed; }
  /// Parallel to changed_roots(): bit f set when a changed node had a face on root face f
  /// (only then can the face neighbour's v_list change; see BoundarySurface::update).
  [[nodiscard]] const std::vector<std::uint8_t>& changed_root_faces() const noexcept { return m_changed_faces; }
  void clear_changed_roots() noexcept;

  /// Finest level used in root @p r.
  [[nodiscard]] int finest_level(const TetHierarchy& hierarchy, std::size_t r) const noexcept;
  [[nodiscard]] const ErosionOptions& options() const noexcept { return m_options; }
  /// Volume budget left (mm³ at density 1).
  [[nodiscard]] double budget() const noexcept { return m_budget; }

 private:
  struct Sphere {
    Vec3 centre = Vec3::Zero();
    double radius = 0.0;
  };
  // One level of the explicit depth-first traversal: a partly covered node being descended.
  struct Frame {
    NodeRef node;
    std::uint32_t word = 0;  // the node's storage word, kept current after every change of the tree
    std::array<std::uint32_t, 8> child{};  // its children's words, decoded once at the push, kept current
    std::array<Vec3, 4> x;
    std::array<std::int8_t, 4> root_face;
    std::int8_t finest = 0;
    std::int8_t next_child = 0;
    bool refined_here = false;
    std::uint8_t face_mask = 0;
  };
  enum class Enter { Done, Pushed, Abort };

  // beyond / d2 / inside: the node's tests without face planes (detail::ErosionChildren).
  Enter enter(TetHierarchy& h, const NodeRef& node, std::uint32_t word, const std::array<Vec3, 4>& x, bool beyond,
              double d2, std::uint8_t inside, int finest, const std::array<std::int8_t, 4>& root_face,
              ErosionStats& stats);
  void leave(TetHierarchy& h, const Frame& f, ErosionStats& stats);
  void take_path_words(const NodeRef& changed) noexcept;
  void mark(const NodeRef& node, std::uint8_t faces);
  void start_sphere(const TetHierarchy& h, const Sphere& s);
  void drop_all(TetHierarchy& h, ErosionStats& stats);
  bool pay(double cost) noexcept;

  ErosionOptions m_options;
  Vec3 m_centre = Vec3::Zero();
  double m_radius = 0.0;
  std::vector<Sphere> m_queue;
  std::size_t m_queue_head = 0;
  bool m_active = false;  // a sphere is in progress (m_centre, m_radius)
  Sphere m_last;            // the last position taken (queued, in progress or done)
  bool m_have_last = false;  // m_last is valid and was not dropped by the volume budget
  std::size_t m_next_candidate = 0;
  std::vector<Frame> m_stack;
  std::size_t m_visits = 0;
  std::vector<NodeRef> m_changed_nodes;
  double m_budget = 0.0;
  bool m_unlimited = false;
  std::vector<std::uint32_t> m_changed;
  std::vector<std::uint32_t> m_stamp;
  std::uint32_t m_epoch = 0;
  std::vector<std::uint32_t> m_candidates;
  std::vector<std::uint8_t> m_is_changed;
  std::vector<std::uint8_t> m_changed_faces;
  std::vector<std::uint32_t> m_slot;  // root → index in m_changed
  std::array<std::uint8_t, kMaxDepth + 1> m_face_mask{};  // root faces touched per level of the current path
  std::array<detail::ErosionChildren, kMaxDepth + 1> m_children;  // children of the frame at each depth
  // Storage words of the current path: the frame at each depth, and the node being entered
  // below the top frame (what TetHierarchy::*_on_path read and update).
  TetHierarchy::PathWords m_frame_word{};
};

}  // namespace ido::drill

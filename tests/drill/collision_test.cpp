// SPDX-License-Identifier: Apache-2.0
// Collision of the tool's samples with the material through the spatial hash of the roots
// (Teschner et al. 2003, the paper's collision detection): every location equals a brute-force
// search over all leaves, on random points, on hash-cell and mesh-face boundaries, for cells
// at negative coordinates and for cells smaller and larger than the tetrahedra; the contact
// counts equal brute force, a flat face gives its normal and depth, and empty, far and
// enclosing queries find nothing.
#include "ido/drill/collision.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "ido/drill/erosion.h"
#include "ido/drill/force.h"
#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/drill/tool.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

// Brute-force point location, independent of the hash and of the TreeTable descent: each
// root's and each leaf's own barycentric map; the roots tried one by one, then every leaf of
// the roots that hold the point. Margins are barycentric (tolerance 1e-9).
class BruteForce {
 public:
  explicit BruteForce(const TetHierarchy& h) {
    for (std::size_t r = 0; r < h.root_count(); ++r) {
      Root root;
      std::array<Vec3, 4> x;
      for (std::size_t k = 0; k < 4; ++k) x[k] = h.vertices()[std::size_t(h.root_tet(r)[k])];
      root.map = map_of(x);
      h.for_each_leaf(r, [&](const NodeRef& n, NodeState s) { root.leaves.push_back({n, s, map_of(h.world_vertices(n))}); });
      m_roots.push_back(std::move(root));
    }
  }
  struct Answer {
    bool inside = false;     // strictly inside a leaf
    bool ambiguous = false;  // within the tolerance of a root's or a leaf's face
    NodeRef leaf;
    NodeState state = NodeState::Erased;
    std::uint32_t root = 0;
  };
  [[nodiscard]] Answer locate(const Vec3& p) const {
    Answer a;
    double best_root = -1e300, best = -1e300;
    for (std::size_t r = 0; r < m_roots.size(); ++r) {
      const double mr = m_roots[r].map.margin(p);
      best_root = std::max(best_root, mr);
      if (mr < -1e-9) continue;
      for (const Leaf& l : m_roots[r].leaves) {
        const double margin = l.map.margin(p);
        if (margin > best) {
          best = margin;
          a.leaf = l.node;
          a.state = l.state;
          a.root = std::uint32_t(r);
        }
      }
    }
    if (best_root < -1e-9) return a;  // outside every root
    a.inside = best > 1e-9;
    a.ambiguous = !a.inside;
    return a;
  }

 private:
  struct Map {
    Mat3 inverse;
    Vec3 x0;
    [[nodiscard]] double margin(const Vec3& p) const {
      const Vec3 m = inverse * (p - x0);
      return std::min({1.0 - m.sum(), m.x(), m.y(), m.z()});
    }
  };
  static Map map_of(const std::array<Vec3, 4>& x) {
    Mat3 e;
    for (int k = 0; k < 3; ++k) e.col(k) = x[std::size_t(k + 1)] - x[0];
    return {e.inverse(), x[0]};
  }
  struct Leaf {
    NodeRef node;
    NodeState state;
    Map map;
  };
  struct Root {
    Map map;
    std::vector<Leaf> leaves;
  };
  std::vector<Root> m_roots;
};

// A 12 × 10 × 8 mm block of 2 mm cells moved by @p shift, drilled along a few burr positions.
geometry::TetMesh shifted_block(const Vec3& shift) {
  geometry::TetMesh m = make_block({12, 10, 8}, 2.0);
  for (Vec3& v : m.vertices) v += shift;
  return m;
}
void drill_some(TetHierarchy& h, const Vec3& shift) {
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 3, .max_node_visits = 0});
  for (int k = 0; k < 6; ++k) (void)eroder.erode(h, shift + Vec3(2.5 + 1.5 * k, 5.0, 8.0), 1.6, 1.0, 0.01);
  (void)eroder.erode(h, shift + Vec3(6.0, 5.0, 4.0), 1.2, 1.0, 0.01);  // a buried cavity
}

TEST(Collision, HashedLocationEqualsBruteForceOnRandomPoints) {
  // Hash cells at the default (mean edge), smaller than a leaf, aligned with the 2 mm cells,
  // and larger than the whole block; the block at positive and at negative coordinates.
  std::mt19937 rng(23);
  for (const Vec3& shift : {Vec3(0, 0, 0), Vec3(-17.3, -4.1, -30.7)})
    for (const double cell : {0.0, 0.3, 2.0, 25.0}) {
      TetHierarchy h(shifted_block(shift), {.hash_cell_mm = cell});
      drill_some(h, shift);
      const BruteForce brute(h);
      std::uniform_real_distribution<double> ux(-1.0, 13.0), uy(-1.0, 11.0), uz(-1.0, 9.0);
      int inside = 0, outside = 0, erased = 0;
      for (int i = 0; i < 2000; ++i) {
        const Vec3 p = shift + Vec3(ux(rng), uy(rng), uz(rng));
        const auto want = brute.locate(p);
        if (want.ambiguous) continue;
        const Location got = h.locate(p);
        ASSERT_EQ(got.inside_mesh, want.inside) << "cell " << cell << " point " << p.transpose();
        if (!want.inside) {
          ++outside;
          continue;
        }
        ++inside;
        erased += want.state == NodeState::Erased ? 1 : 0;
        ASSERT_EQ(got.state, want.state) << p.transpose();
        ASSERT_TRUE(got.leaf == want.leaf) << p.transpose();
        // The hash's candidates for the point hold its root (no false negative).
        const auto cands = h.root_hash().candidates(p);
        EXPECT_NE(std::find(cands.begin(), cands.end(), std::int32_t(want.root)), cands.end());
      }
      EXPECT_GT(inside, 1000);
      EXPECT_GT(outside, 100);
      EXPECT_GT(erased, 10) << "the drilled region is sampled";
    }
}

TEST(Collision, PointsOnHashCellAndMeshFaceBoundariesAreFound) {
  // Hash cells of 2 mm aligned with the block's 2 mm cells: the lattice points, edge and face
  // points lie on cell boundaries and on root faces at once. Every interior one is in the
  // intact material; with cells of 0.7 mm (boundaries not representable exactly) too.
  for (const double cell : {2.0, 1.0, 0.7}) {
    const TetHierarchy h(make_block({12, 10, 8}, 2.0), {.hash_cell_mm = cell});
    int checked = 0;
    for (int i = 1; i < 24; ++i)
      for (int j = 1; j < 20; ++j)
        for (int k = 1; k < 16; ++k) {
          const Vec3 p(0.5 * i, 0.5 * j, 0.5 * k);
          const Location loc = h.locate(p);
          ASSERT_TRUE(loc.inside_mesh) << cell << ": " << p.transpose();
          ASSERT_EQ(loc.state, NodeState::Full) << p.transpose();
          ++checked;
        }
    // Multiples of the cell size itself (as the hash computes its boundaries).
    for (int n = 1; n * cell < 8.0; ++n) {
      const Vec3 p(n * cell, std::min(n * cell, 9.5), std::min(n * cell, 7.5));
      ASSERT_TRUE(h.locate(p).inside_mesh) << p.transpose();
    }
    EXPECT_EQ(checked, 23 * 19 * 15);
  }
  // Just outside the block's faces, by a hair: outside.
  const TetHierarchy h(make_block({12, 10, 8}, 2.0), {.hash_cell_mm = 2.0});
  for (const Vec3& p : {Vec3(-1e-9, 5, 4), Vec3(12 + 1e-9, 5, 4), Vec3(6, -1e-9, 4), Vec3(6, 10 + 1e-9, 4),
                        Vec3(6, 5, -1e-9), Vec3(6, 5, 8 + 1e-9)})
    EXPECT_FALSE(h.locate(p).inside_mesh) << p.transpose();
}

TEST(Collision, ContactCountsAndDirectionEqualBruteForce) {
  TetHierarchy h(make_block({12, 10, 8}, 2.0));
  drill_some(h, Vec3::Zero());
  const BruteForce brute(h);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int touching = 0, with_shaft = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const bool shaft = trial % 2 == 1;
    const Tool tool({.burr_radius_mm = 1.5, .shaft_radius_mm = shaft ? 0.6 : 0.0, .shaft_length_mm = 6.0, .sample_count = 300});
    ToolPose pose;
    pose.position_mm = Vec3(12 * u(rng), 10 * u(rng), 4.0 + 5.0 * u(rng));
    pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(6.0 * u(rng), Vec3(u(rng), u(rng), 1.0).normalized()));
    const ContactModel m = collide(h, tool, pose);
    const Mat3 rot = pose.orientation.normalized().toRotationMatrix();
    int burr = 0, ambiguous = 0;
    Vec3 dir = Vec3::Zero();
    for (const Vec3& s : tool.burr_samples()) {
      const auto b = brute.locate(pose.position_mm + rot * s);
      ambiguous += b.ambiguous ? 1 : 0;
      if (b.inside && b.state == NodeState::Full) {
        ++burr;
        dir -= rot * s;
      }
    }
    int shaft_in = 0, best_ring = 0;
    const int ring = tool.shaft_ring_size();
    for (std::size_t start = 0; ring > 0 && start < tool.shaft_samples().size(); start += std::size_t(ring)) {
      int in_ring = 0;
      for (std::size_t k = start; k < start + std::size_t(ring); ++k) {
        const Vec3& s = tool.shaft_samples()[k];
        const auto b = brute.locate(pose.position_mm + rot * s);
        ambiguous += b.ambiguous ? 1 : 0;
        if (b.inside && b.state == NodeState::Full) {
          ++in_ring;
          dir -= rot * Vec3(s.x(), s.y(), 0.0) * (1.5 / 0.6);
        }
      }
      best_ring = std::max(best_ring, in_ring);
      shaft_in += in_ring;
    }
    if (ambiguous > 0) continue;  // a sample on a leaf face: either answer is right
    ASSERT_EQ(m.burr_samples_inside, burr) << "trial " << trial;
    ASSERT_EQ(m.shaft_samples_inside, shaft_in) << "trial " << trial;
    EXPECT_EQ(m.in_contact, burr + shaft_in > 0);
    EXPECT_EQ(m.position_mm, pose.position_mm);
    if (!m.in_contact) continue;
    ++touching;
    with_shaft += shaft_in > 0 ? 1 : 0;
    // depth = 2 r f for the burr, 2 r_s f for the most covered shaft ring, the larger.
    double depth = 2.0 * 1.5 * burr / 300.0;
    if (ring > 0) depth = std::max(depth, 2.0 * 0.6 * best_ring / ring);
    EXPECT_TRUE(test::near(m.depth_mm, depth, 1e-12)) << "trial " << trial;
    EXPECT_TRUE(test::near(m.normal.norm(), 1.0, 1e-12));
    if (dir.norm() > 1.5) {  // at least one sample's worth of direction
      EXPECT_TRUE(m.normal.isApprox(dir.normalized(), 1e-9)) << "trial " << trial;
    }
  }
  EXPECT_GT(touching, 8);
  EXPECT_GT(with_shaft, 2);
}

TEST(Collision, EachFaceOfABlockPushesTheBurrOutAlongItsNormal) {
  TetHierarchy h(make_block({20, 20, 10}, 2.5));
  const Tool tool({.burr_radius_mm = 2.0});
  const Vec3 centre(10, 10, 5);
  // Outward normals of the four side faces and the top, with the face's position.
  const std::array<std::pair<Vec3, double>, 5> faces{{{Vec3(1, 0, 0), 20.0}, {Vec3(-1, 0, 0), 0.0}, {Vec3(0, 1, 0), 20.0},
                                                      {Vec3(0, -1, 0), 0.0}, {Vec3(0, 0, 1), 10.0}}};
  for (const auto& [n, at] : faces)
    for (const double depth : {0.2, 0.6, 1.0}) {
      ToolPose pose;
      // The burr centre r − depth outside the face, beside the face's centre.
      pose.position_mm = centre - n * n.dot(centre) + n * (at + 2.0 - depth) + Vec3(0.3, -0.2, 0.1).cwiseProduct(Vec3::Ones() - n.cwiseAbs());
      pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
      const ContactModel m = collide(h, tool, pose);
      ASSERT_TRUE(m.in_contact) << n.transpose();
      EXPECT_GT(m.normal.dot(n), std::cos(3.0 * kPi / 180.0)) << n.transpose() << " depth " << depth;
      EXPECT_TRUE(test::near(m.depth_mm, depth, 0.04)) << n.transpose() << " depth " << depth;
      EXPECT_EQ(m.shaft_samples_inside, 0);
    }
}

TEST(Collision, EmptyFarAndEnclosingQueriesFindNothing) {
  TetHierarchy h(make_block({12, 10, 8}, 2.0));
  const Tool tool({.burr_radius_mm = 1.0, .sample_count = 200});
  auto at = [&](const Vec3& p, const Tool& t) {
    ToolPose pose;
    pose.position_mm = p;
    return collide(h, t, pose);
  };
  // Far from the mesh, and just clear of a face.
  for (const Vec3& p : {Vec3(1e6, -1e6, 3e5), Vec3(-50, 5, 4), Vec3(6, 5, 8 + 1.0 + 1e-6)}) {
    const ContactModel m = at(p, tool);
    EXPECT_FALSE(m.in_contact) << p.transpose();
    EXPECT_EQ(m.burr_samples_inside + m.shaft_samples_inside, 0);
    EXPECT_EQ(m.depth_mm, 0.0);
    EXPECT_EQ(m.normal, Vec3::Zero());
  }
  // A burr enclosing the whole block: its surface samples are all outside the material.
  const Tool huge({.burr_radius_mm = 40.0, .sample_count = 2000});
  EXPECT_FALSE(at(Vec3(6, 5, 4), huge).in_contact);
  // A huge burr whose surface sweeps through the block: as many samples as the area inside.
  const ContactModel sweep = at(Vec3(6, 5, -36), huge);  // its top at z = 4, mid-block
  EXPECT_TRUE(sweep.in_contact);
  EXPECT_GT(sweep.burr_samples_inside, 0);
  EXPECT_LT(sweep.normal.z(), -0.9) << "from the material above toward the burr's centre below";
  // Inside a cavity drilled larger than the burr: nothing to touch.
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 5, .max_node_visits = 0});
  (void)eroder.erode(h, Vec3(6, 5, 4), 2.5, 1.0, 0.01);
  EXPECT_FALSE(at(Vec3(6, 5, 4), tool).in_contact);
  EXPECT_TRUE(at(Vec3(6, 5, 4 + 1.8), tool).in_contact) << "moved up against the cavity's wall";
}

TEST(Collision, FullyBuriedBurrPushesBackAlongTheShaft) {
  // Every sample inside: the inward normals of a whole Fibonacci sphere sum to almost nothing
  // (up to 0.21 r for 20 samples, 0.013 r for 1000), which is no direction: the documented
  // fallback is the shaft axis, for every sample count and orientation.
  const TetHierarchy h(make_block({12, 10, 8}, 2.0));
  for (const int samples : {20, 100, 1000})
    for (const double angle : {0.0, 0.9, 2.5}) {
      const Tool tool({.burr_radius_mm = 1.0, .sample_count = samples});
      ToolPose pose;
      pose.position_mm = Vec3(6, 5, 4);
      pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(angle, Vec3(1, -2, 0.5).normalized()));
      const ContactModel m = collide(h, tool, pose);
      ASSERT_TRUE(m.in_contact);
      EXPECT_EQ(m.burr_samples_inside, samples);
      EXPECT_TRUE(test::near(m.depth_mm, 2.0, 1e-12)) << "depth 2 r f with f = 1";
      const Vec3 axis = pose.orientation.normalized().toRotationMatrix() * Vec3::UnitZ();
      EXPECT_TRUE(m.normal.isApprox(axis, 1e-12)) << samples << " samples, angle " << angle << ": " << m.normal.transpose();
    }
}

TEST(Collision, FlatFaceForceIsNormalAndMonotoneInDepth) {
  // Top face of a block at z = 10; the burr approaches from above.
  TetHierarchy h(make_block({20, 20, 10}, 2.5));
  const Tool tool({.burr_radius_mm = 2.0});
  double last = 0.0;
  for (int i = 1; i <= 40; ++i) {
    const double depth = 0.025 * i;  // up to half the radius
    ToolPose pose;
    pose.position_mm = Vec3(10.3, 9.7, 10.0 + 2.0 - depth);
    const ContactModel m = collide(h, tool, pose);
    ASSERT_TRUE(m.in_contact);
    VirtualCoupling coupling;
    Vec3 f = Vec3::Zero();
    for (int k = 0; k < 200; ++k) f = coupling.update(m, pose.position_mm, 1e-3);  // settle
    const double angle = std::acos(std::clamp(f.normalized().dot(Vec3::UnitZ()), -1.0, 1.0)) * 180.0 / kPi;
    if (depth >= 0.1) {
      EXPECT_LT(angle, 5.0) << "depth " << depth;
    }
    EXPECT_GE(f.norm(), last - 1e-12) << "depth " << depth;
    EXPECT_TRUE(test::near(m.depth_mm, depth, 0.02)) << "depth " << depth;
    last = f.norm();
  }
  EXPECT_GT(last, 0.5);
}

TEST(Collision, HintedLocationsGiveTheContactOfPlainLocation) {
  // collide() locates each sample starting from the roots of nearby earlier samples; the
  // contact must be the one found with a plain hash look-up per sample.
  TetHierarchy h(make_block({12, 10, 8}, 2.0));
  Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 0});
  for (int k = 0; k < 8; ++k) (void)eroder.erode(h, Vec3(3.0 + k, 5.0, 8.0), 1.5, 1.0, 0.01);
  const Tool tool({.burr_radius_mm = 1.8, .sample_count = 1000});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int touching = 0;
  for (int trial = 0; trial < 60; ++trial) {
    ToolPose pose;
    pose.position_mm = Vec3(12 * u(rng), 10 * u(rng), 5.0 + 4.0 * u(rng));
    pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(6.0 * u(rng), Vec3(u(rng), u(rng), 1.0).normalized()));
    const ContactModel m = collide(h, tool, pose);
    const Mat3 rot = pose.orientation.normalized().toRotationMatrix();
    int inside = 0;
    Vec3 dir = Vec3::Zero();
    for (const Vec3& s : tool.burr_samples()) {
      const Location loc = h.locate(pose.position_mm + rot * s);
      if (loc.inside_mesh && loc.state == NodeState::Full) {
        ++inside;
        dir -= rot * s;
      }
    }
    ASSERT_EQ(m.burr_samples_inside, inside) << "trial " << trial;
    if (inside > 0 && dir.norm() > tool.burr_radius()) {  // a direction (not a buried burr's residue)
      EXPECT_TRUE(m.normal.isApprox(dir.normalized(), 1e-12)) << "trial " << trial;
      ++touching;
    }
  }
  EXPECT_GT(touching, 10);
}
}  // namespace
}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
// Force: the extrapolated depth of a contact model, and the virtual coupling (first-order
// filter of the proxy offset, spring, clamp) that turns it into a force without steps.
#include "ido/drill/force.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "ido/drill/shapes.h"
#include "ido/drill/tet_hierarchy.h"
#include "ido/drill/tool.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

TEST(Force, SlidingAlongAFlatFaceHasNoSteps) {
  TetHierarchy h(make_block({40, 20, 10}, 2.5));
  const Tool tool({.burr_radius_mm = 2.0});
  VirtualCoupling coupling;
  ContactModel model;
  double peak = 0.0, max_step = 0.0;
  Vec3 prev = Vec3::Zero();
  // 1 kHz haptic ticks, a new contact model every 3 ticks; the burr comes down onto the top
  // face (z = 10) over 200 ms to 0.4 mm depth while sliding along x at 20 mm/s.
  for (int tick = 0; tick < 1500; ++tick) {
    const double x = 5.0 + 0.02 * tick;
    const double depth = tick < 200 ? -0.5 + 0.9 * tick / 200.0 : 0.4;
    const Vec3 device(x, 10.0, 12.0 - depth);
    if (tick % 3 == 0) {
      ToolPose pose;
      pose.position_mm = device;
      model = collide(h, tool, pose);
    }
    const Vec3 f = coupling.update(model, device, 1e-3);
    if (tick > 0) max_step = std::max(max_step, (f - prev).norm());
    peak = std::max(peak, f.norm());
    prev = f;
  }
  EXPECT_GT(peak, 0.5);
  EXPECT_LT(max_step, 0.02 * peak);
}
ContactModel half_space(const Vec3& normal, double depth_mm, const Vec3& position_mm) {
  ContactModel m;
  m.in_contact = true;
  m.normal = normal.normalized();
  m.depth_mm = depth_mm;
  m.position_mm = position_mm;
  return m;
}

TEST(Force, ExtrapolatedDepthIsTheHalfSpacesPenetrationNearTheQuery) {
  const ContactModel m = half_space(Vec3(0, 0, 1), 0.5, Vec3(1, 2, 3));
  EXPECT_TRUE(test::near(extrapolated_depth(m, Vec3(1, 2, 3)), 0.5, 1e-15));
  EXPECT_TRUE(test::near(extrapolated_depth(m, Vec3(1, 2, 2.8)), 0.7, 1e-15));   // pushed deeper
  EXPECT_TRUE(test::near(extrapolated_depth(m, Vec3(4, -1, 3.1)), 0.4, 1e-15));  // sliding along: only the normal part counts
  EXPECT_EQ(extrapolated_depth(m, Vec3(1, 2, 3.6)), 0.0);                       // out of the half-space
  // Beyond the validity radius the model says nothing; within it, it holds.
  EXPECT_EQ(extrapolated_depth(m, Vec3(1, 2, 2.0), 0.9), 0.0);
  EXPECT_TRUE(test::near(extrapolated_depth(m, Vec3(1, 2, 2.2), 0.9), 1.3, 1e-15));
  ContactModel free = m;
  free.in_contact = false;
  EXPECT_EQ(extrapolated_depth(free, Vec3(1, 2, 2)), 0.0);
}

TEST(Force, CouplingFiltersTheOffsetWithItsTimeConstantAndClamps) {
  const CouplingOptions o{.stiffness_n_per_mm = 2.0, .time_constant_s = 0.01, .max_force_n = 10.0, .model_validity_mm = 5.0};
  VirtualCoupling c(o);
  const ContactModel m = half_space(Vec3(1, 0, 0), 0.5, Vec3::Zero());
  // Held still: offset(t) = 0.5 (1 − e^(−t/τ)) whatever the tick length, force = k · offset.
  double t = 0.0;
  for (int i = 0; i < 30; ++i) {
    const double dt = i % 2 == 0 ? 1e-3 : 2.5e-3;
    const Vec3 f = c.update(m, Vec3::Zero(), dt);
    t += dt;
    const double want = 0.5 * (1.0 - std::exp(-t / 0.01));
    ASSERT_TRUE(test::near(c.offset().x(), want, 1e-12)) << i;
    ASSERT_TRUE(test::near(f.x(), 2.0 * want, 1e-12)) << i;
    EXPECT_EQ(f, c.force());
    EXPECT_EQ(f.y(), 0.0);
  }
  // Deep penetration: the force is clamped, along the normal.
  const Vec3 big = c.update(half_space(Vec3(1, 1, 0), 6.0, Vec3::Zero()), Vec3::Zero(), 1.0);  // k · 6 = 12 N
  EXPECT_TRUE(test::near(big.norm(), 10.0, 1e-12));
  EXPECT_TRUE(big.normalized().isApprox(Vec3(1, 1, 0).normalized(), 1e-12));
  // Leaving contact lets the offset decay; reset zeroes it at once.
  const Vec3 decaying = c.update(ContactModel{}, Vec3::Zero(), 0.01);
  EXPECT_TRUE(test::near(decaying.norm(), 2.0 * (6.0 * std::exp(-1.0)), 1e-9));
  c.reset();
  EXPECT_EQ(c.offset(), Vec3::Zero());
  EXPECT_EQ(c.force(), Vec3::Zero());
  // No time constant: the offset follows the model at once.
  VirtualCoupling stiff({.stiffness_n_per_mm = 3.0, .time_constant_s = 0.0});
  EXPECT_TRUE(stiff.update(m, Vec3::Zero(), 1e-3).isApprox(Vec3(1.5, 0, 0), 1e-15));
  EXPECT_EQ(stiff.options().stiffness_n_per_mm, 3.0);
  // A non-positive tick moves nothing.
  VirtualCoupling frozen(o);
  EXPECT_EQ(frozen.update(m, Vec3::Zero(), 0.0), Vec3::Zero());
  EXPECT_EQ(frozen.update(m, Vec3::Zero(), -1.0), Vec3::Zero());
}

}  // namespace
}  // namespace ido::drill

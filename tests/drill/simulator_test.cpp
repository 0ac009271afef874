// SPDX-License-Identifier: Apache-2.0
// The threaded drilling session (label: threads): a scripted session drills and hands the
// render thread the same lists however the surface is rebuilt, its live figures agree with the
// final ones, a plunge-and-hold ends with the path having removed the swept volume, and the
// haptic thread's timing and scheduling options are checked and honoured.
#include "ido/drill/simulator.h"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/erosion.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/shapes.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

ScriptedTrajectory plunge(double duration_s) {
  // Down onto the top face of a 12 mm block, 1.5 mm into it, then sideways.
  std::vector<double> t{0.0, 0.3 * duration_s, 0.7 * duration_s, duration_s};
  std::vector<ToolPose> p(4);
  p[0].position_mm = Vec3(6, 6, 15);
  p[1].position_mm = Vec3(6, 6, 12 + 2 - 1.5);
  p[2].position_mm = Vec3(8, 6.5, 12 + 2 - 1.5);
  p[3].position_mm = Vec3(8, 6.5, 15);
  return ScriptedTrajectory(t, p);
}

TEST(Simulator, TimingPercentilesFollowIdosOnePercentile) {
  std::vector<double> v;
  for (int i = 100; i >= 1; --i) v.push_back(double(i));
  const Percentiles p = percentiles(v);
  EXPECT_EQ(p.count, 100u);
  EXPECT_DOUBLE_EQ(p.p50, 50.5);   // numpy.percentile(range(1, 101), 50)
  EXPECT_DOUBLE_EQ(p.p99, 99.01);  // ... 99
  EXPECT_DOUBLE_EQ(p.p999, 99.901);
  EXPECT_DOUBLE_EQ(p.max, 100.0);
  const Percentiles none = percentiles({});
  EXPECT_EQ(none.count, 0u);
  EXPECT_EQ(none.max, 0.0);
}

// Taken (take_render_v_lists, as ido drill does) rather than viewed, the render copy is the
// same lists, and afterwards the session holds none of its faces (they are not copied).
TEST(Simulator, ScriptedSessionDrillsAndRenderCopyMatches) {
  for (const auto& [threads, take] : {std::pair{1, false}, std::pair{2, false}, std::pair{1, true}, std::pair{2, true}}) {
    TetHierarchy h(make_block({12, 12, 12}, 3.0));
    auto device = plunge(0.4);
    SCOPED_TRACE(threads);
    SCOPED_TRACE(take ? "taken" : "viewed");
    SimulatorOptions o;
    o.surface.threads = threads;  // serial, and two v_list workers on the collision thread
    o.tool.burr_radius_mm = 2.0;
    o.erosion = {.force_threshold_n = 0.05, .removal_rate_mm3_per_s = 0.0, .max_depth = 4};
    const double before = h.material_volume();
    Simulator sim(h, device, o);
    sim.run(10.0);
    const auto& st = sim.stats();
    EXPECT_GT(st.haptic_ticks, 50U);  // no timing assertion: the machine may be loaded
    EXPECT_GT(st.collision_updates, 10U);
    EXPECT_GT(st.removed_volume_mm3, 1.0);
    EXPECT_TRUE(test::rel_near(before - h.material_volume(), st.removed_volume_mm3, 1e-9));
    EXPECT_GT(st.peak_force_n, 0.0);
    ASSERT_FALSE(device.forces().empty());
    const auto fresh = BoundarySurface(h, {.chunk_level = o.surface.chunk_level, .threads = 1}).v_lists();
    if (take) {
      const std::size_t faces = sim.surface().face_count();
      ASSERT_GT(faces, 0U);
      const std::size_t held = sim.memory_use().v_lists;
      const auto taken = sim.take_render_v_lists();
      ASSERT_EQ(taken.size(), fresh.size());
      for (std::size_t r = 0; r < fresh.size(); ++r) ASSERT_EQ(taken[r], fresh[r]) << "root " << r;
      EXPECT_LE(sim.memory_use().v_lists + faces * sizeof(SurfaceFace), held);  // every face left the session
      EXPECT_EQ(sim.surface().face_count(), 0U);
      EXPECT_TRUE(sim.render_v_lists().empty());
      continue;
    }
    // The render consumer's copy equals the authoritative v_lists.
    const auto& mine = sim.render_v_lists();
    const auto& truth = sim.surface().v_lists();
    ASSERT_EQ(mine.size(), truth.size());
    for (std::size_t r = 0; r < truth.size(); ++r) ASSERT_EQ(mine[r], truth[r]) << "root " << r;
    // ... and the incremental lists equal a serial rebuild of the final tree from scratch.
    for (std::size_t r = 0; r < truth.size(); ++r) ASSERT_EQ(truth[r], fresh[r]) << "root " << r;
    EXPECT_GT(st.render_snapshots, 0U);
    // Nothing outside the swept region went: material left ≥ block − (swept volume bound).
    const double swept = 4.0 / 3.0 * kPi * 8 + kPi * 4 * (2.0 + 2.06 + 3.5);
    EXPECT_LE(st.removed_volume_mm3, swept);
  }
}

// live_stats() is read from another thread while the session runs (TSan checks the
// hand-off) and only grows; once the session has stopped its figures are stats()': counts,
// maximum and removed volume exactly, the percentiles within half a bin (the bins' ratio^½).
TEST(Simulator, LiveUpdatePercentilesAgreeWithTheFinalStats) {
  TetHierarchy h(make_block({12, 12, 12}, 3.0));
  auto device = plunge(0.4);
  SimulatorOptions o;
  o.tool.burr_radius_mm = 2.0;
  o.erosion = {.force_threshold_n = 0.05, .removal_rate_mm3_per_s = 0.0, .max_depth = 4};
  o.haptic_realtime_priority = 0;
  Simulator sim(h, device, o);
  EXPECT_EQ(sim.live_stats().collision_updates, 0U);
  std::atomic<bool> done{false};
  std::thread runner([&] {
    sim.run(10.0);
    done.store(true);
  });
  LiveStats last;
  std::size_t reads = 0;
  while (!done.load()) {
    const LiveStats l = sim.live_stats();
    EXPECT_GE(l.collision_updates, last.collision_updates);
    EXPECT_GE(l.removed_volume_mm3, last.removed_volume_mm3);
    EXPECT_GE(l.update_time_s.max, last.update_time_s.max);
    EXPECT_EQ(l.update_time_s.count, l.collision_updates);
    if (l.collision_updates > 0) {
      EXPECT_LE(l.update_time_s.p50, l.update_time_s.p99);
      EXPECT_LE(l.update_time_s.p99, l.update_time_s.max);
    }
    last = l;
    ++reads;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  runner.join();
  EXPECT_GT(reads, 10U);
  const SessionStats& st = sim.stats();
  const LiveStats live = sim.live_stats();
  ASSERT_GT(st.collision_updates, 10U);
  EXPECT_EQ(live.collision_updates, st.collision_updates);
  EXPECT_EQ(live.update_time_s.count, st.update_time_s.size());
  EXPECT_EQ(live.removed_volume_mm3, st.removed_volume_mm3);
  const Percentiles exact = percentiles(st.update_time_s);
  EXPECT_EQ(live.update_time_s.max, exact.max);
  const double half_bin = std::sqrt(Simulator::kLiveBinRatio) * (1.0 + 1e-12);
  for (const auto& [got, want] : {std::pair{live.update_time_s.p50, exact.p50}, std::pair{live.update_time_s.p99, exact.p99},
                                  std::pair{live.update_time_s.p999, exact.p999}}) {
    EXPECT_LE(got, want * half_bin);
    EXPECT_GE(got, want / half_bin);
  }
  EXPECT_NEAR(std::pow(Simulator::kLiveBinRatio, 24), 10.0, 1e-12);
}

// A plunge that ends with the burr resting in contact, at fine leaves (each burr position
// there costs many collision updates of work): the session ends when the path ends, with the
// backlog finished, and has removed what the path swept — the same volume as the eroder
// fed the path's positions directly, and near the analytic swept volume.
TEST(Simulator, PlungeAndHoldEndsWhenThePathEnds) {
  const double r = 1.5;
  std::vector<double> t{0.0, 0.3, 1.2};
  std::vector<ToolPose> p(3);
  p[0].position_mm = Vec3(6, 6, 10);
  p[1].position_mm = Vec3(6, 6, 7);  // 1 mm below the top face (z = 8)
  p[2].position_mm = p[1].position_mm;
  ScriptedTrajectory device(t, p);
  const ErosionOptions eo{.force_threshold_n = 0.0, .removal_rate_mm3_per_s = 0.0, .min_size_mm = 0.0625};
  TetHierarchy h(make_block({12, 12, 8}, 2.0));
  const double before = h.material_volume();
  SimulatorOptions o;
  o.tool.burr_radius_mm = r;
  o.erosion = eo;
  o.drain_limit_s = 30.0;
  o.haptic_realtime_priority = 0;
  Simulator sim(h, device, o);
  sim.run(/*timeout_s=*/60.0);  // a safety net far above the drain limit
  const auto& st = sim.stats();
  EXPECT_TRUE(st.path_finished);
  EXPECT_FALSE(st.timed_out);
  EXPECT_EQ(st.backlog_left_positions, 0U);
  const double removed = before - h.material_volume();
  // Reference: the same vertical sweep eroded directly, positions r / 8 apart.
  TetHierarchy ref(make_block({12, 12, 8}, 2.0));
  Eroder e(eo);
  for (int i = 0; i <= 24; ++i) e.erode(ref, Vec3(6, 6, 10 - 3.0 * i / 24.0), r, 1.0, 0.0);
  (void)e.finish(ref);
  const double expected = before - ref.material_volume();
  EXPECT_TRUE(test::rel_near(removed, expected, 0.01)) << removed << " vs " << expected;
  // Analytic: a cylinder 1 mm deep and the lower half-ball, 14.14 mm³ (leaves of 0.0625 mm).
  EXPECT_TRUE(test::rel_near(removed, kPi * r * r * 1.0 + 2.0 / 3.0 * kPi * r * r * r, 0.05)) << removed;
}

// A 2 mm burr that cuts at once, leaves down to depth 3: plunge(0.4) into a 12 mm block drills.
SimulatorOptions drilling_plunge_options() {
  SimulatorOptions o;
  o.tool.burr_radius_mm = 2.0;
  o.erosion = {.force_threshold_n = 0.05, .removal_rate_mm3_per_s = 0.0, .max_depth = 3};
  return o;
}

TEST(Simulator, HybridWaitMarginMustBeShorterThanThePeriod) {
  TetHierarchy h(make_block({12, 12, 12}, 3.0));
  auto device = plunge(0.4);
  for (const double spin : {-1e-6, 1e-3, 2e-3}) {
    SimulatorOptions o;
    o.haptic_spin_s = spin;
    EXPECT_THROW((void)Simulator(h, device, o), InvalidInput) << "spin " << spin;
  }
  // Plain sleep (0) and a margin just under the period both run a session that drills.
  for (const double spin : {0.0, 0.9e-3}) {
    TetHierarchy g(make_block({12, 12, 12}, 3.0));
    auto d = plunge(0.4);
    SimulatorOptions o = drilling_plunge_options();
    o.haptic_spin_s = spin;
    Simulator sim(g, d, o);
    sim.run(10.0);
    EXPECT_GT(sim.stats().haptic_ticks, 50U) << "spin " << spin;
    EXPECT_GT(sim.stats().removed_volume_mm3, 1.0) << "spin " << spin;
  }
}

// Whether this process may run a thread under SCHED_FIFO: asked for on a scratch thread.
bool process_may_use_realtime() {
  bool granted = false;
  std::thread probe([&granted] {
    sched_param p{};
    p.sched_priority = 10;
    granted = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
  });
  probe.join();
  return granted;
}

// A scripted device that records the scheduling policy of the thread calling it.
class PolicyRecordingDevice final : public HapticDevice {
 public:
  explicit PolicyRecordingDevice(ScriptedTrajectory path) : m_path(std::move(path)) {}
  ToolPose read_pose(double t_s) noexcept override {
    m_policy.store(sched_getscheduler(0), std::memory_order_relaxed);
    return m_path.read_pose(t_s);
  }
  void write_force(const Vec3& f, double t_s) noexcept override { m_path.write_force(f, t_s); }
  [[nodiscard]] bool finished(double t_s) const noexcept override { return m_path.finished(t_s); }
  [[nodiscard]] int policy() const noexcept { return m_policy.load(std::memory_order_relaxed); }

 private:
  ScriptedTrajectory m_path;
  std::atomic<int> m_policy{-1};
};

TEST(Simulator, RealtimePriorityOutsideZeroTo99IsRejected) {
  TetHierarchy h(make_block({12, 12, 12}, 3.0));
  auto device = plunge(0.4);
  for (const int priority : {-1, 100}) {
    SimulatorOptions o;
    o.haptic_realtime_priority = priority;
    EXPECT_THROW((void)Simulator(h, device, o), InvalidInput) << "haptic " << priority;
    o = {};
    o.collision_realtime_priority = priority;
    EXPECT_THROW((void)Simulator(h, device, o), InvalidInput) << "collision " << priority;
  }
}

TEST(Simulator, HapticThreadRunsUnderTheSchedulingItReports) {
  const bool may = process_may_use_realtime();
  for (const int priority : {0, 80}) {
    TetHierarchy g(make_block({12, 12, 12}, 3.0));
    PolicyRecordingDevice device(plunge(0.4));
    SimulatorOptions o = drilling_plunge_options();
    o.haptic_realtime_priority = priority;
    Simulator sim(g, device, o);
    sim.run(10.0);
    const bool realtime = priority > 0 && may;
    EXPECT_EQ(sim.stats().haptic_realtime, realtime) << "priority " << priority;
    EXPECT_FALSE(sim.stats().collision_realtime);
    // The policy seen from inside the device's read_pose, i.e. on the haptic thread.
    EXPECT_EQ(device.policy(), realtime ? SCHED_FIFO : SCHED_OTHER) << "priority " << priority;
    EXPECT_GT(sim.stats().removed_volume_mm3, 1.0) << "priority " << priority;
  }
}

}  // namespace
}  // namespace ido::drill

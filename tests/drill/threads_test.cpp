// SPDX-License-Identifier: Apache-2.0
// The threaded session, lock-free hand-offs and the UDP bridge (label: threads).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "ido/drill/boundary_surface.h"
#include "ido/drill/erosion.h"
#include "ido/drill/haptic_device.h"
#include "ido/drill/lock_free.h"
#include "ido/drill/shapes.h"
#include "ido/drill/simulator.h"
#include "ido/drill/udp_bridge.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

TEST(LockFree, TripleBufferDeliversConsistentLatestValues) {
  struct Pair { std::uint64_t a = 0, b = 0; };
  TripleBuffer<Pair> buf;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= 200000; ++i) buf.write({i, 2 * i});
    done = true;
  });
  std::uint64_t last = 0;
  bool torn = false, backwards = false;
  while (!done.load()) {
    const Pair p = buf.read();
    torn = torn || p.b != 2 * p.a;
    backwards = backwards || p.a < last;
    last = p.a;
  }
  writer.join();
  EXPECT_FALSE(torn);
  EXPECT_FALSE(backwards);
  EXPECT_EQ(buf.read().a, 200000U);
}

TEST(LockFree, SpscRingKeepsOrderAndLosesNothing) {
  SpscRing<std::uint64_t, 64> ring;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < 20000; ++i) {
      std::uint64_t v = i;
      while (!ring.push(v)) std::this_thread::yield();
    }
  });
  std::uint64_t expect = 0;
  while (expect < 20000) {
    if (auto v = ring.pop()) {
      ASSERT_EQ(*v, expect);
      ++expect;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_FALSE(ring.pop().has_value());
}

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

TEST(BoundarySurface, WorkerThreadsRebuildTheSerialLists) {
  // The same random drilling fed to v_lists rebuilt by the calling thread alone, by 2 and by
  // 4 workers (more than the machine's cores). Unbudgeted, every update rewrites the same
  // chunks with the same faces and visits the same nodes; with a visit budget the workers
  // may leave other chunks for later, but once flushed the lists are the serial ones. Under
  // ThreadSanitizer this is the race check of the parallel rebuild.
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const int level : {2, 3}) {
    TetHierarchy h(make_block({10, 8, 6}, 2.0));
    std::vector<BoundarySurface> exact, budgeted;
    for (const int threads : {1, 2, 4}) {
      exact.emplace_back(h, BoundarySurfaceOptions{.chunk_level = level, .threads = threads});
      budgeted.emplace_back(h, BoundarySurfaceOptions{.chunk_level = level, .threads = threads});
    }
    Eroder eroder({.removal_rate_mm3_per_s = 0.0, .max_depth = 4, .max_node_visits = 600});
    std::size_t updates = 0, multi = 0, left = 0;
    for (int step = 0; step < 8; ++step) {
      eroder.enqueue({1 + 8 * u(rng), 1 + 6 * u(rng), 1 + 4 * u(rng)}, 0.8 + 1.2 * u(rng), 1.0, 0.01);
      while (eroder.has_pending()) {
        (void)eroder.run(h, 600);
        const auto changed = eroder.changed_nodes();
        for (auto& s : exact) s.update(h, changed);
        for (auto& s : budgeted) {
          s.update(h, changed, 400);
          left += s.has_pending() ? 1 : 0;
        }
        eroder.clear_changed_roots();
        ++updates;
        const BoundarySurface& serial = exact[0];
        multi += serial.last_rebuilt_chunks().size() >= 8 ? 1 : 0;
        for (std::size_t t = 1; t < exact.size(); ++t) {
          ASSERT_EQ(exact[t].last_rebuilt(), serial.last_rebuilt()) << "level " << level << " update " << updates;
          ASSERT_TRUE(exact[t].last_rebuilt_chunks() == serial.last_rebuilt_chunks()) << "update " << updates;
          ASSERT_EQ(exact[t].last_visits(), serial.last_visits()) << "update " << updates;
          for (const ChunkId& c : serial.last_rebuilt_chunks())
            ASSERT_TRUE(exact[t].chunk(c.root, c.chunk) == serial.chunk(c.root, c.chunk))
                << "level " << level << " update " << updates << " root " << c.root << " chunk " << c.chunk;
        }
      }
    }
    EXPECT_GT(multi, 10U) << "few updates had chunks to share out: the test does not test the workers";
    EXPECT_GT(left, 10U) << "the budget never ran out";
    for (auto& s : budgeted) {
      s.flush(h);
      ASSERT_FALSE(s.has_pending());
    }
    for (std::size_t r = 0; r < h.root_count(); ++r)
      for (std::size_t t = 0; t < exact.size(); ++t) {
        ASSERT_EQ(exact[t].v_list(r), exact[0].v_list(r)) << "level " << level << " root " << r;
        ASSERT_EQ(budgeted[t].v_list(r), exact[0].v_list(r)) << "level " << level << " root " << r;
      }
    const BoundarySurface fresh(h, {.chunk_level = level, .threads = 2});
    for (std::size_t r = 0; r < h.root_count(); ++r) ASSERT_EQ(fresh.v_list(r), exact[0].v_list(r)) << "root " << r;
  }
  const TetHierarchy small(make_block({4, 4, 4}, 2.0));
  EXPECT_THROW(BoundarySurface(small, {.threads = -1}), InvalidInput);
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

TEST(HapticDevice, CsvTrajectoryParsesAndInterpolates) {
  const auto dir = test::scratch_dir("drill_csv");
  {
    std::ofstream f(dir / "path.csv");
    f << "t,x,y,z\n0,0,0,0\n1,10,0,0\n2,10,10,0\n";
  }
  const auto traj = ScriptedTrajectory::load_csv(dir / "path.csv");
  EXPECT_TRUE(test::near(traj.pose_at(0.5).position_mm.x(), 5.0, 1e-12));
  EXPECT_TRUE(test::near(traj.pose_at(1.25).position_mm.y(), 2.5, 1e-12));
  EXPECT_TRUE(test::near(traj.duration(), 2.0, 0));
  {
    std::ofstream f(dir / "bad.csv");
    f << "0,0,0,0\n1,1,1\n";
  }
  try {
    (void)ScriptedTrajectory::load_csv(dir / "bad.csv");
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(e.location().line, 2);
  }
  {
    std::ofstream f(dir / "back.csv");
    f << "0,0,0,0\n0,1,1,1\n";
  }
  EXPECT_THROW((void)ScriptedTrajectory::load_csv(dir / "back.csv"), IoError);
  EXPECT_THROW((void)ScriptedTrajectory::load_csv(dir / "missing.csv"), IoError);
}

// The first line is a header only when every field is a name; a script is played in real
// time, so a time past kMaxScriptDuration_s is refused at its line (file and constructor).
TEST(HapticDevice, CsvHeaderIsNamesOnlyAndTimesAreBounded) {
  const auto dir = test::scratch_dir("drill_csv_header");
  const auto line_of = [&](const std::string& name, const std::string& text) -> std::int64_t {
    std::ofstream(dir / name) << text;
    try {
      (void)ScriptedTrajectory::load_csv(dir / name);
    } catch (const IoError& e) {
      return e.location().line.value_or(-1);
    }
    return 0;  // accepted
  };
  EXPECT_EQ(line_of("data.csv", "0,10,10,abc\n1,10,10,5\n"), 1);  // data with a bad field
  EXPECT_EQ(line_of("names.csv", "# a path\ntime,x,y,z\n0,1,1,1\n1,2,2,2\n"), 0);
  EXPECT_EQ(line_of("second.csv", "t,x,y,z\nt,x,y,z\n0,1,1,1\n"), 2);  // one header only
  EXPECT_EQ(line_of("long.csv", "t,x,y,z\n0,1,1,1\n3600,1,1,2\n3600.5,1,1,3\n"), 4);
  EXPECT_EQ(line_of("huge.csv", "t,x,y,z\n0,1,1,1\n1e30,1,1,2\n"), 3);
  std::vector<ToolPose> p(2);
  EXPECT_THROW(ScriptedTrajectory({0.0, 1e30}, p), InvalidInput);
  EXPECT_NO_THROW(ScriptedTrajectory({0.0, kMaxScriptDuration_s}, p));
}

TEST(UdpBridge, PacketsRoundTrip) {
  PosePacket p;
  p.sequence = 7;
  p.flags = 1;
  p.t_s = 1.25;
  p.pose.position_mm = Vec3(1, -2, 3.5);
  p.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vec3::UnitX()));
  const auto bytes = encode_pose(p);
  PosePacket q;
  ASSERT_TRUE(decode_pose(bytes.data(), bytes.size(), q));
  EXPECT_EQ(q.sequence, 7U);
  EXPECT_EQ(q.flags, 1U);
  EXPECT_TRUE(q.pose.position_mm.isApprox(p.pose.position_mm));
  EXPECT_TRUE(q.pose.orientation.isApprox(p.pose.orientation));
  EXPECT_FALSE(decode_pose(bytes.data(), bytes.size() - 1, q));
  auto broken = bytes;
  broken[0] = 'X';
  EXPECT_FALSE(decode_pose(broken.data(), broken.size(), q));
}

TEST(UdpBridge, DrivesASessionOverLoopback) {
  TetHierarchy h(make_block({12, 12, 12}, 3.0));
  UdpBridge bridge({.port = 0, .idle_timeout_s = 1.0});
  SimulatorOptions o;
  o.tool.burr_radius_mm = 2.0;
  o.erosion = {.force_threshold_n = 1e9, .removal_rate_mm3_per_s = 0.0, .max_depth = 3};  // touch only
  Simulator sim(h, bridge, o);
  sim.start();
  const int sock = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(sock, 0);
  timeval tv{0, 20000};
  ::setsockopt(sock, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(bridge.port());
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  double max_fz = 0.0;
  int forces = 0;
  for (std::uint32_t i = 0; i < 150; ++i) {
    PosePacket p;
    p.sequence = i;
    p.t_s = i * 0.002;
    const double depth = std::min(1.0, i * 0.01);  // pressing 1 mm into the top face
    p.pose.position_mm = Vec3(6, 6, 12 + 2 - depth);
    p.flags = i == 149 ? 1U : 0U;
    const auto bytes = encode_pose(p);
    ::sendto(sock, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
    std::array<std::uint8_t, 128> buf{};
    const ssize_t n = ::recv(sock, buf.data(), buf.size(), 0);
    ForcePacket f;
    if (n > 0 && decode_force(buf.data(), static_cast<std::size_t>(n), f)) {
      ++forces;
      max_fz = std::max(max_fz, f.force_n.z());
      EXPECT_LE(std::abs(f.force_n.x()), 0.1 * std::max(0.1, f.force_n.norm()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::close(sock);
  sim.stop();
  EXPECT_GT(forces, 50);
  EXPECT_GT(max_fz, 0.5);  // pushed up, out of the face
  EXPECT_EQ(bridge.rejected_packets(), 0U);
  EXPECT_GE(bridge.received_packets(), 100U);
}

}  // namespace
}  // namespace ido::drill

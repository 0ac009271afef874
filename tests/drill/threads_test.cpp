// SPDX-License-Identifier: Apache-2.0
// Across threads (label: threads): the lock-free hand-offs, the boundary surface rebuilt by
// worker threads, the scripted device's CSV paths and the UDP bridge driving a session. The
// threaded session itself has its own test file (simulator_test).
#include <arpa/inet.h>
#include <netinet/in.h>
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

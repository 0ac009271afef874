// SPDX-License-Identifier: Apache-2.0
// The UDP device bridge: the documented packet layouts byte for byte, decoding that refuses
// malformed packets, and a bridge on the loopback that keeps the newest pose, counts the
// rejected packets, answers the latest sender, and ends on the flag or after the idle time.
#include "ido/drill/udp_bridge.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

template <class T>
T read_at(const std::uint8_t* bytes, std::size_t at) {
  T v;
  std::memcpy(&v, bytes + at, sizeof(T));
  return v;
}

TEST(UdpBridge, PacketsHaveTheDocumentedLayout) {
  PosePacket p;
  p.sequence = 0x01020304;
  p.flags = 1;
  p.t_s = 2.75;
  p.pose.position_mm = Vec3(-1.5, 2.25, 1e3);
  p.pose.orientation = Eigen::Quaterniond(0.5, 0.5, -0.5, 0.5);  // w, x, y, z
  const auto b = encode_pose(p);
  static_assert(std::tuple_size_v<decltype(b)> == 80);
  EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "IDOP");
  EXPECT_EQ(b[4], 0x04) << "little-endian sequence";
  EXPECT_EQ(read_at<std::uint32_t>(b.data(), 4), 0x01020304U);
  EXPECT_EQ(read_at<std::uint32_t>(b.data(), 8), 1U);
  EXPECT_EQ(read_at<std::uint32_t>(b.data(), 12), 0U);
  EXPECT_EQ(read_at<double>(b.data(), 16), 2.75);
  EXPECT_EQ(read_at<double>(b.data(), 24), -1.5);
  EXPECT_EQ(read_at<double>(b.data(), 32), 2.25);
  EXPECT_EQ(read_at<double>(b.data(), 40), 1e3);
  EXPECT_EQ(read_at<double>(b.data(), 48), 0.5);   // qx
  EXPECT_EQ(read_at<double>(b.data(), 56), -0.5);  // qy
  EXPECT_EQ(read_at<double>(b.data(), 64), 0.5);   // qz
  EXPECT_EQ(read_at<double>(b.data(), 72), 0.5);   // qw

  ForcePacket f;
  f.sequence = 9;
  f.flags = 1;
  f.t_s = 0.125;
  f.force_n = Vec3(0.5, -1, 3);
  const auto fb = encode_force(f);
  static_assert(std::tuple_size_v<decltype(fb)> == 48);
  EXPECT_EQ(std::string(fb.begin(), fb.begin() + 4), "IDOF");
  EXPECT_EQ(read_at<std::uint32_t>(fb.data(), 4), 9U);
  EXPECT_EQ(read_at<std::uint32_t>(fb.data(), 8), 1U);
  EXPECT_EQ(read_at<double>(fb.data(), 16), 0.125);
  EXPECT_EQ(read_at<double>(fb.data(), 24), 0.5);
  EXPECT_EQ(read_at<double>(fb.data(), 32), -1.0);
  EXPECT_EQ(read_at<double>(fb.data(), 40), 3.0);
  ForcePacket back;
  ASSERT_TRUE(decode_force(fb.data(), fb.size(), back));
  EXPECT_EQ(back.sequence, 9U);
  EXPECT_EQ(back.flags, 1U);
  EXPECT_EQ(back.t_s, 0.125);
  EXPECT_EQ(back.force_n, f.force_n);
}

TEST(UdpBridge, MalformedPacketsAreRefusedAndQuaternionsNormalised) {
  PosePacket p;
  p.pose.orientation = Eigen::Quaterniond(2, 0, 0, 0);  // not unit: decoded as the identity
  auto good = encode_pose(p);
  PosePacket q;
  ASSERT_TRUE(decode_pose(good.data(), good.size(), q));
  EXPECT_TRUE(q.pose.orientation.isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_EQ(q.pose.orientation.w(), 1.0);
  // Every field that must be finite, one at a time; a zero quaternion; size and magic.
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const std::size_t at : {16U, 24U, 32U, 40U, 48U, 56U, 64U, 72U})
    for (const double bad : {nan, inf}) {
      auto b = good;
      std::memcpy(b.data() + at, &bad, sizeof(double));
      PosePacket untouched;
      untouched.sequence = 77;
      EXPECT_FALSE(decode_pose(b.data(), b.size(), untouched)) << "offset " << at;
      EXPECT_EQ(untouched.sequence, 77U) << "a refused packet leaves the output alone";
    }
  p.pose.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  const auto zero = encode_pose(p);
  EXPECT_FALSE(decode_pose(zero.data(), zero.size(), q));
  EXPECT_FALSE(decode_pose(good.data(), good.size() - 1, q));
  std::array<std::uint8_t, 81> longer{};
  std::memcpy(longer.data(), good.data(), good.size());
  EXPECT_FALSE(decode_pose(longer.data(), longer.size(), q));
  auto wrong = good;
  wrong[3] = 'F';  // "IDOF": a force packet's magic
  EXPECT_FALSE(decode_pose(wrong.data(), wrong.size(), q));
  ForcePacket f;
  const auto fb = encode_force(f);
  EXPECT_FALSE(decode_force(good.data(), 48, f)) << "pose magic in a force-sized packet";
  auto fnan = fb;
  std::memcpy(fnan.data() + 32, &nan, sizeof(double));
  EXPECT_FALSE(decode_force(fnan.data(), fnan.size(), f));
}

// A client socket on the loopback with a receive timeout.
struct Client {
  int fd = -1;
  sockaddr_in to{};
  explicit Client(std::uint16_t port) {
    fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    timeval tv{0, 200000};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~Client() {
    if (fd >= 0) ::close(fd);
  }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;
  template <std::size_t N>
  void send(const std::array<std::uint8_t, N>& bytes) const {
    ASSERT_EQ(::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to)), ssize_t(N));
  }
};

// Calls read_pose until @p count packets were taken in (received or rejected), at most 2 s.
void drain_until(UdpBridge& bridge, std::uint64_t count, double t_s) {
  for (int i = 0; i < 2000 && bridge.received_packets() + bridge.rejected_packets() < count; ++i) {
    (void)bridge.read_pose(t_s);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

TEST(UdpBridge, KeepsTheNewestPoseAnswersTheSenderAndEnds) {
  UdpBridge bridge({.port = 0, .idle_timeout_s = 0.5});
  ASSERT_NE(bridge.port(), 0);
  EXPECT_FALSE(bridge.has_pose());
  EXPECT_FALSE(bridge.finished(1e6)) << "no packet yet: no idle time either";
  bridge.write_force(Vec3(1, 0, 0), 0.0);  // no sender yet: nothing to do, no crash
  const Client client(bridge.port());
  for (std::uint32_t s = 1; s <= 3; ++s) {
    PosePacket p;
    p.sequence = s;
    p.t_s = 0.01 * s;
    p.pose.position_mm = Vec3(s, 2.0 * s, 0);
    client.send(encode_pose(p));
  }
  std::array<std::uint8_t, 10> junk{};
  client.send(junk);
  drain_until(bridge, 4, 1.0);
  EXPECT_EQ(bridge.received_packets(), 3U);
  EXPECT_EQ(bridge.rejected_packets(), 1U);
  EXPECT_TRUE(bridge.has_pose());
  EXPECT_EQ(bridge.read_pose(1.0).position_mm, Vec3(3, 6, 0)) << "the newest pose";
  // The force goes back to the sender, with the latest pose's sequence and the contact flag.
  bridge.write_force(Vec3(0.25, -0.5, 2.0), 1.0);
  std::array<std::uint8_t, 128> buf{};
  ssize_t n = ::recv(client.fd, buf.data(), buf.size(), 0);
  ASSERT_EQ(n, ssize_t(kForcePacketBytes));
  ForcePacket f;
  ASSERT_TRUE(decode_force(buf.data(), std::size_t(n), f));
  EXPECT_EQ(f.sequence, 3U);
  EXPECT_EQ(f.flags, 1U);
  EXPECT_EQ(f.t_s, 1.0);
  EXPECT_EQ(f.force_n, Vec3(0.25, -0.5, 2.0));
  bridge.write_force(Vec3::Zero(), 1.001);
  n = ::recv(client.fd, buf.data(), buf.size(), 0);
  ASSERT_EQ(n, ssize_t(kForcePacketBytes));
  ASSERT_TRUE(decode_force(buf.data(), std::size_t(n), f));
  EXPECT_EQ(f.flags, 0U) << "no force, no contact";
  // Idle: finished once no pose came for longer than the timeout (session time).
  EXPECT_FALSE(bridge.finished(1.4));
  EXPECT_TRUE(bridge.finished(1.6));
  // The end-of-session flag ends it at once.
  PosePacket last;
  last.sequence = 4;
  last.flags = 1;
  client.send(encode_pose(last));
  drain_until(bridge, 5, 2.0);
  EXPECT_TRUE(bridge.finished(2.0));
}

TEST(UdpBridge, APortInUseIsAnErrorNamingIt) {
  const UdpBridge first({.port = 0});
  try {
    const UdpBridge second({.port = first.port()});
    FAIL() << "bound the same port twice";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(first.port())), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ido::drill

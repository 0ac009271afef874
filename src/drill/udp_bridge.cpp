// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/udp_bridge.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>

#include "ido/core/error.h"

namespace ido::drill {
namespace {

static_assert(sizeof(sockaddr_in) <= 16, "peer buffer too small");

template <class T>
void put(std::uint8_t* p, std::size_t& at, T v) {
  std::memcpy(p + at, &v, sizeof(T));  // x86 / little-endian hosts: bytes are little-endian
  at += sizeof(T);
}
template <class T>
T get(const std::uint8_t* p, std::size_t& at) {
  T v;
  std::memcpy(&v, p + at, sizeof(T));
  at += sizeof(T);
  return v;
}

}  // namespace

std::array<std::uint8_t, kPosePacketBytes> encode_pose(const PosePacket& p) noexcept {
  std::array<std::uint8_t, kPosePacketBytes> b{};
  std::memcpy(b.data(), "IDOP", 4);
  std::size_t at = 4;
  put(b.data(), at, p.sequence);
  put(b.data(), at, p.flags);
  put(b.data(), at, std::uint32_t{0});
  put(b.data(), at, p.t_s);
  for (int i = 0; i < 3; ++i) put(b.data(), at, p.pose.position_mm[i]);
  put(b.data(), at, p.pose.orientation.x());
  put(b.data(), at, p.pose.orientation.y());
  put(b.data(), at, p.pose.orientation.z());
  put(b.data(), at, p.pose.orientation.w());
  return b;
}

std::array<std::uint8_t, kForcePacketBytes> encode_force(const ForcePacket& p) noexcept {
  std::array<std::uint8_t, kForcePacketBytes> b{};
  std::memcpy(b.data(), "IDOF", 4);
  std::size_t at = 4;
  put(b.data(), at, p.sequence);
  put(b.data(), at, p.flags);
  put(b.data(), at, std::uint32_t{0});
  put(b.data(), at, p.t_s);
  for (int i = 0; i < 3; ++i) put(b.data(), at, p.force_n[i]);
  return b;
}

bool decode_pose(const std::uint8_t* bytes, std::size_t size, PosePacket& out) noexcept {
  if (size != kPosePacketBytes || std::memcmp(bytes, "IDOP", 4) != 0) return false;
  std::size_t at = 4;
  PosePacket p;
  p.sequence = get<std::uint32_t>(bytes, at);
  p.flags = get<std::uint32_t>(bytes, at);
  (void)get<std::uint32_t>(bytes, at);
  p.t_s = get<double>(bytes, at);
  for (int i = 0; i < 3; ++i) p.pose.position_mm[i] = get<double>(bytes, at);
  const double qx = get<double>(bytes, at), qy = get<double>(bytes, at), qz = get<double>(bytes, at),
               qw = get<double>(bytes, at);
  p.pose.orientation = Eigen::Quaterniond(qw, qx, qy, qz);
  if (!std::isfinite(p.t_s) || !p.pose.position_mm.allFinite() || !p.pose.orientation.coeffs().allFinite()) return false;
  const double n = p.pose.orientation.norm();
  if (n < 1e-9) return false;
  p.pose.orientation.coeffs() /= n;
  out = p;
  return true;
}

bool decode_force(const std::uint8_t* bytes, std::size_t size, ForcePacket& out) noexcept {
  if (size != kForcePacketBytes || std::memcmp(bytes, "IDOF", 4) != 0) return false;
  std::size_t at = 4;
  ForcePacket p;
  p.sequence = get<std::uint32_t>(bytes, at);
  p.flags = get<std::uint32_t>(bytes, at);
  (void)get<std::uint32_t>(bytes, at);
  p.t_s = get<double>(bytes, at);
  for (int i = 0; i < 3; ++i) p.force_n[i] = get<double>(bytes, at);
  if (!std::isfinite(p.t_s) || !p.force_n.allFinite()) return false;
  out = p;
  return true;
}

UdpBridge::UdpBridge(const UdpBridgeOptions& options) : m_options(options) {
  m_socket = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (m_socket < 0) throw Error(std::string("udp bridge: cannot open a socket: ") + std::strerror(errno));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(options.port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(m_socket, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const std::string why = std::strerror(errno);
    ::close(m_socket);
    throw Error("udp bridge: cannot bind 127.0.0.1:" + std::to_string(options.port) + ": " + why);
  }
  socklen_t len = sizeof(addr);
  ::getsockname(m_socket, reinterpret_cast<sockaddr*>(&addr), &len);
  m_port = ntohs(addr.sin_port);
}

UdpBridge::~UdpBridge() {
  if (m_socket >= 0) ::close(m_socket);
}

ToolPose UdpBridge::read_pose(double t_s) noexcept {
  std::array<std::uint8_t, 256> buf{};
  for (;;) {
    sockaddr_in from{};
    socklen_t len = sizeof(from);
    const ssize_t n = ::recvfrom(m_socket, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&from), &len);
    if (n < 0) break;  // EAGAIN: drained
    PosePacket p;
    if (!decode_pose(buf.data(), static_cast<std::size_t>(n), p)) {
      m_rejected.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    m_received.fetch_add(1, std::memory_order_relaxed);
    m_pose = p.pose;
    m_sequence = p.sequence;
    std::memcpy(m_peer.data(), &from, sizeof(from));
    m_have_peer = true;
    m_last_packet_s.store(t_s, std::memory_order_relaxed);
    if (p.flags & 1U) m_end.store(true, std::memory_order_relaxed);
  }
  return m_pose;
}

void UdpBridge::write_force(const Vec3& force_n, double t_s) noexcept {
  if (!m_have_peer) return;
  ForcePacket f;
  f.sequence = m_sequence;
  f.flags = force_n.squaredNorm() > 0.0 ? 1U : 0U;
  f.t_s = t_s;
  f.force_n = force_n;
  const auto bytes = encode_force(f);
  sockaddr_in to{};
  std::memcpy(&to, m_peer.data(), sizeof(to));
  (void)::sendto(m_socket, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
}

bool UdpBridge::finished(double t_s) const noexcept {
  if (m_end.load(std::memory_order_relaxed)) return true;
  const double last = m_last_packet_s.load(std::memory_order_relaxed);
  return last >= 0.0 && t_s - last > m_options.idle_timeout_s;
}

}  // namespace ido::drill

// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "ido/drill/haptic_device.h"

namespace ido::drill {

/// UDP packet formats of the device bridge (all fields little-endian, no padding; see
/// docs/drilling.md). Pose, from the device driver to ido, 80 bytes:
///   char magic[4] = "IDOP"; u32 sequence; u32 flags (bit 0: end of session); u32 reserved;
///   f64 t_s; f64 position_mm[3]; f64 quaternion[4] (qx, qy, qz, qw).
/// Force, from ido back to the sender of the latest pose, 48 bytes:
///   char magic[4] = "IDOF"; u32 sequence (of the latest pose); u32 flags (bit 0: in
///   contact); u32 reserved; f64 t_s (session time); f64 force_n[3].
inline constexpr std::size_t kPosePacketBytes = 80;
inline constexpr std::size_t kForcePacketBytes = 48;

/// A decoded pose packet.
struct PosePacket {
  std::uint32_t sequence = 0;
  std::uint32_t flags = 0;
  double t_s = 0.0;
  ToolPose pose;
};
/// A decoded force packet.
struct ForcePacket {
  std::uint32_t sequence = 0;
  std::uint32_t flags = 0;
  double t_s = 0.0;
  Vec3 force_n = Vec3::Zero();
};

[[nodiscard]] std::array<std::uint8_t, kPosePacketBytes> encode_pose(const PosePacket& p) noexcept;
[[nodiscard]] std::array<std::uint8_t, kForcePacketBytes> encode_force(const ForcePacket& p) noexcept;
/// False when the bytes are not a well-formed packet (size, magic, non-finite values).
[[nodiscard]] bool decode_pose(const std::uint8_t* bytes, std::size_t size, PosePacket& out) noexcept;
[[nodiscard]] bool decode_force(const std::uint8_t* bytes, std::size_t size, ForcePacket& out) noexcept;

/// Options of the UDP bridge.
struct UdpBridgeOptions {
  std::uint16_t port = 0;        ///< UDP port on 127.0.0.1; 0 = any free port (see port())
  double idle_timeout_s = 2.0;   ///< finished when no pose arrived for this long after the first
};

/// A HapticDevice fed by UDP pose packets on the loopback interface; forces go back to
/// the sender of the latest pose. read_pose drains the socket without blocking and keeps
/// the newest pose; malformed packets are counted and ignored. No allocation on the
/// haptic path (only recvfrom/sendto system calls).
class UdpBridge final : public HapticDevice {
 public:
  /// Binds 127.0.0.1:port. @throws ido::Error if the socket cannot be opened or bound.
  explicit UdpBridge(const UdpBridgeOptions& options = {});
  ~UdpBridge() override;
  UdpBridge(const UdpBridge&) = delete;
  UdpBridge& operator=(const UdpBridge&) = delete;

  /// The bound port.
  [[nodiscard]] std::uint16_t port() const noexcept { return m_port; }
  ToolPose read_pose(double t_s) noexcept override;
  void write_force(const Vec3& force_n, double t_s) noexcept override;
  [[nodiscard]] bool finished(double t_s) const noexcept override;
  [[nodiscard]] bool has_pose() const noexcept override { return m_have_peer; }
  /// Packets rejected as malformed.
  [[nodiscard]] std::uint64_t rejected_packets() const noexcept { return m_rejected.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t received_packets() const noexcept { return m_received.load(std::memory_order_relaxed); }

 private:
  UdpBridgeOptions m_options;
  int m_socket = -1;
  std::uint16_t m_port = 0;
  ToolPose m_pose;
  std::uint32_t m_sequence = 0;
  std::array<std::uint8_t, 16> m_peer{};  // sockaddr_in of the latest sender
  bool m_have_peer = false;
  std::atomic<bool> m_end{false};
  std::atomic<double> m_last_packet_s{-1.0};
  std::atomic<std::uint64_t> m_rejected{0};
  std::atomic<std::uint64_t> m_received{0};
};

}  // namespace ido::drill

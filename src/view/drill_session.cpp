// SPDX-License-Identifier: Apache-2.0
#include "ido/view/drill_session.h"

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "ido/drill/boundary_surface.h"

namespace ido::view {
namespace {

/// The volume (mm³) a closed, outward-oriented surface encloses (divergence theorem).
double enclosed_volume(const geometry::TriangleMesh& m) {
  double v = 0.0;
  for (const Tri& t : m.triangles)
    v += m.vertices[std::size_t(t[0])].dot(m.vertices[std::size_t(t[1])].cross(m.vertices[std::size_t(t[2])]));
  return v / 6.0;
}

}  // namespace

// ---- the device ------------------------------------------------------------------------------

WindowDevice::WindowDevice(std::size_t capacity, double max_duration_s, std::unique_ptr<drill::HapticDevice> source)
    : m_source(std::move(source)), m_times(capacity), m_poses(capacity), m_max_duration_s(max_duration_s) {
  if (capacity == 0) throw InvalidInput("the window device needs room for at least one tick");
}

void WindowDevice::set_position(const Vec3& position_mm) noexcept {
  drill::ToolPose pose;
  pose.position_mm = position_mm;
  set_pose(pose);
}

void WindowDevice::set_pose(const drill::ToolPose& pose) noexcept {
  m_pose.write(pose);
  m_has_pose.store(true, std::memory_order_release);
}

bool WindowDevice::has_pose() const noexcept {
  return m_source ? m_source->has_pose() : m_has_pose.load(std::memory_order_acquire);
}

drill::ToolPose WindowDevice::read_pose(double t_s) noexcept {
  const drill::ToolPose pose = m_source ? m_source->read_pose(t_s) : m_pose.read();
  if (!has_pose()) return pose;  // nothing to record or show yet (no packet from the device)
  m_shown.write(pose);
  const std::size_t n = m_count.load(std::memory_order_relaxed);
  if (n < m_times.size() && (n == 0 || t_s > m_times[n - 1])) {
    m_times[n] = t_s;
    m_poses[n] = pose;
    m_count.store(n + 1, std::memory_order_release);
  }
  return pose;
}

void WindowDevice::write_force(const Vec3& force_n, double t_s) noexcept {
  drill::ForceSample s;
  s.t_s = t_s;
  s.force_n = force_n;
  m_force.write(s);
  if (m_source) m_source->write_force(force_n, t_s);
}

bool WindowDevice::finished(double t_s) const noexcept {
  return m_finished.load(std::memory_order_acquire) || t_s > m_max_duration_s ||
         m_count.load(std::memory_order_relaxed) >= m_times.size() || (m_source && m_source->finished(t_s));
}

// ---- the session -----------------------------------------------------------------------------

drill::SimulatorOptions drill_cli_options(double burr_radius_mm, double shaft_radius_mm) {
  // As apps/ido/cmd_drill.cpp with its defaults (--force-threshold 0.2, --removal-rate 0,
  // --stiffness 1.5, neither --max-depth nor --min-size).
  drill::SimulatorOptions so;
  so.tool.burr_radius_mm = burr_radius_mm;
  so.tool.shaft_radius_mm = shaft_radius_mm;
  so.erosion.force_threshold_n = 0.2;
  so.erosion.removal_rate_mm3_per_s = 0.0;
  so.erosion.min_size_mm = burr_radius_mm / 4.0;
  so.coupling.stiffness_n_per_mm = 1.5;
  so.surface.threads = 0;
  return so;
}

std::unique_ptr<drill::ScriptedTrajectory> load_path_device(const std::filesystem::path& csv,
                                                            const drill::SimulatorOptions& options) {
  // As `ido drill`: the recording holds the path's ticks and the drain, not a fixed 2^20.
  const auto peek = drill::ScriptedTrajectory::load_csv(csv, 1);
  const auto ticks = static_cast<std::size_t>((peek.duration() + options.drain_limit_s + 1.0) / options.haptic_period_s) + 1024;
  return std::make_unique<drill::ScriptedTrajectory>(peek.times(), peek.poses(), std::min(ticks, options.max_haptic_ticks));
}

DrillSession::DrillSession(const geometry::TetMesh& mesh, const drill::SimulatorOptions& options, double max_duration_s,
                           std::unique_ptr<drill::HapticDevice> source)
    : m_options(options),
      m_max_duration_s(max_duration_s),
      m_hierarchy(std::make_unique<drill::TetHierarchy>(mesh)),
      m_device(static_cast<std::size_t>(max_duration_s / options.haptic_period_s) + 1024, max_duration_s, std::move(source)) {
  if (!(max_duration_s > 0) || max_duration_s > drill::kMaxScriptDuration_s)
    throw InvalidInput(fmt::format("a drilling session lasts 0..{} s, not {}", drill::kMaxScriptDuration_s, max_duration_s));
  m_root_vertices = m_hierarchy->vertices();
  m_initial_volume_mm3 = m_hierarchy->material_volume();
  m_options.max_haptic_ticks = std::min<std::size_t>(
      static_cast<std::size_t>((max_duration_s + m_options.drain_limit_s + 1.0) / m_options.haptic_period_s) + 1024,
      m_options.max_haptic_ticks);
  m_simulator = std::make_unique<drill::Simulator>(*m_hierarchy, m_device, m_options);
  m_simulator->set_surface_snapshots(
      [this](double t, const std::vector<std::vector<drill::SurfaceFace>>& lists) { take_snapshot(t, lists); }, 0.05,
      max_duration_s);
}

DrillSession::~DrillSession() {
  m_device.finish();
  if (m_thread.joinable()) m_thread.join();
}

void DrillSession::take_snapshot(double t_s, const std::vector<std::vector<drill::SurfaceFace>>& v_lists) {
  // Times the session did not reach are served all at once when it stops: those are skipped
  // (the session thread hands over the final surface itself).
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
  if (t_s > elapsed + 0.2) return;
  auto snap = std::make_shared<DrillSnapshot>();
  snap->t_s = t_s;
  snap->surface = drill::assemble_surface(std::span<const std::vector<drill::SurfaceFace>>(v_lists), m_root_vertices);
  snap->volume_mm3 = enclosed_volume(snap->surface);
  m_surfaces.write(std::shared_ptr<const DrillSnapshot>(std::move(snap)));
}

void DrillSession::start(const drill::ToolPose& start) {
  if (started()) return;
  m_device.set_pose(start);
  m_start = std::chrono::steady_clock::now();
  m_thread = std::thread([this] {
    try {
      m_simulator->run(m_max_duration_s + m_options.drain_limit_s + 30.0);
      auto snap = std::make_shared<DrillSnapshot>();
      snap->t_s = m_simulator->stats().haptic_ticks * m_options.haptic_period_s;
      snap->surface = drill::assemble_surface(std::span<const std::vector<drill::SurfaceFace>>(m_simulator->render_v_lists()),
                                              m_root_vertices);
      snap->volume_mm3 = enclosed_volume(snap->surface);
      snap->final = true;
      m_surfaces.write(std::shared_ptr<const DrillSnapshot>(std::move(snap)));
    } catch (const std::exception&) {
      m_failed = true;
    }
    m_ended.store(true, std::memory_order_release);
  });
}

bool DrillSession::ended() {
  if (m_ended.load(std::memory_order_acquire) && m_thread.joinable()) m_thread.join();  // returned: no wait
  return m_ended.load(std::memory_order_acquire);
}

std::shared_ptr<const DrillSnapshot> DrillSession::latest_surface() {
  if (m_surfaces.has_new()) m_latest = m_surfaces.read();
  return m_latest;
}

DrillFigures DrillSession::figures() {
  DrillFigures f;
  const drill::ForceSample s = m_device.latest_force();
  f.force_n = s.force_n;
  f.contact = s.force_n.squaredNorm() > 0.0;
  const std::size_t n = m_device.recorded();
  f.ticks = n;
  if (n > 0) f.session_s = m_device.time_s(n - 1);
  std::vector<double> periods;
  for (std::size_t i = n > 2000 ? n - 2000 : 1; i < n; ++i)
    periods.push_back(1e3 * (m_device.time_s(i) - m_device.time_s(i - 1)));
  f.haptic_period_ms = drill::percentiles(std::move(periods));
  const drill::LiveStats live = m_simulator->live_stats();
  f.update_time_ms = live.update_time_s;
  for (double* x : {&f.update_time_ms.p50, &f.update_time_ms.p99, &f.update_time_ms.p999, &f.update_time_ms.max}) *x *= 1e3;
  f.removed_volume_mm3 = live.removed_volume_mm3;
  return f;
}

void DrillSession::write_path_csv(const std::filesystem::path& path) const {
  if (!m_ended.load(std::memory_order_acquire)) throw Error("the drilling session has not ended");
  const std::size_t n = m_device.recorded();
  bool turned = false;  // orientation columns only when the tool was turned
  for (std::size_t i = 0; i < n && !turned; ++i)
    turned = m_device.pose(i).orientation.coeffs() != Eigen::Quaterniond::Identity().coeffs();
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        out << (turned ? "t,x,y,z,qx,qy,qz,qw\n" : "t,x,y,z\n");
        for (std::size_t i = 0; i < n; ++i) {
          const drill::ToolPose& p = m_device.pose(i);
          out << fmt::format("{:.9g},{:.17g},{:.17g},{:.17g}", m_device.time_s(i), p.position_mm.x(), p.position_mm.y(),
                             p.position_mm.z());
          if (turned) {
            const Eigen::Quaterniond& q = p.orientation;
            out << fmt::format(",{:.17g},{:.17g},{:.17g},{:.17g}", q.x(), q.y(), q.z(), q.w());
          }
          out << '\n';
        }
      },
      false);
}

}  // namespace ido::view

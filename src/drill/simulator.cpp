// SPDX-License-Identifier: Apache-2.0
#include "ido/drill/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "ido/core/error.h"
#include "ido/core/statistics.h"

namespace ido::drill {
namespace {

// Spin-wait hint: lets the core's other hardware thread run and saves power while spinning.
void cpu_relax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

// Asks for SCHED_FIFO at @p priority for the calling thread; false when refused or
// unsupported (the thread then keeps ordinary scheduling). priority 0 asks for nothing.
bool request_realtime(int priority) noexcept {
  if (priority <= 0) return false;
#if defined(__linux__)
  sched_param param{};
  param.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
#else
  return false;
#endif
}

// The session's v_list options: threads = 0 becomes the hardware threads less one for the
// haptic thread (at least 1).
BoundarySurfaceOptions session_surface_options(BoundarySurfaceOptions o) {
  if (o.threads == 0) o.threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
  return o;
}

}  // namespace

Percentiles percentiles(std::vector<double> v) {
  Percentiles p;
  p.count = v.size();
  if (v.empty()) return p;
  const std::vector<double> q = ido::percentiles(std::move(v), {0.5, 0.99, 0.999, 1.0});
  p.p50 = q[0];
  p.p99 = q[1];
  p.p999 = q[2];
  p.max = q[3];
  return p;
}

void Simulator::record_live_update(double seconds, double removed_mm3) noexcept {
  // Bin b holds [kLiveMin_s · r^b, kLiveMin_s · r^(b+1)), r = 10^(1/kLiveBinsPerDecade).
  const double x = seconds > kLiveMin_s ? std::log10(seconds / kLiveMin_s) * kLiveBinsPerDecade : 0.0;
  const int bin = std::clamp(static_cast<int>(x), 0, kLiveBins - 1);
  m_live_bins[std::size_t(bin)].fetch_add(1, std::memory_order_relaxed);
  if (seconds > m_live_max_s.load(std::memory_order_relaxed)) m_live_max_s.store(seconds, std::memory_order_relaxed);
  m_live_removed_mm3.store(removed_mm3, std::memory_order_relaxed);
}

LiveStats Simulator::live_stats() const noexcept {
  std::array<std::uint64_t, kLiveBins> bins{};
  std::uint64_t n = 0;
  for (std::size_t b = 0; b < bins.size(); ++b) {
    bins[b] = m_live_bins[b].load(std::memory_order_relaxed);
    n += bins[b];
  }
  LiveStats out;
  out.collision_updates = static_cast<std::size_t>(n);
  out.removed_volume_mm3 = m_live_removed_mm3.load(std::memory_order_relaxed);
  Percentiles& p = out.update_time_s;
  p.count = static_cast<std::size_t>(n);
  p.max = m_live_max_s.load(std::memory_order_relaxed);
  if (n == 0) return out;
  // The k-th smallest time (0-based) as the geometric centre of its bin; never above the max.
  const auto order_statistic = [&](std::uint64_t k) {
    std::uint64_t below = 0;
    std::size_t b = 0;
    for (; b + 1 < bins.size() && below + bins[b] <= k; ++b) below += bins[b];
    return std::min(p.max, kLiveMin_s * std::pow(10.0, (static_cast<double>(b) + 0.5) / kLiveBinsPerDecade));
  };
  // ido::percentile: linear interpolation at q · (n − 1).
  const auto quantile = [&](double q) {
    const double pos = q * static_cast<double>(n - 1);
    const auto k = static_cast<std::uint64_t>(pos);
    const double lo = order_statistic(k);
    return k + 1 < n ? lo + (pos - static_cast<double>(k)) * (order_statistic(k + 1) - lo) : lo;
  };
  p.p50 = quantile(0.5);
  p.p99 = quantile(0.99);
  p.p999 = quantile(0.999);
  return out;
}

Simulator::Simulator(TetHierarchy& hierarchy, HapticDevice& device, const SimulatorOptions& options)
    : m_hierarchy(hierarchy),
      m_device(device),
      m_options(options),
      m_tool(options.tool),
      m_eroder(options.erosion),
      m_surface(hierarchy, session_surface_options(options.surface)),
      m_coupling(options.coupling) {
  if (!(options.haptic_period_s > 0.0) || !std::isfinite(options.haptic_period_s)) {
    throw InvalidInput("simulator: haptic period must be positive");
  }
  if (!(options.haptic_spin_s >= 0.0) || !(options.haptic_spin_s < options.haptic_period_s)) {
    throw InvalidInput("simulator: haptic spin time must be at least 0 and shorter than the haptic period");
  }
  for (const int priority : {options.haptic_realtime_priority, options.collision_realtime_priority}) {
    if (priority < 0 || priority > 99) throw InvalidInput("simulator: real-time priority must be in [0, 99] (0 = ordinary)");
  }
  // The render copy is kept as chunks; render_v_lists() is flattened at stop() (building the
  // surface's concatenated v_lists here would keep a third copy of every face for nothing).
  m_tick_period.assign(options.max_haptic_ticks, 0.0);
  m_tick_compute.assign(options.max_haptic_ticks, 0.0);
  m_tick_force.assign(options.max_haptic_ticks, 0.0);
}

Simulator::~Simulator() { stop(); }

SessionMemory Simulator::memory_use() const noexcept {
  SessionMemory m;
  m.nodes = m_hierarchy.node_storage_capacity_bytes();
  m.hash = m_hierarchy.root_hash().memory_bytes();
  m.v_lists = m_surface.memory_bytes();
  // The render copy's lists count where the surface no longer holds them.
  for (std::size_t r = 0; r < m_render_chunks.size(); ++r) {
    m.v_lists += m_render_chunks[r].capacity() * sizeof(m_render_chunks[r][0]);
    for (std::size_t c = 0; c < m_render_chunks[r].size(); ++c) {
      const auto& list = m_render_chunks[r][c];
      if (list && (c >= m_surface.chunk_count(r) || list != m_surface.shared_chunk(r, c)))
        m.v_lists += list->capacity() * sizeof(SurfaceFace);
    }
  }
  for (const auto& l : m_render_lists) m.v_lists += l.capacity() * sizeof(SurfaceFace);
  m.buffers = (m_tick_period.capacity() + m_tick_compute.capacity() + m_tick_force.capacity()) * sizeof(double);
  const auto& st = m_stats;
  m.buffers += (st.update_time_s.capacity() + st.haptic_period_s.capacity() + st.force_compute_time_s.capacity() +
                st.erosion_visits.capacity()) *
               sizeof(double);
  m.buffers += sizeof(m_live_bins) + sizeof(m_pose_buffer) + sizeof(m_contact_buffer) + sizeof(m_snapshots) + m_pending.capacity() * sizeof(ChunkId);
  return m;
}

void Simulator::set_surface_snapshots(SurfaceSnapshotFn fn, double period_s, double end_s) {
  if (!(period_s > 0.0) || !std::isfinite(period_s)) throw InvalidInput("simulator: snapshot period must be positive");
  m_snapshot_fn = std::move(fn);
  m_snapshot_period_s = period_s;
  m_snapshot_end_s = std::max(0.0, end_s);
  m_next_snapshot = 0;
}

double Simulator::now_s() const noexcept {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
  return static_cast<double>(ns - m_start_ns) * 1e-9;
}

void Simulator::start() {
  if (m_running) return;
  m_stop.store(false);
  m_collision_done.store(false);
  m_finished.store(false);
  m_collision_exited.store(false);
  m_path_over.store(false);
  m_timed_out = false;
  m_stats = {};
  for (auto& b : m_live_bins) b.store(0, std::memory_order_relaxed);
  m_live_max_s.store(0.0, std::memory_order_relaxed);
  m_live_removed_mm3.store(0.0, std::memory_order_relaxed);
  m_stats.surface_threads = m_surface.options().threads;
  // The render consumer's copy starts as the surface is now.
  m_render_lists = {};
  m_render_chunks.assign(m_hierarchy.root_count(), {});
  for (std::size_t r = 0; r < m_hierarchy.root_count(); ++r) {
    m_render_chunks[r].resize(m_surface.chunk_count(r));
    for (std::size_t c = 0; c < m_surface.chunk_count(r); ++c) m_render_chunks[r][c] = m_surface.shared_chunk(r, c);
  }
  m_start_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
  // Initial pose and contact model before the threads run.
  if (m_device.has_pose()) {
    PoseSample first;
    first.pose = m_device.read_pose(0.0);
    m_contact_buffer.write(collide(m_hierarchy, m_tool, first.pose));
  }
  m_running = true;
  m_collision = std::thread([this] { collision_loop(); });
  m_render = std::thread([this] { render_loop(); });
  m_haptic = std::thread([this] { haptic_loop(); });
}

void Simulator::stop() {
  if (!m_running) return;
  m_stop.store(true);
  m_haptic.join();
  m_collision.join();
  m_render.join();
  m_running = false;
  m_stats.timed_out = m_timed_out;
  // A drain cut short may leave v_list chunks unbuilt: build them, so the render copy
  // matches the tree (the threads are joined; this thread owns everything now).
  if (m_surface.has_pending()) {
    m_surface.flush(m_hierarchy);
    for (const ChunkId& c : m_surface.last_rebuilt_chunks()) {
      auto& root = m_render_chunks[c.root];
      if (root.size() < m_surface.chunk_count(c.root)) root.resize(m_surface.chunk_count(c.root));
      root[c.chunk] = m_surface.shared_chunk(c.root, c.chunk);
    }
  }
  // The render copy stays as chunk lists, shared with the surface, until render_v_lists() or
  // take_render_v_lists() asks for it (flattening it here held every face twice).
  const std::size_t n = std::min(m_stats.haptic_ticks, m_tick_period.size());
  m_stats.haptic_period_s.assign(m_tick_period.begin() + (n > 0 ? 1 : 0), m_tick_period.begin() + static_cast<std::ptrdiff_t>(n));
  m_stats.force_compute_time_s.assign(m_tick_compute.begin(), m_tick_compute.begin() + static_cast<std::ptrdiff_t>(n));
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double f = m_tick_force[i];
    m_stats.peak_force_n = std::max(m_stats.peak_force_n, f);
    if (f > 0.0) {
      sum += f;
      ++m_stats.contact_ticks;
    }
    if (i > 0) m_stats.max_force_step_n = std::max(m_stats.max_force_step_n, std::abs(f - m_tick_force[i - 1]));
  }
  m_stats.mean_force_n = m_stats.contact_ticks > 0 ? sum / static_cast<double>(m_stats.contact_ticks) : 0.0;
}

void Simulator::run(double timeout_s, Progress* progress) {
  start();
  const auto t0 = std::chrono::steady_clock::now();
  const double duration = m_device.duration_s();
  bool cancelled = false;
  while (!m_finished.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (elapsed > timeout_s) {
      m_timed_out = true;
      break;
    }
    if (progress != nullptr) {
      if (progress->cancelled()) {
        cancelled = true;
        break;
      }
      const bool draining = m_path_over.load(std::memory_order_acquire);
      progress->update(draining ? 1.0 : (duration > 0.0 ? std::min(1.0, elapsed / duration) : 0.0),
                       draining ? "finishing" : "drilling");
    }
  }
  stop();
  check_cancel(cancelled ? progress : nullptr);
}

void Simulator::haptic_loop() {
  using clock = std::chrono::steady_clock;
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(m_options.haptic_period_s * 1e9));
  const auto spin = std::chrono::nanoseconds(static_cast<std::int64_t>(m_options.haptic_spin_s * 1e9));
  m_stats.haptic_realtime = request_realtime(m_options.haptic_realtime_priority);
  auto next = clock::now();
  double prev_start = -1.0;
  std::uint64_t seq = 0;
  std::size_t tick = 0;
  while (!m_stop.load(std::memory_order_relaxed)) {
    const double t0 = now_s();
    const ToolPose pose = m_device.read_pose(t0);
    const bool live = m_device.has_pose();
    const ContactModel& model = m_contact_buffer.read();
    const Vec3 f = live ? m_coupling.update(model, pose.position_mm, m_options.haptic_period_s) : Vec3(Vec3::Zero());
    m_device.write_force(f, t0);
    PoseSample s;
    s.sequence = ++seq;
    s.t_s = t0;
    s.pose = pose;
    // Pressing force: the component pushing the tool back out of the material.
    s.force_n = model.in_contact ? std::max(0.0, f.dot(model.normal)) : 0.0;
    if (live) m_pose_buffer.write(s);
    const double t1 = now_s();
    if (tick < m_tick_period.size()) {
      m_tick_period[tick] = prev_start < 0.0 ? 0.0 : t0 - prev_start;
      m_tick_compute[tick] = t1 - t0;
      m_tick_force[tick] = f.norm();
    }
    ++tick;
    m_stats.haptic_ticks = tick;
    prev_start = t0;
    next += period;
    if (clock::now() > next) {
      ++m_stats.missed_deadlines;
      // Resynchronise after an overrun instead of bursting to catch up.
      next = clock::now();
    }
    if (m_device.finished(t0) && m_collision_done.load(std::memory_order_acquire)) {
      m_finished.store(true, std::memory_order_release);
    }
    // Hybrid wait: sleep until spin before the tick, then spin on the clock up to it.
    if (spin.count() > 0) {
      if (clock::now() < next - spin) std::this_thread::sleep_until(next - spin);
      while (clock::now() < next) cpu_relax();
    } else {
      std::this_thread::sleep_until(next);
    }
  }
}

void Simulator::send_pending() {
  if (m_pending.empty()) return;
  std::sort(m_pending.begin(), m_pending.end());
  m_pending.erase(std::unique(m_pending.begin(), m_pending.end()), m_pending.end());
  auto snap = std::make_unique<Snapshot>();
  snap->chunks = m_pending;
  snap->lists.reserve(m_pending.size());
  for (const ChunkId& c : m_pending) {
    snap->chunk_counts.push_back(static_cast<std::uint32_t>(m_surface.chunk_count(c.root)));
    snap->lists.push_back(m_surface.shared_chunk(c.root, c.chunk));
  }
  if (m_snapshots.push(snap)) m_pending.clear();
}

void Simulator::collision_loop() {
  std::uint64_t last_seq = 0;
  bool have_last = false;
  Vec3 last_centre = Vec3::Zero();
  double last_t = 0.0;
  const double r = m_tool.burr_radius();
  const double substep = m_options.max_substep_mm > 0.0 ? m_options.max_substep_mm : 0.25 * r;
  const std::size_t budget = m_options.erosion.max_node_visits;
  m_stats.collision_realtime = request_realtime(m_options.collision_realtime_priority);
  bool path_over = false;  // a pose past the path's end was taken: no more erosion is queued
  bool done = false;       // the backlog is finished (or the drain limit passed)
  double drain_start = 0.0;
  while (!m_stop.load(std::memory_order_relaxed)) {
    const bool fresh = m_pose_buffer.has_new();
    if (done || (!fresh && !m_eroder.has_pending() && !m_surface.has_pending())) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    const double t0 = now_s();
    bool new_pose = false;
    PoseSample s;
    if (fresh) {
      s = m_pose_buffer.read();
      new_pose = s.sequence != last_seq;
    }
    if (new_pose && !path_over) {
      last_seq = s.sequence;
      const Vec3 c = s.pose.position_mm;
      const double dt = have_last ? std::max(0.0, s.t_s - last_t) : 0.0;
      const Vec3 from = have_last ? last_centre : c;
      const int n = std::max(1, static_cast<int>(std::ceil((c - from).norm() / substep)));
      for (int i = 1; i <= n; ++i) m_eroder.enqueue(from + (c - from) * (static_cast<double>(i) / n), r, s.force_n, dt / n);
      m_stats.erosion_backlog_max = std::max(m_stats.erosion_backlog_max, m_eroder.queued());
      have_last = true;
      last_centre = c;
      last_t = s.t_s;
      if (m_device.finished(s.t_s)) {
        // The path is over: this pose (its end) was the last one queued; what is left is
        // the backlog, finished within drain_limit_s.
        path_over = true;
        drain_start = t0;
        m_path_over.store(true, std::memory_order_release);
      }
    } else if (new_pose) {
      last_seq = s.sequence;
    } else if (!m_eroder.has_pending() && !m_surface.has_pending()) {
      continue;
    }
    const ErosionStats es = m_eroder.run(m_hierarchy, budget);
    m_stats.removed_volume_mm3 += es.removed_volume_mm3;
    if (es.node_limit_reached) ++m_stats.node_limit_passes;
    m_stats.erosion_visits.push_back(static_cast<double>(es.nodes_visited));
    if (new_pose) m_contact_buffer.write(collide(m_hierarchy, m_tool, s.pose));
    // Changed v_list chunks: rebuild and hand them to the render consumer.
    if (!m_eroder.changed_nodes().empty() || m_surface.has_pending()) {
      m_surface.update(m_hierarchy, m_eroder.changed_nodes(), m_options.surface_visits_per_update);
      m_eroder.clear_changed_roots();
      m_pending.insert(m_pending.end(), m_surface.last_rebuilt_chunks().begin(), m_surface.last_rebuilt_chunks().end());
    } else if (!m_eroder.changed_roots().empty()) {
      m_eroder.clear_changed_roots();
    }
    const double t1 = now_s();
    m_stats.update_time_s.push_back(t1 - t0);
    ++m_stats.collision_updates;
    record_live_update(t1 - t0, m_stats.removed_volume_mm3);
    send_pending();
    if (path_over) {
      const bool drained = !m_eroder.has_pending() && !m_surface.has_pending();
      if (drained || t1 - drain_start > m_options.drain_limit_s) {
        m_stats.drain_time_s = t1 - drain_start;
        m_stats.backlog_left_positions = m_eroder.unfinished();
        m_stats.path_finished = true;
        done = true;
        m_collision_done.store(true, std::memory_order_release);
      }
    }
  }
  if (!done) m_stats.backlog_left_positions = m_eroder.unfinished();
  // Hand over what is still pending (the render consumer runs until we have exited).
  while (!m_pending.empty()) {
    send_pending();
    if (!m_pending.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  m_collision_exited.store(true, std::memory_order_release);
}

const std::vector<std::vector<SurfaceFace>>& Simulator::render_v_lists() const {
  if (m_running || m_render_chunks.empty()) return m_render_lists;
  // Each chunk is freed as it is appended, so the render copy is never held twice (start()
  // takes the chunks again from the surface).
  m_render_lists.assign(m_render_chunks.size(), {});
  for (std::size_t r = 0; r < m_render_chunks.size(); ++r) {
    std::size_t n = 0;
    for (const auto& c : m_render_chunks[r]) n += c ? c->size() : 0;
    m_render_lists[r].reserve(n);
    for (auto& c : m_render_chunks[r]) {
      if (c) m_render_lists[r].insert(m_render_lists[r].end(), c->begin(), c->end());
      c = nullptr;
    }
  }
  m_render_chunks.clear();
  return m_render_lists;
}

std::vector<std::vector<SurfaceFace>> Simulator::take_render_v_lists() {
  if (m_running) return {};
  bool shared = !m_render_chunks.empty() && m_render_chunks.size() == m_surface.root_count();
  for (std::size_t r = 0; r < m_render_chunks.size() && shared; ++r) {
    shared = m_render_chunks[r].size() <= m_surface.chunk_count(r);
    for (std::size_t c = 0; c < m_surface.chunk_count(r) && shared; ++c)
      shared = (c < m_render_chunks[r].size() ? m_render_chunks[r][c] : nullptr) == m_surface.shared_chunk(r, c);
  }
  if (shared) {
    m_render_chunks.clear();  // the surface then holds the only reference to each list
    return m_surface.take_v_lists();
  }
  (void)render_v_lists();
  return std::move(m_render_lists);
}

void Simulator::take_surface_snapshots(bool final) {
  if (!m_snapshot_fn) return;
  const double now = now_s();
  for (;;) {
    const double t = static_cast<double>(m_next_snapshot) * m_snapshot_period_s;
    if (t > m_snapshot_end_s + 1e-9 * m_snapshot_period_s) return;
    if (!final && now < t) return;
    std::vector<std::vector<SurfaceFace>> lists(m_render_chunks.size());
    for (std::size_t r = 0; r < m_render_chunks.size(); ++r)
      for (const auto& c : m_render_chunks[r])
        if (c) lists[r].insert(lists[r].end(), c->begin(), c->end());
    m_snapshot_fn(t, lists);
    ++m_next_snapshot;
    ++m_stats.surface_snapshots;
  }
}

void Simulator::render_loop() {
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(m_options.render_period_s * 1e9));
  for (;;) {
    // Read the flag before draining: after it is seen set, one more drain gets everything.
    const bool collision_exited = m_collision_exited.load(std::memory_order_acquire);
    while (auto snap = m_snapshots.pop()) {
      auto& sn = **snap;
      for (std::size_t i = 0; i < sn.chunks.size(); ++i) {
        auto& root = m_render_chunks[sn.chunks[i].root];
        if (root.size() < sn.chunk_counts[i]) root.resize(sn.chunk_counts[i]);
        root[sn.chunks[i].chunk] = std::move(sn.lists[i]);
      }
      ++m_stats.render_snapshots;
    }
    if (collision_exited) {
      take_surface_snapshots(true);
      break;
    }
    take_surface_snapshots(false);
    std::this_thread::sleep_for(period);
  }
}

}  // namespace ido::drill

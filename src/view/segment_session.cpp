// SPDX-License-Identifier: Apache-2.0
#include "ido/view/segment_session.h"

#include <chrono>
#include <exception>

#include "ido/core/error.h"
#include "ido/core/progress.h"

namespace ido::view {

const char* segment_stage_name(SegmentStage stage) noexcept {
  switch (stage) {
    case SegmentStage::Idle: return "idle";
    case SegmentStage::Preparing: return "preparing";
    case SegmentStage::Inflating: return "inflating";
    case SegmentStage::Paused: return "paused";
    case SegmentStage::Finishing: return "finishing";
    case SegmentStage::Done: return "done";
    case SegmentStage::Failed: return "failed";
  }
  return "?";
}

/// One run: its controls (atomics written by the render thread) and its hand-over buffer.
struct SegmentSession::Run {
  std::uint64_t id = 0;
  std::vector<Vec3> seeds;
  segment::BalloonOptions options;
  std::atomic<bool> cancel{false};
  std::atomic<bool> paused{false};
  std::atomic<std::int64_t> step_requests{0};
  std::atomic<bool> ended{false};
  Progress progress;  ///< cancelled on retirement: stops Balloon::run() (the edge stage)
  drill::TripleBuffer<std::shared_ptr<const SegmentState>> states;
  std::thread thread;
};

SegmentSession::SegmentSession(std::shared_ptr<const image::Volume<float>> ct)
    : m_ct(std::move(ct)), m_latest(std::make_shared<SegmentState>()) {
  if (!m_ct || m_ct->empty()) throw InvalidInput("segmentation needs a volume");
}

SegmentSession::~SegmentSession() {
  if (m_current) {
    m_current->cancel = true;
    m_retired.push_back(std::move(m_current));
  }
  for (auto& r : m_retired) {
    r->cancel = true;
    r->progress.cancel();
    if (r->thread.joinable()) r->thread.join();
  }
}

void SegmentSession::work(Run& run, const image::Volume<float>& ct) {
  auto publish = [&run](SegmentStage stage, std::int64_t steps, geometry::TriangleMesh surface,
                        std::shared_ptr<const segment::BalloonResult> result = {}, std::string error = {}) {
    auto s = std::make_shared<SegmentState>();
    s->run = run.id;
    s->stage = stage;
    s->steps = steps;
    s->surface = std::move(surface);
    s->seeds_mm = run.seeds;
    s->options = run.options;
    s->result = std::move(result);
    s->error = std::move(error);
    run.states.write(std::shared_ptr<const SegmentState>(std::move(s)));
  };
  std::int64_t steps = 0;
  try {
    publish(SegmentStage::Preparing, 0, {});
    segment::Balloon balloon(ct, run.seeds, run.options);
    publish(run.paused ? SegmentStage::Paused : SegmentStage::Inflating, 0, balloon.surface());
    bool done = false;
    bool pause_shown = run.paused;
    while (!done) {
      if (run.cancel) return;
      if (run.paused) {
        if (run.step_requests.load() <= 0) {
          if (!pause_shown) publish(SegmentStage::Paused, steps, balloon.surface());
          pause_shown = true;
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
          continue;
        }
        run.step_requests.fetch_sub(1);
      } else {
        pause_shown = false;
      }
      done = balloon.step();
      ++steps;
      // A new picture only when the render thread took the previous one (surface() copies the
      // mesh), and always when paused so each single step shows.
      if (!run.states.has_new() || run.paused)
        publish(run.paused ? SegmentStage::Paused : SegmentStage::Inflating, steps, balloon.surface());
    }
    publish(SegmentStage::Finishing, steps, balloon.surface());
    auto result = std::make_shared<segment::BalloonResult>(balloon.run(&run.progress));
    geometry::TriangleMesh surface = result->surface;
    publish(SegmentStage::Done, steps, std::move(surface), std::move(result));
  } catch (const Cancelled&) {
  } catch (const std::exception& e) {
    publish(SegmentStage::Failed, steps, {}, {}, e.what());
  }
}

void SegmentSession::start(std::vector<Vec3> seeds_mm, const segment::BalloonOptions& options, bool paused) {
  if (m_current) {
    m_current->cancel = true;
    m_current->progress.cancel();
    m_retired.push_back(std::move(m_current));
  }
  ++m_runs;
  if (seeds_mm.empty()) {
    auto idle = std::make_shared<SegmentState>();
    idle->run = m_runs;
    m_latest = std::move(idle);
    return;
  }
  auto run = std::make_unique<Run>();
  run->id = m_runs;
  run->seeds = std::move(seeds_mm);
  run->options = options;
  run->paused = paused;
  Run* r = run.get();
  const image::Volume<float>* ct = m_ct.get();
  run->thread = std::thread([r, ct] {
    work(*r, *ct);
    r->ended = true;
  });
  m_current = std::move(run);
  auto preparing = std::make_shared<SegmentState>();
  preparing->run = m_runs;
  preparing->stage = SegmentStage::Preparing;
  preparing->seeds_mm = m_current->seeds;
  preparing->options = m_current->options;
  m_latest = std::move(preparing);
}

void SegmentSession::set_paused(bool paused) {
  if (m_current) m_current->paused = paused;
}

bool SegmentSession::paused() const { return m_current && m_current->paused; }

void SegmentSession::step_once() {
  if (m_current && m_current->paused) m_current->step_requests.fetch_add(1);
}

void SegmentSession::reap() {
  std::erase_if(m_retired, [](std::unique_ptr<Run>& r) {
    if (!r->ended) return false;
    r->thread.join();  // the worker has returned: this does not wait
    return true;
  });
}

std::shared_ptr<const SegmentState> SegmentSession::latest() {
  reap();
  if (m_current && m_current->states.has_new()) {
    const auto& s = m_current->states.read();
    if (s) m_latest = s;
  }
  return m_latest;
}

bool SegmentSession::busy() {
  const auto s = latest();
  if (!m_current) return false;
  if (s->stage == SegmentStage::Paused) return m_current->step_requests.load() > 0;
  return s->stage == SegmentStage::Preparing || s->stage == SegmentStage::Inflating ||
         s->stage == SegmentStage::Finishing;
}

}  // namespace ido::view

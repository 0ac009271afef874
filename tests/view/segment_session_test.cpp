// SPDX-License-Identifier: Apache-2.0
// The balloon on the Segment workspace's worker thread: its result equals segment_balloon()'s
// bit for bit however it was paused, stepped and restarted; a bad seed fails with the balloon's
// message.
#include "ido/view/segment_session.h"

#include <chrono>
#include <memory>
#include <thread>

#include <gtest/gtest.h>

#include "ido/segment/balloon.h"
#include "ido/segment/organ.h"
#include "support/ball_ct.h"
#include "support/test_support.h"

namespace ido {
namespace {

std::shared_ptr<const view::SegmentState> wait_for(view::SegmentSession& s, view::SegmentStage stage) {
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    auto st = s.latest();
    if (st->stage == stage || st->stage == view::SegmentStage::Failed) return st;
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(120)) return st;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void expect_identical(const segment::BalloonResult& a, const segment::BalloonResult& b) {
  EXPECT_TRUE(a.surface.vertices == b.surface.vertices) << "vertex positions differ";
  EXPECT_TRUE(a.surface.triangles == b.surface.triangles);
  EXPECT_EQ(a.report.iterations, b.report.iterations);
  EXPECT_EQ(a.report.stop_reason, b.report.stop_reason);
}

TEST(SegmentSession, LiveBalloonEqualsOneCallSegmentation) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  const std::vector<Vec3> seeds = {ct->index_to_world(Vec3(16, 15, 14))};
  const segment::BalloonOptions options = segment::organ_options(segment::Organ::Generic);
  const segment::BalloonResult expected = segment::segment_balloon(*ct, seeds, options);

  view::SegmentSession session(ct);
  EXPECT_EQ(session.latest()->stage, view::SegmentStage::Idle);
  session.start(seeds, options);
  const auto done = wait_for(session, view::SegmentStage::Done);
  ASSERT_EQ(done->stage, view::SegmentStage::Done) << done->error;
  ASSERT_TRUE(done->result);
  expect_identical(*done->result, expected);
  EXPECT_TRUE(done->surface.vertices == expected.surface.vertices);
  EXPECT_GT(done->steps, 10);
  EXPECT_FALSE(session.busy());
}

TEST(SegmentSession, PausedSteppedAndRestartedRunsGiveTheSameResult) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  const std::vector<Vec3> seeds = {ct->index_to_world(Vec3(13, 17, 12))};
  const segment::BalloonOptions options = segment::organ_options(segment::Organ::Generic);
  const segment::BalloonResult expected = segment::segment_balloon(*ct, seeds, options);

  view::SegmentSession session(ct);
  // A run started elsewhere and retired at once (a seed placed, then undone) does not disturb the next.
  session.start({ct->index_to_world(Vec3(2, 2, 2))}, options);
  session.start(seeds, options, /*paused=*/true);
  EXPECT_TRUE(session.paused());
  auto st = wait_for(session, view::SegmentStage::Paused);
  ASSERT_EQ(st->stage, view::SegmentStage::Paused);
  EXPECT_EQ(st->steps, 0);
  for (int i = 0; i < 3; ++i) session.step_once();
  for (auto t0 = std::chrono::steady_clock::now();
       session.latest()->steps < 3 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60);)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  st = session.latest();
  EXPECT_EQ(st->steps, 3);
  EXPECT_EQ(st->seeds_mm, seeds);
  EXPECT_FALSE(st->surface.triangles.empty());
  session.set_paused(false);
  const auto done = wait_for(session, view::SegmentStage::Done);
  ASSERT_EQ(done->stage, view::SegmentStage::Done) << done->error;
  expect_identical(*done->result, expected);
  // No seed: back to idle.
  session.start({}, options);
  EXPECT_EQ(session.latest()->stage, view::SegmentStage::Idle);
}

TEST(SegmentSession, ABadSeedFailsWithTheBalloonsMessage) {
  const auto ct = std::make_shared<const image::Volume<float>>(test::ball_ct());
  view::SegmentSession session(ct);
  session.start({Vec3(1e4, 0, 0)}, {});
  const auto st = wait_for(session, view::SegmentStage::Done);
  EXPECT_EQ(st->stage, view::SegmentStage::Failed);
  EXPECT_FALSE(st->error.empty());
}

}  // namespace
}  // namespace ido

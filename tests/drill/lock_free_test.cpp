// SPDX-License-Identifier: Apache-2.0
// The lock-free hand-offs, one thread at a time (threads_test runs them across threads): the
// triple buffer gives the latest complete value and says when one is new; the ring holds N
// items in order, refuses the (N+1)th without touching it, and wraps around.
#include "ido/drill/lock_free.h"

#include <memory>
#include <string>

#include <gtest/gtest.h>

namespace ido::drill {
namespace {

TEST(TripleBuffer, ReaderGetsTheLatestWriteAndKnowsWhenItIsNew) {
  TripleBuffer<std::string> b(std::string("initial"));
  EXPECT_FALSE(b.has_new());
  EXPECT_EQ(b.read(), "initial");
  b.write("one");
  EXPECT_TRUE(b.has_new());
  EXPECT_EQ(b.read(), "one");
  EXPECT_FALSE(b.has_new());
  EXPECT_EQ(b.read(), "one") << "nothing new: the same value again";
  // Several writes between two reads: only the last is seen, none is torn or stale.
  for (int i = 0; i < 100; ++i) b.write("v" + std::to_string(i));
  EXPECT_TRUE(b.has_new());
  EXPECT_EQ(b.read(), "v99");
  // Alternating many times cycles the three slots without losing the latest.
  for (int i = 0; i < 1000; ++i) {
    b.write(std::to_string(i));
    if (i % 3 == 0) {
      EXPECT_EQ(b.read(), std::to_string(i));
    }
  }
  EXPECT_EQ(b.read(), "999");
  // Default construction holds value-initialised slots.
  TripleBuffer<int> zero;
  EXPECT_EQ(zero.read(), 0);
  EXPECT_FALSE(zero.has_new());
}

TEST(SpscRing, HoldsNInOrderRefusesMoreAndWrapsAround) {
  SpscRing<int, 8> ring;
  EXPECT_FALSE(ring.pop().has_value());
  int next_in = 0, next_out = 0;
  // Fill to capacity: the 9th push fails and leaves its value alone.
  for (int i = 0; i < 8; ++i) {
    int v = next_in++;
    ASSERT_TRUE(ring.push(v));
  }
  int extra = 1234;
  EXPECT_FALSE(ring.push(extra));
  EXPECT_EQ(extra, 1234);
  // Drain half, refill, many times round: FIFO order throughout, the indices wrapping.
  for (int round = 0; round < 100; ++round) {
    for (int k = 0; k < 5; ++k) {
      const auto v = ring.pop();
      ASSERT_TRUE(v.has_value());
      ASSERT_EQ(*v, next_out++);
    }
    for (int k = 0; k < 5; ++k) {
      int v = next_in++;
      ASSERT_TRUE(ring.push(v));
    }
    int more = -1;
    ASSERT_FALSE(ring.push(more)) << "full again after each refill";
  }
  while (const auto v = ring.pop()) ASSERT_EQ(*v, next_out++);
  EXPECT_EQ(next_out, next_in);
}

TEST(SpscRing, MovesItemsInAndOutAndKeepsARefusedOne) {
  SpscRing<std::unique_ptr<int>, 2> ring;
  auto a = std::make_unique<int>(1), b = std::make_unique<int>(2), c = std::make_unique<int>(3);
  ASSERT_TRUE(ring.push(a));
  ASSERT_TRUE(ring.push(b));
  EXPECT_EQ(a, nullptr) << "moved into the ring";
  EXPECT_FALSE(ring.push(c));
  ASSERT_NE(c, nullptr) << "a refused item stays with the producer";
  EXPECT_EQ(*c, 3);
  auto first = ring.pop();
  ASSERT_TRUE(first.has_value());
  ASSERT_NE(*first, nullptr);
  EXPECT_EQ(**first, 1);
  ASSERT_TRUE(ring.push(c));
  EXPECT_EQ(**ring.pop(), 2);
  EXPECT_EQ(**ring.pop(), 3);
  EXPECT_FALSE(ring.pop().has_value());
}

}  // namespace
}  // namespace ido::drill

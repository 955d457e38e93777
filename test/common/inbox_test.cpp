#include "common/inbox.hpp"

#include <gtest/gtest.h>

#include <string>

namespace alight {
namespace {

TEST(InboxTest, DeliversEverySourceInOneArrivalOrder) {
  Inbox<std::string> inbox;
  const size_t frames = inbox.add_source(10), poses = inbox.add_source(10);
  ASSERT_TRUE(inbox.push(poses, "p1"));
  ASSERT_TRUE(inbox.push(frames, "f1"));
  ASSERT_TRUE(inbox.push(poses, "p2"));
  std::string order;
  while (auto m = inbox.pop()) order += m->second + (m->first == frames ? "F " : "P ");
  EXPECT_EQ(order, "p1P f1F p2P ");
  EXPECT_EQ(inbox.size(), 0u);
}

TEST(InboxTest, AFullSourceRefusesTheNewestAndCountsIt) {
  Inbox<int> inbox;
  const size_t frames = inbox.add_source(3), poses = inbox.add_source(100);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(inbox.push(frames, i), i < 3) << i;
  // Another source is not held back by a full one.
  EXPECT_TRUE(inbox.push(poses, 100));
  EXPECT_EQ(inbox.dropped(frames), 2u);
  EXPECT_EQ(inbox.dropped(poses), 0u);
  EXPECT_EQ(inbox.waiting(frames), 3u);
  // Room again once one is taken: the waiting ones keep their order, none comes twice.
  EXPECT_EQ(inbox.pop()->second, 0);
  EXPECT_TRUE(inbox.push(frames, 5));
  std::vector<int> rest;
  while (auto m = inbox.pop()) rest.push_back(m->second);
  EXPECT_EQ(rest, (std::vector<int>{1, 2, 100, 5}));
}

// Property: whatever the pattern of pushes and pops, every item pushed is either delivered
// exactly once, in push order, or counted as dropped, and a source never holds more than its
// capacity.
TEST(InboxTest, EveryItemIsDeliveredOnceInOrderOrCountedDropped) {
  Inbox<int> inbox;
  const size_t a = inbox.add_source(4), b = inbox.add_source(1);
  uint32_t lcg = 12345;
  const auto next = [&] { return (lcg = lcg * 1664525u + 1013904223u) >> 16; };
  int pushed = 0, delivered = 0, last = -1;
  for (int step = 0; step < 10000; ++step) {
    if (next() % 3 != 0) {
      inbox.push(next() % 2 ? a : b, pushed++);
    } else if (auto m = inbox.pop()) {
      EXPECT_GT(m->second, last);
      last = m->second;
      ++delivered;
    }
    ASSERT_LE(inbox.waiting(a), 4u);
    ASSERT_LE(inbox.waiting(b), 1u);
  }
  while (auto m = inbox.pop()) ++delivered;
  EXPECT_GT(inbox.dropped(a) + inbox.dropped(b), 0u);
  EXPECT_EQ(static_cast<uint64_t>(delivered) + inbox.dropped(a) + inbox.dropped(b),
            static_cast<uint64_t>(pushed));
}

}  // namespace
}  // namespace alight

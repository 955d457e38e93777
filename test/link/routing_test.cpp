// What alight-link sends when: the newest message of a channel, a bounded queue where every
// message counts, channels taking turns, rate limits that hold the newest; and what it takes
// from the peer.

#include "link/routing.hpp"

#include <gtest/gtest.h>

namespace alight::link {
namespace {

std::vector<uint8_t> msg(uint8_t v) { return {v}; }

TEST(LinkRateLimit, KeepsTheAverageRateWithoutBurstingAfterAPause) {
  RateLimit r(10.0);  // 100 ms
  EXPECT_TRUE(r.allows(0));
  r.sent(0);
  EXPECT_FALSE(r.allows(99'999));
  EXPECT_TRUE(r.allows(100'000));
  // Sent 30 ms late: the schedule stays (next at 200 ms), so the average is still 10 Hz.
  r.sent(130'000);
  EXPECT_EQ(r.next_allowed_us(), 200'000);
  // A long pause, then one message: the next waits a whole period, no catching up.
  r.sent(5'000'000);
  EXPECT_EQ(r.next_allowed_us(), 5'100'000);
  RateLimit none;
  EXPECT_FALSE(none.limited());
  none.sent(0);
  EXPECT_TRUE(none.allows(0));
}

TEST(LinkOutbox, ANewerMessageReplacesTheWaitingOne) {
  Outbox o;
  o.add_channel("CAMERA", SendMode::kNewest);
  for (uint8_t i = 1; i <= 3; ++i) o.offer("CAMERA", msg(i));
  EXPECT_EQ(o.waiting(), 1u);
  const auto item = o.next(0);
  ASSERT_TRUE(item);
  EXPECT_EQ(item->channel, "CAMERA");
  EXPECT_EQ(item->payload, msg(3));
  EXPECT_FALSE(o.next(0));
  EXPECT_EQ(o.stats("CAMERA").superseded, 2u);
  EXPECT_EQ(o.stats("CAMERA").sent, 1u);
  EXPECT_EQ(o.stats("CAMERA").offered, 3u);
}

TEST(LinkOutbox, EveryMessageWaitsInOrderUpToTheCapacity) {
  Outbox o;
  o.add_channel("NODE_STATUS", SendMode::kEvery, 3);
  for (uint8_t i = 1; i <= 5; ++i) o.offer("NODE_STATUS", msg(i));
  EXPECT_EQ(o.stats("NODE_STATUS").overflowed, 2u);
  for (uint8_t i = 3; i <= 5; ++i) {
    const auto item = o.next(0);
    ASSERT_TRUE(item);
    EXPECT_EQ(item->payload, msg(i)) << "the oldest went, the rest keep their order";
  }
  EXPECT_FALSE(o.next(0));
}

TEST(LinkOutbox, ChannelsTakeTurns) {
  Outbox o;
  o.add_channel("NODE_STATUS", SendMode::kEvery, 10);
  o.add_channel("CAMERA", SendMode::kNewest);
  o.add_channel("AUTONOMY_STATUS", SendMode::kNewest);
  for (uint8_t i = 0; i < 4; ++i) o.offer("NODE_STATUS", msg(i));
  o.offer("CAMERA", msg(10));
  o.offer("AUTONOMY_STATUS", msg(20));
  std::vector<std::string> order;
  while (auto item = o.next(0)) order.push_back(item->channel);
  const std::vector<std::string> expected = {"NODE_STATUS", "CAMERA",      "AUTONOMY_STATUS",
                                             "NODE_STATUS", "NODE_STATUS", "NODE_STATUS"};
  EXPECT_EQ(order, expected);
}

TEST(LinkOutbox, ARateHoldsTheNewestUntilItsTurnAndSaysWhen) {
  Outbox o;
  o.add_channel("CAMERA", SendMode::kNewest, 1, 2.0);  // 500 ms
  o.add_channel("AUTONOMY_STATUS", SendMode::kNewest);
  o.offer("CAMERA", msg(1));
  ASSERT_TRUE(o.next(0));
  EXPECT_FALSE(o.next_due_us(0)) << "nothing waits";
  o.offer("CAMERA", msg(2));
  o.offer("AUTONOMY_STATUS", msg(9));
  const auto status = o.next(100'000);
  ASSERT_TRUE(status);
  EXPECT_EQ(status->channel, "AUTONOMY_STATUS") << "the held camera does not block others";
  EXPECT_FALSE(o.next(100'000));
  ASSERT_TRUE(o.next_due_us(100'000));
  EXPECT_EQ(*o.next_due_us(100'000), 500'000);
  o.offer("CAMERA", msg(3));
  EXPECT_FALSE(o.next(499'999));
  const auto camera = o.next(500'000);
  ASSERT_TRUE(camera);
  EXPECT_EQ(camera->payload, msg(3));
  EXPECT_EQ(o.stats("CAMERA").superseded, 1u);
}

TEST(LinkOutbox, ClearDropsWhatWaitsAndCountsIt) {
  Outbox o;
  o.add_channel("CAMERA", SendMode::kNewest);
  o.add_channel("NODE_STATUS", SendMode::kEvery, 8);
  o.offer("CAMERA", msg(1));
  o.offer("NODE_STATUS", msg(1));
  o.offer("NODE_STATUS", msg(2));
  o.clear();
  EXPECT_EQ(o.waiting(), 0u);
  EXPECT_FALSE(o.next(0));
  EXPECT_EQ(o.total().discarded, 3u);
  EXPECT_EQ(o.total().offered, 3u);
  EXPECT_EQ(o.stats("NOT_A_CHANNEL").offered, 0u);
}

TEST(LinkReceiveFilter, OnlyListedChannelsWithinTheirRate) {
  ReceiveFilter f;
  f.allow("OPERATOR_CMD");
  f.allow("MOCAP_POSE", 10.0);
  EXPECT_EQ(f.check("POSITION_SETPOINT", 0), Admit::kNotListed);
  EXPECT_FALSE(f.allowed("POSITION_SETPOINT"));
  for (int i = 0; i < 100; ++i) EXPECT_EQ(f.check("OPERATOR_CMD", 0), Admit::kAccepted);
  EXPECT_EQ(f.check("MOCAP_POSE", 0), Admit::kAccepted);
  EXPECT_EQ(f.check("MOCAP_POSE", 50'000), Admit::kOverRate);
  EXPECT_EQ(f.check("MOCAP_POSE", 100'000), Admit::kAccepted);
  EXPECT_STREQ(admit_name(Admit::kNotListed), "not a --receive channel");
}

}  // namespace
}  // namespace alight::link

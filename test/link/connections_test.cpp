// Which connections the vehicle's link keeps while strangers connect, and the ground's retries.

#include "link/connections.hpp"

#include <gtest/gtest.h>

namespace alight::link {
namespace {

TEST(LinkAdmission, StrangersPushEachOtherOutNotTheNewcomer) {
  Admission a(3, 5'000'000);
  EXPECT_FALSE(a.add(1, 0));
  EXPECT_FALSE(a.add(2, 10));
  EXPECT_FALSE(a.add(3, 20));
  // A fourth pushes out the oldest; the newest always gets its chance to authenticate.
  EXPECT_EQ(a.add(4, 30), std::optional<uint64_t>(1));
  EXPECT_EQ(a.pending(), 3u);
  EXPECT_FALSE(a.is_pending(1));
  EXPECT_TRUE(a.is_pending(4));
  EXPECT_FALSE(a.authenticated(4));
  EXPECT_EQ(a.session(), std::optional<uint64_t>(4));
  EXPECT_EQ(a.pending(), 2u);
}

TEST(LinkAdmission, HandshakesExpireAndANewSessionReplacesTheOld) {
  Admission a(kMaxPendingHandshakes, 1'000'000);
  a.add(1, 0);
  a.add(2, 600'000);
  EXPECT_EQ(a.next_expiry_us(), std::optional<int64_t>(1'000'000));
  EXPECT_TRUE(a.expired(1'000'000).empty());
  EXPECT_EQ(a.expired(1'000'001), std::vector<uint64_t>{1});
  a.remove(1);
  EXPECT_FALSE(a.authenticated(2));
  EXPECT_FALSE(a.next_expiry_us()) << "a session does not expire as a handshake";
  a.add(3, 2'000'000);
  EXPECT_EQ(a.authenticated(3), std::optional<uint64_t>(2));
  a.remove(3);
  EXPECT_FALSE(a.session());
}

TEST(LinkBackoff, DoublesUpToItsMaximumAndStartsAgainAfterASession) {
  Backoff b(200, 1000);
  EXPECT_EQ(b.failed(), 200);
  EXPECT_EQ(b.failed(), 400);
  EXPECT_EQ(b.failed(), 800);
  EXPECT_EQ(b.failed(), 1000);
  EXPECT_EQ(b.failed(), 1000);
  b.succeeded();
  EXPECT_EQ(b.failed(), 200);
}

}  // namespace
}  // namespace alight::link

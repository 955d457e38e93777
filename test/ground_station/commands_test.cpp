// Command requests from the page: parsing, signing with increasing seq, and who may send them.

#include "ground_station/commands.hpp"

#include <gtest/gtest.h>

#include "common/operator_auth.hpp"

namespace alight::ground_station {
namespace {

OperatorKey key() { return OperatorKey{std::vector<uint8_t>(32, 0x5a)}; }

TEST(ParseCommandTest, AcceptsEveryCommandWithItsFields) {
  auto go = parse_command_request({{"command", "go"}, {"mission", "ingress"}}, 1.0);
  ASSERT_TRUE(go.request) << go.error;
  EXPECT_EQ(go.request->command, operator_cmd_t::CMD_GO);
  EXPECT_EQ(go.request->mission, 2);
  EXPECT_EQ(
      parse_command_request({{"command", "go"}, {"mission", "landing"}}, 1.0).request->mission, 1);
  for (const char* name : {"takeoff", "abort", "land_here"}) {
    auto p = parse_command_request({{"command", name}}, 1.0);
    ASSERT_TRUE(p.request) << name << ": " << p.error;
    EXPECT_STREQ(command_name(p.request->command), name);
  }
  auto kill = parse_command_request({{"command", "kill"}, {"confirm", "kill"}}, 1.0);
  ASSERT_TRUE(kill.request);
  EXPECT_EQ(kill.request->command, operator_cmd_t::CMD_KILL);
  auto nudge = parse_command_request({{"command", "nudge"}, {"dx", "0.1"}, {"dz", "-0.2"}}, 0.5);
  ASSERT_TRUE(nudge.request) << nudge.error;
  EXPECT_DOUBLE_EQ(nudge.request->nudge_W[0], 0.1);
  EXPECT_DOUBLE_EQ(nudge.request->nudge_W[1], 0.0);
  EXPECT_DOUBLE_EQ(nudge.request->nudge_W[2], -0.2);
}

TEST(ParseCommandTest, RefusesMalformedRequests) {
  EXPECT_FALSE(parse_command_request({}, 1.0).request);
  EXPECT_FALSE(parse_command_request({{"command", "selfdestruct"}}, 1.0).request);
  EXPECT_FALSE(parse_command_request({{"command", "go"}}, 1.0).request);
  EXPECT_FALSE(parse_command_request({{"command", "go"}, {"mission", "moon"}}, 1.0).request);
  // Kill without its confirmation.
  const auto kill = parse_command_request({{"command", "kill"}}, 1.0);
  EXPECT_FALSE(kill.request);
  EXPECT_NE(kill.error.find("confirm"), std::string::npos);
  EXPECT_FALSE(parse_command_request({{"command", "kill"}, {"confirm", "yes"}}, 1.0).request);
  // Nudges beyond the limit or not numbers.
  EXPECT_FALSE(parse_command_request({{"command", "nudge"}, {"dx", "2"}}, 1.0).request);
  EXPECT_FALSE(parse_command_request({{"command", "nudge"}, {"dy", "nan"}}, 1.0).request);
  EXPECT_FALSE(parse_command_request({{"command", "nudge"}, {"dz", "0.1m"}}, 1.0).request);
  EXPECT_FALSE(parse_command_request({{"command", "nudge"}, {"dz", ""}}, 1.0).request);
}

constexpr int64_t kCommandSession = 77;

TEST(CommandBuilderTest, SignsCommandsThatTheVerifierAccepts) {
  CommandBuilder builder("gs-test", key(), "uav-1");
  CommandVerifier verifier(key(), "uav-1", kCommandSession);
  const int64_t now = 1'700'000'000'000'000;
  CommandRequest go{operator_cmd_t::CMD_GO, 1, {9, 9, 9}};
  const operator_cmd_t a = builder.build(go, kCommandSession, now);
  EXPECT_EQ(a.sender, "gs-test");
  EXPECT_EQ(a.vehicle_id, "uav-1");
  EXPECT_EQ(a.session, kCommandSession);
  EXPECT_EQ(a.utime, now);
  EXPECT_EQ(a.nudge_W[0], 0.0);  // only nudges carry an offset
  EXPECT_EQ(verifier.check(a, now).reason, CommandVerdict::Reason::kNone);
  // Two commands in the same microsecond still get increasing seq.
  const operator_cmd_t b = builder.build({operator_cmd_t::CMD_ABORT, 0, {}}, kCommandSession, now);
  EXPECT_GT(b.seq, a.seq);
  EXPECT_EQ(b.mission, 0);
  EXPECT_EQ(verifier.check(b, now).reason, CommandVerdict::Reason::kNone);
}

TEST(CommandBuilderTest, SeqIncreasesAcrossGroundStationRestarts) {
  const int64_t t0 = 1'700'000'000'000'000;
  CommandVerifier verifier(key(), "uav-1", kCommandSession);
  CommandBuilder first("gs", key(), "uav-1");
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(
        verifier
            .check(first.build({operator_cmd_t::CMD_ABORT, 0, {}}, kCommandSession, t0), t0 + 10)
            .accepted());
  // A restarted station (fresh builder) one second later is not taken for a replay.
  CommandBuilder second("gs", key(), "uav-1");
  EXPECT_TRUE(
      verifier
          .check(second.build({operator_cmd_t::CMD_ABORT, 0, {}}, kCommandSession, t0 + 1'000'000),
                 t0 + 1'000'000)
          .accepted());
}

// --- acknowledgement -------------------------------------------------------------------------

autonomy_status_t command_status(int64_t session, int64_t last_cmd_seq, int32_t rejected = 0,
                                 int64_t last_rejected_seq = -1, int8_t reason = 0) {
  autonomy_status_t st{};
  st.vehicle_id = "uav-1";
  st.cmd_session = session;
  st.last_cmd_seq = last_cmd_seq;
  st.cmds_rejected = rejected;
  st.last_rejected_seq = last_rejected_seq;
  st.last_reject_reason = reason;
  return st;
}

// Regression (issue 14): a KILL with no vehicle listening showed "sent", nothing more. Now it
// turns NOT ACKNOWLEDGED once the deadline passes without AUTONOMY_STATUS echoing it.
TEST(CommandTrackerRegression, KillWithNoVehicleListeningRaisesTheAlarm) {
  CommandTracker tracker(1.0);
  const int64_t t0 = 5'000'000;
  tracker.sent("kill", 1001, kCommandSession, t0);
  const TrackedCommand& kill = tracker.commands().back();
  EXPECT_EQ(tracker.state_at(kill, t0 + 999'999), AckState::kSent);
  EXPECT_EQ(tracker.alarm(t0 + 999'999), nullptr);
  EXPECT_EQ(tracker.state_at(kill, t0 + 1'000'001), AckState::kNotAcknowledged);
  ASSERT_NE(tracker.alarm(t0 + 1'000'001), nullptr);
  EXPECT_EQ(tracker.alarm(t0 + 1'000'001)->name, "kill");
  EXPECT_STREQ(ack_state_name(tracker.state_at(kill, t0 + 2'000'000)), "not_acknowledged");
}

TEST(CommandTrackerTest, EchoedSeqAcknowledgesAndALateEchoStillCounts) {
  CommandTracker tracker(1.0);
  tracker.on_status(command_status(kCommandSession, -1), 0);
  tracker.sent("go", 2000, kCommandSession, 100);
  tracker.on_status(command_status(kCommandSession, -1), 50'000);  // not yet
  EXPECT_EQ(tracker.state_at(tracker.commands().back(), 60'000), AckState::kSent);
  tracker.on_status(command_status(kCommandSession, 2000), 120'000);
  const TrackedCommand& go = tracker.commands().back();
  EXPECT_EQ(tracker.state_at(go, 5'000'000), AckState::kAcknowledged);
  EXPECT_EQ(go.answered_utime, 120'000);
  EXPECT_EQ(tracker.alarm(5'000'000), nullptr);

  tracker.sent("abort", 2001, kCommandSession, 6'000'000);
  EXPECT_NE(tracker.alarm(7'500'000), nullptr);  // overdue
  tracker.on_status(command_status(kCommandSession, 2001), 7'600'000);
  EXPECT_EQ(tracker.alarm(7'600'000), nullptr);  // answered late: the alarm clears
}

TEST(CommandTrackerTest, RejectionIsShownWithItsReason) {
  CommandTracker tracker(1.0);
  tracker.sent("go", 3000, kCommandSession, 0);
  tracker.on_status(command_status(kCommandSession, -1, 1, 3000, autonomy_status_t::REJECT_STALE),
                    10'000);
  const TrackedCommand& go = tracker.commands().back();
  EXPECT_EQ(tracker.state_at(go, 10'000), AckState::kRejected);
  EXPECT_NE(go.reject_reason.find("stale"), std::string::npos);
}

TEST(CommandTrackerTest, ALaterEchoAcknowledgesAnEarlierCommandOnlyWhenNothingWasRejected) {
  CommandTracker tracker(1.0);
  tracker.on_status(command_status(kCommandSession, -1, 4), 0);
  tracker.sent("nudge", 10, kCommandSession, 100);
  tracker.sent("nudge", 11, kCommandSession, 200);
  // Only seq 11 was echoed, and the rejection count is unchanged: 10 was accepted before it.
  tracker.on_status(command_status(kCommandSession, 11, 4), 50'000);
  EXPECT_EQ(tracker.state_at(tracker.commands()[0], 60'000), AckState::kAcknowledged);
  EXPECT_EQ(tracker.state_at(tracker.commands()[1], 60'000), AckState::kAcknowledged);

  // The same with one rejection in between: it may have been ours; never guessed.
  CommandTracker other(1.0);
  other.on_status(command_status(kCommandSession, -1, 4), 0);
  other.sent("nudge", 10, kCommandSession, 100);
  other.sent("nudge", 11, kCommandSession, 200);
  other.on_status(command_status(kCommandSession, 11, 5, 999), 50'000);
  EXPECT_EQ(other.state_at(other.commands()[0], 2'000'000), AckState::kNotAcknowledged);
  EXPECT_EQ(other.state_at(other.commands()[1], 2'000'000), AckState::kAcknowledged);
}

TEST(CommandTrackerTest, AnswersOfAnotherSessionAcknowledgeNothing) {
  // autonomy restarted (new session) and happens to echo an equal seq: not ours.
  CommandTracker tracker(1.0);
  tracker.sent("go", 42, kCommandSession, 0);
  tracker.on_status(command_status(kCommandSession + 1, 42), 10'000);
  EXPECT_EQ(tracker.state_at(tracker.commands().back(), 2'000'000), AckState::kNotAcknowledged);
}

TEST(CommandTrackerTest, KeepsABoundedHistory) {
  CommandTracker tracker(1.0, 5);
  for (int i = 0; i < 50; ++i) tracker.sent("abort", i, kCommandSession, i);
  EXPECT_EQ(tracker.commands().size(), 5u);
  EXPECT_EQ(tracker.commands().front().seq, 45);
}

TEST(LoopbackTest, RecognisesLoopbackAddresses) {
  for (const char* a : {"127.0.0.1", "127.1.2.3", "localhost", "LOCALHOST", "::1", "[::1]"})
    EXPECT_TRUE(is_loopback_address(a)) << a;
  for (const char* a : {"0.0.0.0", "192.168.1.10", "10.0.0.1", "::", "128.0.0.1", "127.0.0.1x",
                        "127.0.0.256", "example.com", ""})
    EXPECT_FALSE(is_loopback_address(a)) << a;
}

using Headers = std::multimap<std::string, std::string>;

// Regression (issue 14): on 127.0.0.1 no token was asked, so any web page the operator's
// browser opened could post commands (a form needs no script). Now the token is required there
// too, in a custom header that a cross-site form cannot set.
TEST(AccessRegression, LoopbackCommandsNeedTheTokenToo) {
  const std::string token = "0123456789abcdef0123456789abcdef";
  const AccessPolicy p = policy_for_bind("127.0.0.1", token);
  EXPECT_TRUE(p.require_token);
  EXPECT_EQ(check_command_access(p, {{"Host", "127.0.0.1:8080"}}), Access::kMissingToken);
  // What a cross-site <form method=post> can send: no custom header.
  EXPECT_EQ(check_command_access(p, {{"Host", "127.0.0.1:8080"},
                                     {"Content-Type", "application/x-www-form-urlencoded"}}),
            Access::kMissingToken);
  EXPECT_EQ(check_command_access(p, {{"Host", "127.0.0.1:8080"}, {"X-Alight-Token", token}}),
            Access::kAllowed);
}

TEST(AccessTest, LoopbackNeedsALoopbackHost) {
  const std::string token = "0123456789abcdef0123456789abcdef";
  const AccessPolicy p = policy_for_bind("127.0.0.1", token);
  EXPECT_EQ(check_command_access(p, {{"host", "localhost:8080"},
                                     {"Origin", "http://localhost:8080"},
                                     {"X-Alight-Token", token}}),
            Access::kAllowed);
  // DNS rebinding: a name that resolves to 127.0.0.1 but is not ours.
  EXPECT_EQ(check_command_access(p, {{"Host", "evil.example:8080"}, {"X-Alight-Token", token}}),
            Access::kBadHost);
  EXPECT_EQ(check_command_access(p, {}), Access::kBadHost);
  // A page from another site posting to the station (CSRF).
  EXPECT_EQ(check_command_access(p, {{"Host", "127.0.0.1:8080"},
                                     {"Origin", "https://evil.example"},
                                     {"X-Alight-Token", token}}),
            Access::kCrossOrigin);
}

TEST(AccessTest, NonLoopbackBindRefusesRequestsWithoutTheToken) {
  const std::string token = "0123456789abcdef0123456789abcdef";
  for (const char* bind : {"0.0.0.0", "192.168.1.10", "::"}) {
    const AccessPolicy p = policy_for_bind(bind, token);
    EXPECT_TRUE(p.require_token) << bind;
    const Headers host{{"Host", "192.168.1.10:8080"}};
    EXPECT_EQ(check_command_access(p, host), Access::kMissingToken) << bind;
    Headers empty = host;
    empty.emplace("X-Alight-Token", "");
    EXPECT_EQ(check_command_access(p, empty), Access::kMissingToken);
    Headers wrong = host;
    wrong.emplace("X-Alight-Token", "0123456789abcdef0123456789abcdee");
    EXPECT_EQ(check_command_access(p, wrong), Access::kBadToken);
    Headers shorter = host;
    shorter.emplace("X-Alight-Token", "0123456789abcdef");
    EXPECT_EQ(check_command_access(p, shorter), Access::kBadToken);
    Headers right = host;
    right.emplace("x-alight-token", token);  // header names are case-insensitive
    EXPECT_EQ(check_command_access(p, right), Access::kAllowed);
    // The token does not excuse a cross-site request.
    right.emplace("Origin", "http://evil.example");
    EXPECT_EQ(check_command_access(p, right), Access::kCrossOrigin);
  }
}

TEST(HexTest, FormatsBytes) {
  const uint8_t b[] = {0x00, 0x0f, 0xa5, 0xff};
  EXPECT_EQ(to_hex(b, 4), "000fa5ff");
}

}  // namespace
}  // namespace alight::ground_station

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

TEST(CommandBuilderTest, SignsCommandsThatTheVerifierAccepts) {
  CommandBuilder builder("gs-test", key());
  CommandVerifier verifier(key());
  const int64_t now = 1'700'000'000'000'000;
  CommandRequest go{operator_cmd_t::CMD_GO, 1, {9, 9, 9}};
  const operator_cmd_t a = builder.build(go, now);
  EXPECT_EQ(a.sender, "gs-test");
  EXPECT_EQ(a.utime, now);
  EXPECT_EQ(a.nudge_W[0], 0.0);  // only nudges carry an offset
  EXPECT_EQ(verifier.check(a, now).reason, CommandVerdict::Reason::kAccepted);
  // Two commands in the same microsecond still get increasing seq.
  const operator_cmd_t b = builder.build({operator_cmd_t::CMD_ABORT, 0, {}}, now);
  EXPECT_GT(b.seq, a.seq);
  EXPECT_EQ(b.mission, 0);
  EXPECT_EQ(verifier.check(b, now).reason, CommandVerdict::Reason::kAccepted);
}

TEST(CommandBuilderTest, SeqIncreasesAcrossGroundStationRestarts) {
  const int64_t t0 = 1'700'000'000'000'000;
  CommandVerifier verifier(key());
  CommandBuilder first("gs", key());
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(
        verifier.check(first.build({operator_cmd_t::CMD_ABORT, 0, {}}, t0), t0 + 10).accepted());
  // A restarted station (fresh builder) one second later is not taken for a replay.
  CommandBuilder second("gs", key());
  EXPECT_TRUE(
      verifier
          .check(second.build({operator_cmd_t::CMD_ABORT, 0, {}}, t0 + 1'000'000), t0 + 1'000'000)
          .accepted());
}

TEST(LoopbackTest, RecognisesLoopbackAddresses) {
  for (const char* a : {"127.0.0.1", "127.1.2.3", "localhost", "LOCALHOST", "::1", "[::1]"})
    EXPECT_TRUE(is_loopback_address(a)) << a;
  for (const char* a : {"0.0.0.0", "192.168.1.10", "10.0.0.1", "::", "128.0.0.1", "127.0.0.1x",
                        "127.0.0.256", "example.com", ""})
    EXPECT_FALSE(is_loopback_address(a)) << a;
}

using Headers = std::multimap<std::string, std::string>;

TEST(AccessTest, LoopbackNeedsNoTokenButALoopbackHost) {
  const AccessPolicy p = policy_for_bind("127.0.0.1", "0123456789abcdef0123456789abcdef");
  EXPECT_FALSE(p.require_token);
  EXPECT_EQ(check_command_access(p, {{"Host", "127.0.0.1:8080"}}), Access::kAllowed);
  EXPECT_EQ(
      check_command_access(p, {{"host", "localhost:8080"}, {"Origin", "http://localhost:8080"}}),
      Access::kAllowed);
  // DNS rebinding: a name that resolves to 127.0.0.1 but is not ours.
  EXPECT_EQ(check_command_access(p, {{"Host", "evil.example:8080"}}), Access::kBadHost);
  EXPECT_EQ(check_command_access(p, {}), Access::kBadHost);
  // A page from another site posting to the station (CSRF).
  EXPECT_EQ(
      check_command_access(p, {{"Host", "127.0.0.1:8080"}, {"Origin", "https://evil.example"}}),
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

// alight-mavlink's LCM conversions: the validating ones refuse what must never become a setpoint.
#include "mavlink/bridge_msgs.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace alight::mavlink {
namespace {

TEST(BridgeMsgsTest, AttitudeCommandsWithNonFiniteOrAbsurdValuesAreRefused) {
  attitude_cmd_t m{};
  m.utime = 5;
  m.roll_rad = 0.1;
  m.thrust_N = 12;
  m.armed = true;
  std::string why;
  const auto t = attitude_from_msg(m, &why);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->utime, 5);
  EXPECT_EQ(t->roll_rad, 0.1);
  EXPECT_TRUE(t->armed);
  auto bad = m;
  bad.pitch_rad = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(attitude_from_msg(bad, &why));
  bad = m;
  bad.thrust_N = -1;
  EXPECT_FALSE(attitude_from_msg(bad, &why));
  bad = m;
  bad.yaw_rate_radps = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(attitude_from_msg(bad, &why));
  EXPECT_FALSE(why.empty());
}

TEST(BridgeMsgsTest, PositionSetpointsNeedFiniteValuesAndAKnownMotorsValue) {
  position_setpoint_t m{};
  m.p_W[2] = 1.5;
  m.motors = position_setpoint_t::MOTORS_KILL;
  std::string why;
  const auto t = position_from_msg(m, &why);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->motors, Motors::kKill);
  EXPECT_EQ(t->p_W.z(), 1.5);
  auto bad = m;
  bad.motors = 7;
  EXPECT_FALSE(position_from_msg(bad, &why));
  bad = m;
  bad.v_W[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(position_from_msg(bad, &why));
  auto turning = m;
  turning.a_W[1] = 0.8;  // a moving platform's turn
  const auto a = position_from_msg(turning, &why);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->a_W.y(), 0.8);
  bad = m;
  bad.a_W[2] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(position_from_msg(bad, &why));
  bad = m;
  bad.a_W[0] = 60;  // beyond 5 g
  EXPECT_FALSE(position_from_msg(bad, &why));
  EXPECT_NE(why.find("acceleration"), std::string::npos);
}

TEST(BridgeMsgsTest, StatusCarriesModeArmingLinkAndCounters) {
  AutopilotStatus s;
  s.link_up = true;
  s.mode = "OFFBOARD";
  s.armed = true;
  s.offboard = true;
  s.engage = EngageState::kFlying;
  s.flavour = Flavour::kArdupilot;
  s.stats.commands_failed = 3;
  s.parser.crc_errors = 4;
  s.firmware = "4.5.7";
  s.accel_feedforward = true;
  const auto m = to_msg(s, 42, 2);
  EXPECT_EQ(m.firmware, "4.5.7");
  EXPECT_TRUE(m.accel_feedforward);
  EXPECT_EQ(m.utime, 42);
  EXPECT_TRUE(m.link_up);
  EXPECT_EQ(m.mode, "OFFBOARD");
  EXPECT_EQ(m.engage, "FLYING");
  EXPECT_EQ(m.autopilot, autopilot_status_t::AUTOPILOT_ARDUPILOT);
  EXPECT_EQ(m.commands_failed, 3);
  EXPECT_EQ(m.crc_errors, 4);
  EXPECT_EQ(m.reopens, 2);
}

}  // namespace
}  // namespace alight::mavlink

namespace alight::mavlink {
namespace {

TEST(BridgeMsgsTest, SetpointStampsMayStepBackALittleButNotReplayOrRunFarAhead) {
  const int64_t ref = 1'700'000'000'000'000;
  EXPECT_FALSE(setpoint_stamp_problem(ref - 20'000, ref, 1.0, 10.0));  // the outer loop's step back
  EXPECT_FALSE(setpoint_stamp_problem(ref + 5'000'000, ref, 1.0, 10.0));
  EXPECT_FALSE(setpoint_stamp_problem(5, 0, 1.0, 10.0));  // nothing to judge against yet
  EXPECT_TRUE(setpoint_stamp_problem(ref - 2'000'000, ref, 1.0, 10.0));  // an old log replayed
  EXPECT_TRUE(setpoint_stamp_problem(ref + 11'000'000, ref, 1.0, 10.0));
  EXPECT_TRUE(setpoint_stamp_problem(0, ref, 1.0, 10.0));
  EXPECT_TRUE(setpoint_stamp_problem(INT64_MIN, ref, 1.0, 10.0));
  EXPECT_TRUE(setpoint_stamp_problem(INT64_MAX, ref, 1.0, 10.0));
}

// Issue 37: a forced disarm only for the operator's signed CMD_KILL, as the outer loop and the
// simulator check it (common/operator_auth.hpp, KillVerifier).
TEST(BridgeMsgsTest, OnlyTheOperatorsSignedKillForThisVehicleAuthorisesAForcedDisarm) {
  OperatorKey key{std::vector<uint8_t>(32, 0x5a)};
  const int64_t now = 1'800'000'000'000'000;
  const auto kill = [&](const std::string& vehicle, int64_t utime, int8_t command) {
    operator_cmd_t c{};
    c.utime = utime;
    c.seq = utime;
    c.sender = "station";
    c.vehicle_id = vehicle;
    c.command = command;
    sign(c, key);
    return c;
  };
  KillVerifier verifier(key, "pelican-1", 2'000'000);
  std::string why;
  EXPECT_TRUE(kill_authorised(&verifier, kill("pelican-1", now - 500'000, operator_cmd_t::CMD_KILL),
                              now, &why));
  // Repeated with every setpoint after it: still authorised, however old.
  EXPECT_TRUE(kill_authorised(&verifier, kill("pelican-1", now - 500'000, operator_cmd_t::CMD_KILL),
                              now + 60'000'000, &why));

  KillVerifier v(key, "pelican-1", 2'000'000);
  EXPECT_FALSE(kill_authorised(&v, operator_cmd_t{}, now, &why));
  EXPECT_EQ(why, "no kill authority attached");
  EXPECT_FALSE(kill_authorised(&v, kill("pelican-2", now, operator_cmd_t::CMD_KILL), now, &why));
  EXPECT_EQ(why, kill_check_name(KillCheck::kWrongVehicle));
  EXPECT_FALSE(
      kill_authorised(&v, kill("pelican-1", now - 5'000'000, operator_cmd_t::CMD_KILL), now, &why));
  EXPECT_EQ(why, kill_check_name(KillCheck::kStale));
  EXPECT_FALSE(kill_authorised(&v, kill("pelican-1", now, operator_cmd_t::CMD_ABORT), now, &why));
  EXPECT_EQ(why, kill_check_name(KillCheck::kNotKill));
  operator_cmd_t forged = kill("pelican-1", now, operator_cmd_t::CMD_KILL);
  forged.hmac[0] ^= 1;
  EXPECT_FALSE(kill_authorised(&v, forged, now, &why));
  EXPECT_EQ(why, kill_check_name(KillCheck::kBadSignature));
  operator_cmd_t unsigned_kill = kill("pelican-1", now, operator_cmd_t::CMD_KILL);
  unsigned_kill.auth = operator_cmd_t::AUTH_NONE;
  EXPECT_FALSE(kill_authorised(&v, unsigned_kill, now, &why));
  // No operator key configured: no KILL is ever forced.
  EXPECT_FALSE(
      kill_authorised(nullptr, kill("pelican-1", now, operator_cmd_t::CMD_KILL), now, &why));
}

}  // namespace
}  // namespace alight::mavlink

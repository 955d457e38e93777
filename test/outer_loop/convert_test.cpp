// LCM <-> domain conversions of the outer loop (no network).

#include "outer_loop/convert.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/msg_convert.hpp"

namespace alight::outer_loop {
namespace {

TEST(OuterLoopConvertTest, SetpointRoundTrips) {
  PositionSetpoint sp;
  sp.utime = 123456789;
  sp.p_W = {1, -2, 3};
  sp.v_W = {0.1, 0.2, -0.3};
  sp.a_W = {0.4, -0.5, 0.0};
  sp.yaw_rad = 0.7;
  sp.yaw_rate_radps = -0.05;
  sp.motors_on = true;
  sp.idle = false;
  const auto msg = to_msg(sp);
  EXPECT_EQ(msg.motors, position_setpoint_t::MOTORS_ON);
  EXPECT_EQ(msg.mode, position_setpoint_t::MODE_POSITION);
  // Through the wire format too.
  std::vector<uint8_t> buf(msg.getEncodedSize());
  ASSERT_EQ(msg.encode(buf.data(), 0, buf.size()), static_cast<int>(buf.size()));
  position_setpoint_t decoded;
  ASSERT_EQ(decoded.decode(buf.data(), 0, buf.size()), static_cast<int>(buf.size()));
  const auto back = from_msg(decoded);
  EXPECT_EQ(back.utime, sp.utime);
  EXPECT_EQ(back.p_W, sp.p_W);
  EXPECT_EQ(back.v_W, sp.v_W);
  EXPECT_EQ(back.a_W, sp.a_W);
  EXPECT_EQ(back.yaw_rad, sp.yaw_rad);
  EXPECT_EQ(back.yaw_rate_radps, sp.yaw_rate_radps);
  EXPECT_TRUE(back.motors_on);
  EXPECT_FALSE(back.idle);
  sp.motors_on = false;
  sp.idle = true;
  const auto off = from_msg(to_msg(sp));
  EXPECT_FALSE(off.motors_on);
  EXPECT_TRUE(off.idle);
  sp.motors_on = true;
  sp.idle = false;
  sp.precise = true;
  EXPECT_EQ(to_msg(sp).mode, position_setpoint_t::MODE_PRECISE);
  const auto precise = from_msg(to_msg(sp));
  EXPECT_TRUE(precise.precise);
  EXPECT_FALSE(precise.idle);
}

TEST(OuterLoopConvertTest, AttitudeCommandRoundTripsEveryMode) {
  for (Mode m : {Mode::kNormal, Mode::kHoldLevel, Mode::kFailsafeDescent, Mode::kHoldPosition,
                 Mode::kSetpointLostDescent, Mode::kDisarmed}) {
    AttitudeCommand c;
    c.utime = 42;
    c.roll_rad = 0.1;
    c.pitch_rad = -0.2;
    c.yaw_rate_radps = 0.3;
    c.thrust_N = 11.0;
    c.armed = m != Mode::kDisarmed;
    c.mode = m;
    const auto back = from_msg(to_msg(c));
    EXPECT_EQ(back.mode, m) << mode_name(m);
    EXPECT_EQ(back.armed, c.armed);
    EXPECT_EQ(back.roll_rad, 0.1);
    EXPECT_EQ(back.pitch_rad, -0.2);
    EXPECT_EQ(back.yaw_rate_radps, 0.3);
    EXPECT_EQ(back.thrust_N, c.armed ? 11.0 : 0.0) << "disarmed commands carry no thrust";
  }
  EXPECT_EQ(mode_to_msg(Mode::kHoldLevel), attitude_cmd_t::MODE_HOLD_LEVEL);
  EXPECT_EQ(mode_to_msg(Mode::kFailsafeDescent), attitude_cmd_t::MODE_FAILSAFE_DESCENT);
}

TEST(OuterLoopConvertTest, KillRoundTripsAsItsOwnMotorsValue) {
  PositionSetpoint sp;
  sp.utime = 1;
  sp.kill = true;
  const auto msg = to_msg(sp);
  EXPECT_EQ(msg.motors, position_setpoint_t::MOTORS_KILL);
  const auto back = setpoint_from_msg(msg, nullptr);
  ASSERT_TRUE(back);
  EXPECT_TRUE(back->kill);
  EXPECT_FALSE(back->motors_on);
  sp.kill = false;
  EXPECT_FALSE(setpoint_from_msg(to_msg(sp), nullptr)->kill);
}

TEST(OuterLoopRegression, NonFiniteSetpointIsRefusedAtConversion) {
  PositionSetpoint sp;
  sp.utime = 1;
  sp.motors_on = true;
  const position_setpoint_t good = to_msg(sp);
  std::string why;
  ASSERT_TRUE(setpoint_from_msg(good, &why));
  for (int field = 0; field < 11; ++field) {
    for (double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
      position_setpoint_t m = good;
      if (field < 3)
        m.p_W[field] = bad;
      else if (field < 6)
        m.v_W[field - 3] = bad;
      else if (field < 9)
        m.a_W[field - 6] = bad;
      else if (field == 9)
        m.yaw_rad = bad;
      else
        m.yaw_rate_radps = bad;
      why.clear();
      EXPECT_FALSE(setpoint_from_msg(m, &why)) << field;
      EXPECT_NE(why.find("non-finite"), std::string::npos) << why;
    }
  }
  position_setpoint_t m = good;
  m.motors = 7;
  EXPECT_FALSE(setpoint_from_msg(m, &why));
  m = good;
  m.mode = -1;
  EXPECT_FALSE(setpoint_from_msg(m, &why));
  m.mode = position_setpoint_t::MODE_PRECISE + 1;
  EXPECT_FALSE(setpoint_from_msg(m, &why));
  EXPECT_NE(why.find("unknown mode"), std::string::npos) << why;
  m.mode = position_setpoint_t::MODE_PRECISE;
  EXPECT_TRUE(setpoint_from_msg(m, &why)) << why;
}

TEST(OuterLoopRegression, NonFiniteOrNonUnitPoseIsRefusedAtConversion) {
  PoseSample s;
  s.utime = 1;
  s.p_W_B = {1, 2, 3};
  const pose_t good = alight::to_msg(s, 1);
  std::string why;
  ASSERT_TRUE(pose_from_msg(good, &why));
  const double nan = std::nan("");
  for (int field = 0; field < 13; ++field) {
    pose_t m = good;
    if (field < 3)
      m.pos[field] = nan;
    else if (field < 6)
      m.vel[field - 3] = nan;
    else if (field < 10)
      m.orientation[field - 6] = nan;
    else
      m.angular_velocity_B[field - 10] = nan;
    EXPECT_FALSE(pose_from_msg(m, &why)) << field;
  }
  pose_t m = good;
  m.orientation[0] = 0.98;  // norm 0.98: not a rotation
  EXPECT_FALSE(pose_from_msg(m, &why));
  EXPECT_NE(why.find("norm"), std::string::npos);
  m.orientation[0] = 0.0;  // all zero
  EXPECT_FALSE(pose_from_msg(m, &why));
  m.orientation[0] = 1.005;  // within 0.01 of 1: renormalised
  const auto ok = pose_from_msg(m, &why);
  ASSERT_TRUE(ok);
  EXPECT_NEAR(ok->q_WB.norm(), 1.0, 1e-12);
}

}  // namespace
}  // namespace alight::outer_loop

// LCM <-> domain conversions of the outer loop (no network).

#include "outer_loop/convert.hpp"

#include <gtest/gtest.h>

namespace alight::outer_loop {
namespace {

TEST(OuterLoopConvertTest, SetpointRoundTrips) {
  PositionSetpoint sp;
  sp.utime = 123456789;
  sp.p_W = {1, -2, 3};
  sp.v_W = {0.1, 0.2, -0.3};
  sp.yaw_rad = 0.7;
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
  EXPECT_EQ(back.yaw_rad, sp.yaw_rad);
  EXPECT_TRUE(back.motors_on);
  EXPECT_FALSE(back.idle);
  sp.motors_on = false;
  sp.idle = true;
  const auto off = from_msg(to_msg(sp));
  EXPECT_FALSE(off.motors_on);
  EXPECT_TRUE(off.idle);
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

}  // namespace
}  // namespace alight::outer_loop

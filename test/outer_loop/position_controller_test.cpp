// Known answers and stale-input modes of the outer-loop position controller.

#include "outer_loop/position_controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "lag_model.hpp"

namespace alight::outer_loop {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kMs = 1000;

OuterLoopParams params() {
  OuterLoopParams p;
  p.mass_kg = 1.2;
  return p;
}

PoseSample pose_at(const Vector3d& p, double yaw, int64_t utime) {
  PoseSample s;
  s.utime = utime;
  s.p_W_B = p;
  s.q_WB = Quaterniond(rotation_from_rpy(0, 0, yaw));
  return s;
}

PositionSetpoint setpoint_at(const Vector3d& p, double yaw, int64_t utime) {
  PositionSetpoint sp;
  sp.utime = utime;
  sp.p_W = p;
  sp.yaw_rad = yaw;
  sp.motors_on = true;
  return sp;
}

// A motors-off setpoint (without KILL) at p.
PositionSetpoint motors_off_at(const Vector3d& p, int64_t t) {
  auto off = setpoint_at(p, 0, t);
  off.motors_on = false;
  return off;
}

TEST(PositionControllerTest, AtTheSetpointCommandsLevelHoverThrust) {
  PositionController c(params());
  const auto cmd = c.update(setpoint_at({1, 2, 1}, 0.3, kT0), pose_at({1, 2, 1}, 0.3, kT0), kT0);
  EXPECT_EQ(cmd.mode, Mode::kNormal);
  EXPECT_TRUE(cmd.armed);
  EXPECT_NEAR(cmd.roll_rad, 0, 1e-12);
  EXPECT_NEAR(cmd.pitch_rad, 0, 1e-12);
  EXPECT_NEAR(cmd.yaw_rate_radps, 0, 1e-12);
  EXPECT_NEAR(cmd.thrust_N, 1.2 * 9.81, 1e-9);
}

TEST(PositionControllerTest, ForwardErrorPitchesNoseDownAndLeftErrorRollsLeft) {
  PositionController c(params());
  // Setpoint 0.1 m ahead (+x): accelerate along +x_B: positive pitch, no roll.
  auto cmd = c.update(setpoint_at({0.1, 0, 1}, 0, kT0), pose_at({0, 0, 1}, 0, kT0), kT0);
  EXPECT_NEAR(cmd.pitch_rad, std::atan2(0.4, 9.81), 1e-9);  // kp 4 * 0.1 m
  EXPECT_NEAR(cmd.roll_rad, 0, 1e-12);
  // Setpoint 0.1 m to the left (+y_B): body z must lean to +y, which is negative roll.
  PositionController c2(params());
  cmd = c2.update(setpoint_at({0, 0.1, 1}, 0, kT0), pose_at({0, 0, 1}, 0, kT0), kT0);
  EXPECT_LT(cmd.roll_rad, 0);
  EXPECT_NEAR(cmd.pitch_rad, 0, 1e-12);
  // The thrust vector of the command points along the desired specific force.
  const Vector3d z_B = rotation_from_rpy(cmd.roll_rad, cmd.pitch_rad, 0) * Vector3d::UnitZ();
  EXPECT_NEAR(z_B.y() / z_B.z(), 0.4 / 9.81, 1e-9);
  EXPECT_NEAR(cmd.thrust_N, 1.2 * std::hypot(0.4, 9.81), 1e-9);
}

TEST(PositionControllerTest, PreciseSetpointsUseThePreciseLateralGains) {
  auto p = params();
  p.precise_kp_xy_per_s2 = 9.0;
  p.precise_kd_xy_per_s = 5.0;
  // 0.1 m ahead, moving back at 0.02 m/s: kp 0.1 + kd 0.02.
  auto pose = pose_at({0, 0, 1}, 0, kT0);
  pose.v_W_B = Vector3d(-0.02, 0, 0);
  auto sp = setpoint_at({0.1, 0, 1}, 0, kT0);
  PositionController normal(p);
  auto cmd = normal.update(sp, pose, kT0);
  EXPECT_NEAR(cmd.pitch_rad, std::atan2(4.0 * 0.1 + 3.2 * 0.02, 9.81), 1e-9);
  EXPECT_STREQ(cmd.reason, "tracking");
  sp.precise = true;
  PositionController precise(p);
  cmd = precise.update(sp, pose, kT0);
  EXPECT_NEAR(cmd.pitch_rad, std::atan2(9.0 * 0.1 + 5.0 * 0.02, 9.81), 1e-9);
  EXPECT_STREQ(cmd.reason, "tracking (precise)");
  // The altitude loop is the same either way.
  sp.p_W.z() = 1.2;
  // The vertical part of the thrust (thrust cos(roll) cos(pitch)) is the altitude loop's alone.
  auto vertical_N = [](const AttitudeCommand& c) {
    return c.thrust_N * std::cos(c.roll_rad) * std::cos(c.pitch_rad);
  };
  PositionController a(p), b(p);
  sp.precise = false;
  const double vertical_normal_N = vertical_N(a.update(sp, pose, kT0));
  sp.precise = true;
  EXPECT_NEAR(vertical_N(b.update(sp, pose, kT0)), vertical_normal_N, 1e-9)
      << "only the lateral gains differ";
  EXPECT_GT(vertical_normal_N, 1.2 * 9.81) << "the altitude error asks for a climb";
}

TEST(PositionControllerTest, LateralCommandIsInTheHeadingFrame) {
  // Facing +y (yaw 90 deg), an error along world +x is to the vehicle's right (-y_B): roll right.
  PositionController c(params());
  const auto cmd =
      c.update(setpoint_at({0.1, 0, 1}, M_PI / 2, kT0), pose_at({0, 0, 1}, M_PI / 2, kT0), kT0);
  EXPECT_GT(cmd.roll_rad, 0);
  EXPECT_NEAR(cmd.pitch_rad, 0, 1e-9);
}

TEST(PositionControllerTest, TiltAndThrustAreLimited) {
  auto p = params();
  PositionController c(p);
  const auto cmd = c.update(setpoint_at({50, -50, 30}, 0, kT0), pose_at({0, 0, 1}, 0, kT0), kT0);
  const double max_tilt = p.max_tilt_deg * M_PI / 180;
  EXPECT_LE(std::abs(cmd.roll_rad), max_tilt + 1e-12);
  EXPECT_LE(std::abs(cmd.pitch_rad), max_tilt + 1e-12);
  const Vector3d z_B = rotation_from_rpy(cmd.roll_rad, cmd.pitch_rad, 0) * Vector3d::UnitZ();
  EXPECT_LE(std::acos(z_B.z()), max_tilt + 1e-9);
  EXPECT_LE(cmd.thrust_N, p.thrust_max_N);
  PositionController c2(p);
  const auto down = c2.update(setpoint_at({0, 0, -30}, 0, kT0), pose_at({0, 0, 1}, 0, kT0), kT0);
  EXPECT_GE(down.thrust_N, p.thrust_min_N);
  EXPECT_NEAR(down.thrust_N, 1.2 * (9.81 - p.max_accel_z_mps2), 1e-9);
}

// A turning heading (a turning platform's) is fed forward: on the heading, the command is the
// turn; a P loop alone trails a ramp by rate / kp (3.3 deg at 5 deg/s with kp 1.5 /s).
TEST(PositionControllerTest, AYawRateFeedForwardTurnsWithTheHeadingWithinTheLimit) {
  auto p = params();
  PositionController c(p);
  auto sp = setpoint_at({0, 0, 1}, 0.2, kT0);
  sp.yaw_rate_radps = 0.09;
  auto cmd = c.update(sp, pose_at({0, 0, 1}, 0.2, kT0), kT0);
  EXPECT_NEAR(cmd.yaw_rate_radps, 0.09, 1e-9);
  sp.yaw_rate_radps = -0.09;
  cmd = c.update(sp, pose_at({0, 0, 1}, 0.1, kT0), kT0);
  EXPECT_NEAR(cmd.yaw_rate_radps, p.yaw_kp_per_s * 0.1 - 0.09, 1e-9);
  sp.yaw_rate_radps = 100.0;
  cmd = c.update(sp, pose_at({0, 0, 1}, 0.2, kT0), kT0);
  EXPECT_NEAR(cmd.yaw_rate_radps, p.max_yaw_rate_dps * M_PI / 180, 1e-9);
}

TEST(PositionControllerTest, YawRateFollowsTheHeadingErrorWithinItsLimit) {
  auto p = params();
  PositionController c(p);
  auto cmd = c.update(setpoint_at({0, 0, 1}, 0.1, kT0), pose_at({0, 0, 1}, 0, kT0), kT0);
  EXPECT_NEAR(cmd.yaw_rate_radps, p.yaw_kp_per_s * 0.1, 1e-9);
  // Across the +-pi seam the short way round.
  cmd =
      c.update(setpoint_at({0, 0, 1}, M_PI - 0.1, kT0), pose_at({0, 0, 1}, -M_PI + 0.1, kT0), kT0);
  EXPECT_LT(cmd.yaw_rate_radps, 0);
  cmd = c.update(setpoint_at({0, 0, 1}, 3.0, kT0), pose_at({0, 0, 1}, 0, kT0), kT0);
  EXPECT_NEAR(cmd.yaw_rate_radps, p.max_yaw_rate_dps * M_PI / 180, 1e-9);
}

TEST(PositionControllerTest, RefusesToArmWithoutSetpointOrPoseOrWhenMotorsOff) {
  PositionController c(params());
  auto cmd = c.update(std::nullopt, pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_FALSE(cmd.armed);
  EXPECT_EQ(cmd.mode, Mode::kDisarmed);
  cmd = c.update(setpoint_at({0, 0, 1}, 0, kT0), std::nullopt, kT0);
  EXPECT_FALSE(cmd.armed);
  auto sp = setpoint_at({0, 0, 1}, 0, kT0);
  sp.motors_on = false;
  cmd = c.update(sp, pose_at({0, 0, 1}, 0, kT0), kT0);
  EXPECT_FALSE(cmd.armed);
  EXPECT_EQ(cmd.thrust_N, 0.0);
}

TEST(PositionControllerTest, IdleSetpointSpinsAtMinimumThrustLevel) {
  auto p = params();
  PositionController c(p);
  auto sp = setpoint_at({0, 0, 1}, 0, kT0);
  sp.idle = true;
  const auto cmd = c.update(sp, pose_at({0.5, 0, 0}, 0, kT0), kT0);
  EXPECT_TRUE(cmd.armed);
  EXPECT_EQ(cmd.thrust_N, p.thrust_min_N);
  EXPECT_EQ(cmd.roll_rad, 0.0);
  EXPECT_EQ(cmd.pitch_rad, 0.0);
}

TEST(PositionControllerTest, StalePoseGivesLevelHoverThrustAndNoLateralCommand) {
  auto p = params();
  PositionController c(p);
  const auto pose = pose_at({0, 0, 1}, 0, kT0);
  // Fresh enough (0.29 s): still tracking, with a lateral command.
  int64_t now = kT0 + 290 * kMs;
  auto cmd = c.update(setpoint_at({1, 0, 1}, 0, now), pose, now);
  EXPECT_EQ(cmd.mode, Mode::kNormal);
  EXPECT_GT(cmd.pitch_rad, 0);
  now = kT0 + 310 * kMs;
  cmd = c.update(setpoint_at({1, 0, 1}, 0, now), pose, now);
  EXPECT_EQ(cmd.mode, Mode::kHoldLevel);
  EXPECT_TRUE(cmd.armed);
  EXPECT_EQ(cmd.roll_rad, 0.0);
  EXPECT_EQ(cmd.pitch_rad, 0.0);
  EXPECT_EQ(cmd.yaw_rate_radps, 0.0);
  EXPECT_NEAR(cmd.thrust_N, 1.2 * (9.81 + c.integral().z()), 1e-9);
}

TEST(PositionControllerTest, LostPoseDescendsSlowlyOpenLoopThenDisarmsAndLatches) {
  auto p = params();
  PositionController c(p);
  test::LagModel model;
  model.hover_at({0, 0, 3});
  const auto last_pose = model.pose(kT0);
  c.update(setpoint_at({0, 0, 3}, 0, kT0), last_pose, kT0);
  AttitudeCommand cmd;
  double max_descent = 0;
  int64_t t = kT0;
  // Fly without pose; autonomy keeps sending setpoints (stepped on the IMU).
  for (; t < kT0 + static_cast<int64_t>((p.failsafe_disarm_after_s + 2.0) * 1e6); t += 10 * kMs) {
    cmd = c.update(setpoint_at({0, 0, 3}, 0, t), last_pose, t);
    const double age = (t - kT0) * 1e-6;
    if (age > p.pose_lost_s && age < p.pose_lost_s + p.failsafe_disarm_after_s) {
      ASSERT_EQ(cmd.mode, Mode::kFailsafeDescent) << age;
      ASSERT_EQ(cmd.roll_rad, 0.0);
      ASSERT_TRUE(cmd.armed);
    }
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
    if (model.p.z() > 0) max_descent = std::max(max_descent, -model.v.z());
  }
  EXPECT_LT(model.p.z(), 1e-9) << "reached the ground";
  EXPECT_LE(max_descent, p.failsafe_descent_mps * 1.1) << "slow descent";
  EXPECT_GT(max_descent, p.failsafe_descent_mps * 0.7);
  EXPECT_FALSE(cmd.armed) << "disarmed after failsafe_disarm_after_s";
  // Pose back and a motors-on setpoint: stays disarmed until autonomy acknowledges with motors off.
  cmd = c.update(setpoint_at({0, 0, 3}, 0, t), model.pose(t), t);
  EXPECT_FALSE(cmd.armed);
  auto off = motors_off_at({0, 0, 0}, t);
  c.update(off, model.pose(t), t);
  cmd = c.update(setpoint_at({0, 0, 1}, 0, t), model.pose(t), t);
  EXPECT_TRUE(cmd.armed);
}

TEST(PositionControllerTest, StaleSetpointHoldsWhereItWentStaleNotTheOldSetpoint) {
  auto p = params();
  PositionController c(p);
  test::LagModel model;
  model.hover_at({0, 0, 1});
  const auto sp = setpoint_at({2, 0, 1}, 0, kT0);  // flying towards x = 2 when autonomy dies
  AttitudeCommand cmd;
  Vector3d p_stale = Vector3d::Zero();
  for (int64_t t = kT0; t < kT0 + 2'500 * kMs; t += 10 * kMs) {
    cmd = c.update(sp, model.pose(t), t);
    if (t - kT0 <= 500 * kMs) {
      EXPECT_EQ(cmd.mode, Mode::kNormal);
      p_stale = model.p;
    } else {
      EXPECT_EQ(cmd.mode, Mode::kHoldPosition);
    }
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  EXPECT_LT(model.p.x(), 1.5) << "did not keep flying to the stale setpoint";
  EXPECT_LT((model.p - p_stale).norm(), 0.3);
  EXPECT_LT(model.v.norm(), 0.2);
}

TEST(PositionControllerTest, LostSetpointDescendsOnThePoseAndDisarmsOnTheGround) {
  auto p = params();
  PositionController c(p);
  test::LagModel model;
  model.hover_at({0.5, 0.5, 1.0});
  const auto sp = setpoint_at({0.5, 0.5, 1.0}, 0, kT0);
  AttitudeCommand cmd;
  bool saw_descent = false;
  for (int64_t t = kT0; t < kT0 + 15'000 * kMs; t += 10 * kMs) {
    cmd = c.update(sp, model.pose(t), t);
    saw_descent |= cmd.mode == Mode::kSetpointLostDescent;
    if (saw_descent && model.p.z() > 0.05) {
      EXPECT_LT(-model.v.z(), p.setpoint_lost_descent_mps * 1.5);
    }
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  EXPECT_TRUE(saw_descent);
  EXPECT_NEAR(model.p.z(), 0.0, 1e-9);
  EXPECT_NEAR(model.p.x(), 0.5, 0.05);
  EXPECT_FALSE(cmd.armed);
  EXPECT_EQ(cmd.mode, Mode::kDisarmed);
}

TEST(PositionControllerTest, ParamsValidateRejectsNonsense) {
  auto p = params();
  p.max_tilt_deg = 80;
  EXPECT_THROW(p.validate(), ParamError);
  p = params();
  p.pose_lost_s = 0.1;  // below pose_stale_s
  EXPECT_THROW(p.validate(), ParamError);
  p = params();
  p.thrust_max_N = 1.0;  // cannot hover
  EXPECT_THROW(p.validate(), ParamError);
}

// Flies `c` on `model` from t for `seconds` with the setpoint `sp` (restamped each step), the
// pose from the model; returns the last command.
AttitudeCommand fly(PositionController& c, test::LagModel& model, PositionSetpoint sp, int64_t& t,
                    double seconds) {
  AttitudeCommand cmd;
  const int64_t end = t + static_cast<int64_t>(seconds * 1e6);
  for (; t < end; t += 10 * kMs) {
    sp.utime = t;
    cmd = c.update(sp, model.pose(t), t);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  return cmd;
}

// Hovers the model at p0 for a second on a setpoint there; returns the time it is then.
int64_t hover_for_a_second(PositionController& c, test::LagModel& model, const Vector3d& p0) {
  model.hover_at(p0);
  int64_t t = kT0;
  fly(c, model, setpoint_at(p0, 0, t), t, 1.0);
  return t;
}

bool finite(const AttitudeCommand& c) {
  return std::isfinite(c.roll_rad) && std::isfinite(c.pitch_rad) &&
         std::isfinite(c.yaw_rate_radps) && std::isfinite(c.thrust_N);
}

TEST(OuterLoopRegression, NanPoseNeverReachesThrust) {
  // Given a vehicle hovering under control
  PositionController c(params());
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 1});
  // When one pose has a NaN position, one a NaN velocity and one a NaN quaternion
  for (int field = 0; field < 3; ++field) {
    auto bad = model.pose(t);
    if (field == 0) bad.p_W_B.z() = std::nan("");
    if (field == 1) bad.v_W_B.x() = std::nan("");
    if (field == 2) bad.q_WB.w() = std::nan("");
    const auto cmd = c.update(setpoint_at({0, 0, 1}, 0, t), bad, t);
    // Then the command stays finite and armed, and the integrator is untouched
    EXPECT_TRUE(finite(cmd)) << field;
    EXPECT_TRUE(cmd.armed) << field;
    EXPECT_TRUE(c.integral().allFinite()) << field;
    t += 10 * kMs;
  }
  // And a second of good input flies on as before
  const auto cmd = fly(c, model, setpoint_at({0, 0, 1}, 0, t), t, 1.0);
  EXPECT_TRUE(finite(cmd));
  EXPECT_TRUE(c.integral().allFinite());
  EXPECT_NEAR(model.p.z(), 1.0, 0.05);
}

TEST(OuterLoopRegression, NanSetpointNeverReachesThrust) {
  PositionController c(params());
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 1});
  auto bad = setpoint_at({0, 0, std::numeric_limits<double>::infinity()}, 0, t);
  bad.v_W.x() = std::nan("");
  bad.yaw_rad = std::nan("");
  const auto cmd = c.update(bad, model.pose(t), t);
  EXPECT_TRUE(finite(cmd));
  EXPECT_TRUE(cmd.armed);
  EXPECT_TRUE(c.integral().allFinite());
  const auto after = fly(c, model, setpoint_at({0, 0, 1}, 0, t), t, 1.0);
  EXPECT_TRUE(finite(after));
  EXPECT_NEAR(model.p.z(), 1.0, 0.05);
}

TEST(OuterLoopRegression, MotorsOffWithoutKillLandsInsteadOfDisarmingInTheAir) {
  // Given a vehicle hovering at 1.5 m (a restarted autonomy's first setpoint is motors off)
  auto p = params();
  PositionController c(p);
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0.3, 0.2, 1.5});
  // When motors off arrives without KILL
  auto off = motors_off_at({0, 0, 0}, t);
  AttitudeCommand cmd;
  double lowest_armed_m = 10;
  bool disarmed_in_air = false;
  for (int64_t end = t + 15'000 * kMs; t < end; t += 10 * kMs) {
    off.utime = t;
    cmd = c.update(off, model.pose(t), t);
    if (cmd.armed) lowest_armed_m = std::min(lowest_armed_m, model.p.z());
    if (!cmd.armed && model.p.z() > 0.01) disarmed_in_air = true;
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  // Then it lands slowly on the pose where it was and disarms only on the ground
  EXPECT_FALSE(disarmed_in_air);
  EXPECT_FALSE(cmd.armed);
  EXPECT_NEAR(model.p.z(), 0.0, 1e-9);
  EXPECT_NEAR(model.p.x(), 0.3, 0.05);
  EXPECT_NEAR(model.p.y(), 0.2, 0.05);
}

TEST(OuterLoopRegression, KillDisarmsAtOnceInTheAir) {
  PositionController c(params());
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 1.5});
  auto kill = setpoint_at({0, 0, 1.5}, 0, t);
  kill.motors_on = false;
  kill.kill = true;
  const auto cmd = c.update(kill, model.pose(t), t);
  EXPECT_FALSE(cmd.armed);
  EXPECT_EQ(cmd.mode, Mode::kDisarmed);
}

TEST(PositionControllerTest, MotorsOffAfterATouchDownDisarmsWithinASecond) {
  // Autonomy's final descent presses the vehicle onto the ground, then it sends motors off.
  PositionController c(params());
  test::LagModel model;
  model.hover_at({0, 0, 0.3});
  int64_t t = kT0;
  fly(c, model, setpoint_at({0, 0, -0.3}, 0, t), t, 1.5);
  ASSERT_NEAR(model.p.z(), 0.0, 1e-9);
  auto off = motors_off_at({0, 0, -0.3}, t);
  const int64_t t_off = t;
  AttitudeCommand cmd;
  for (; t < t_off + 2'000 * kMs; t += 10 * kMs) {
    off.utime = t;
    cmd = c.update(off, model.pose(t), t);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
    if (!cmd.armed) break;
  }
  EXPECT_FALSE(cmd.armed);
  EXPECT_LE(t - t_off, 1'000 * kMs);
}

TEST(OuterLoopRegression, MotorsOffAtTheImpactDoesNotBrakeTheDescent) {
  // Autonomy's final descent leads the vehicle down at 1 m/s; its motors-off comes as the gear
  // meets the top, while the pose still shows the descent. Braking there (the old landing took
  // the pose's altitude and the slow setpoint-lost speed) raised the thrust at the impact, and
  // the vehicle bounced off the platform and came to rest centimetres away.
  PositionController c(params());
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 1.0});
  auto sp = setpoint_at({0, 0, 1.0}, 0, t);
  sp.v_W = Vector3d(0, 0, -1.0);
  AttitudeCommand cmd;
  for (int i = 0; i < 50; ++i, t += 10 * kMs) {  // 0.5 s of the led descent, still airborne
    sp.utime = t;
    sp.p_W.z() = 1.0 - 1.0 * 0.01 * i;
    cmd = c.update(sp, model.pose(t), t);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  ASSERT_GT(model.p.z(), 0.1);
  ASSERT_LT(model.v.z(), -0.5);
  auto off = sp;
  off.motors_on = false;
  off.v_W.setZero();
  double highest_thrust_N = 0;
  for (int i = 0; i < 10; ++i, t += 10 * kMs) {  // the next 0.1 s, the pose still descending
    off.utime = t;
    cmd = c.update(off, model.pose(t), t);
    EXPECT_TRUE(cmd.armed);
    EXPECT_EQ(cmd.mode, Mode::kSetpointLostDescent);
    highest_thrust_N = std::max(highest_thrust_N, cmd.thrust_N);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  // Below hover thrust all along: the landing keeps pushing down, it never brakes.
  EXPECT_LT(highest_thrust_N, 1.2 * 9.81);
}

TEST(PositionControllerTest, AMotorsOffOnAMovingTopGoesOnWithItsVelocity) {
  // A touch-down on a moving platform: autonomy fed the platform's 0.5 m/s forward up to its
  // motors-off. Until the land detector levels the vehicle, the landing must go on moving with
  // the top, not brake to where the motors-off came (which drags the gear across the top).
  PositionController c(params());
  test::LagModel model;
  model.floor = false;  // still in the air: what the landing asks for, not a contact
  int64_t t = hover_for_a_second(c, model, {0, 0, 1.0});
  auto sp = setpoint_at({0, 0, 1.0}, 0, t);
  const double v = 0.5;
  for (int i = 0; i < 300; ++i, t += 10 * kMs) {  // 3 s following at 0.5 m/s, descending
    sp.utime = t;
    sp.p_W = Vector3d(v * 0.01 * i, 0, 1.0 - 0.2 * 0.01 * i);
    sp.v_W = Vector3d(v, 0, -0.2);
    const auto cmd = c.update(sp, model.pose(t), t);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  ASSERT_NEAR(model.v.x(), v, 0.05);
  auto off = sp;
  off.motors_on = false;
  const double x0 = model.p.x();
  for (int i = 0; i < 40; ++i, t += 10 * kMs) {  // 0.4 s
    off.utime = t;
    const auto cmd = c.update(off, model.pose(t), t);
    EXPECT_EQ(cmd.mode, Mode::kSetpointLostDescent);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  EXPECT_NEAR(model.v.x(), v, 0.05);
  EXPECT_NEAR(model.p.x() - x0, v * 0.4, 0.03);
}

TEST(PositionControllerTest, AMotorsOffInAHoverStillDescendsSlowly) {
  // No descent was commanded: the refused motors-off lands at setpoint_lost_descent_mps.
  auto p = params();
  PositionController c(p);
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 2.0});
  auto off = motors_off_at({0, 0, 2.0}, t);
  fly(c, model, off, t, 2.0);
  EXPECT_NEAR(model.v.z(), -p.setpoint_lost_descent_mps, 0.05);
}

TEST(PositionControllerTest, InGroundContactARefusedMotorsOffLandsLevel) {
  // A refused motors-off lands from a hover at 0.3 m while the pose reads 5 cm off the landing's
  // start: in the air the loop tilts to correct it, on the ground the friction holds the
  // vehicle and tilting against it would only drag it, so the landing goes level there.
  PositionController c(params());
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 0.3});
  auto off = motors_off_at({0, 0, 0.3}, t);
  AttitudeCommand cmd = c.update(off, model.pose(t), t);  // the landing begins here
  bool tilted_in_the_air = false, level_on_the_ground = false;
  for (int i = 0; i < 500 && cmd.armed; ++i) {
    t += 10 * kMs;
    off.utime = t;
    auto pose = model.pose(t);
    pose.p_W_B.x() += 0.05;
    cmd = c.update(off, pose, t);
    if (!cmd.armed) break;
    EXPECT_EQ(cmd.mode, Mode::kSetpointLostDescent);
    const bool level = cmd.pitch_rad == 0.0 && cmd.roll_rad == 0.0;
    if (model.p.z() > 0.05 && !level) tilted_in_the_air = true;
    if (model.p.z() == 0.0 && model.v.norm() == 0.0 && level) level_on_the_ground = true;
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  EXPECT_TRUE(tilted_in_the_air);
  EXPECT_TRUE(level_on_the_ground);
  EXPECT_FALSE(cmd.armed);  // and the land detector still disarms it
  EXPECT_NEAR(model.p.z(), 0.0, 1e-9);
}

// A led descent (as autonomy's final descent) meets the ground and autonomy's motors-off comes
// at the impact; returns the thrust commanded over the landing, 10 ms apart, up to the disarm.
std::vector<double> thrust_over_an_arrival(const OuterLoopParams& p) {
  PositionController c(p);
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 0.3});
  auto sp = setpoint_at({0, 0, 0.3}, 0, t);
  sp.v_W = Vector3d(0, 0, -0.5);
  for (int i = 0; model.p.z() > 0.0; ++i, t += 10 * kMs) {  // led down until the gear meets it
    if (i == 500) {
      ADD_FAILURE() << "never reached the ground in 5 s";
      return {};
    }
    sp.utime = t;
    sp.p_W.z() -= 0.5 * 0.01;
    const auto cmd = c.update(sp, model.pose(t), t);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  auto off = sp;
  off.motors_on = false;
  off.v_W.setZero();
  std::vector<double> thrust_N;
  for (int i = 0; i < 200; ++i, t += 10 * kMs) {
    off.utime = t;
    const auto cmd = c.update(off, model.pose(t), t);
    if (!cmd.armed) break;
    thrust_N.push_back(cmd.thrust_N);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  return thrust_N;
}

TEST(PositionControllerTest, ALandingThatArrivesOnTheGroundCutsTheThrustAtOnce) {
  // With land_contact_cut the thrust goes to its minimum as soon as the ground holds the vehicle
  // up (a few cycles after the impact), long before the land detector's verdict disarms it;
  // without, it stays on the position loop's demand (well above the minimum) until then.
  auto p = params();
  p.land_contact_cut = true;
  const auto cut = thrust_over_an_arrival(p);
  ASSERT_GE(cut.size(), 20u);  // still armed for land_detect_s
  const auto first_min = std::find(cut.begin(), cut.end(), p.thrust_min_N);
  ASSERT_NE(first_min, cut.end());
  EXPECT_LE(first_min - cut.begin(), 10);  // within 0.1 s of the motors-off
  EXPECT_TRUE(std::all_of(first_min, cut.end(), [&](double f) { return f == p.thrust_min_N; }));

  p.land_contact_cut = false;
  const auto kept = thrust_over_an_arrival(p);
  ASSERT_GE(kept.size(), 20u);
  EXPECT_GT(*std::min_element(kept.begin(), kept.end()), 4 * p.thrust_min_N);
}

TEST(PositionControllerTest, ALandingFromAHoverIsNotCutAtItsStart) {
  // A refused motors-off in a hover: the demand leads down before the vehicle moves, so it looks
  // held up for a moment; cutting there would drop it. Only the ground at the end cuts.
  auto p = params();
  p.land_contact_cut = true;
  PositionController c(p);
  test::LagModel model;
  int64_t t = hover_for_a_second(c, model, {0, 0, 0.5});
  auto off = motors_off_at({0, 0, 0.5}, t);
  bool cut_in_the_air = false, cut_on_the_ground = false;
  AttitudeCommand cmd;
  for (int i = 0; i < 1000; ++i, t += 10 * kMs) {
    off.utime = t;
    cmd = c.update(off, model.pose(t), t);
    if (!cmd.armed) break;
    if (cmd.thrust_N == p.thrust_min_N)
      (model.p.z() > 0.0 ? cut_in_the_air : cut_on_the_ground) = true;
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
  }
  EXPECT_FALSE(cut_in_the_air);
  EXPECT_TRUE(cut_on_the_ground);
  EXPECT_FALSE(cmd.armed);
  EXPECT_NEAR(model.p.z(), 0.0, 1e-9);
}

TEST(PositionControllerTest, HoverWithAMassErrorIsNotTakenForLanded) {
  // The nominal mass 20 % above the true one: hover thrust well below m g, yet airborne.
  auto p = params();
  p.mass_kg = 1.2 * 1.2;
  PositionController c(p);
  test::LagModel model;
  model.hover_at({0, 0, 1});
  int64_t t = kT0;
  fly(c, model, setpoint_at({0, 0, 1}, 0, t), t, 15.0);
  EXPECT_FALSE(c.landed());
  auto off = motors_off_at({0, 0, 1}, t);
  EXPECT_TRUE(c.update(off, model.pose(t), t).armed);
}

TEST(OuterLoopRegression, LatchedFailsafeDisarmSurvivesARestart) {
  // A new controller given the latch its predecessor persisted refuses a motors-on setpoint
  PositionController c(params(), PersistentState{true, false});
  auto cmd = c.update(setpoint_at({0, 0, 1}, 0, kT0), pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_FALSE(cmd.armed);
  EXPECT_TRUE(c.persistent_state().disarm_latched);
  // until autonomy acknowledges with motors off
  auto off = setpoint_at({0, 0, 0}, 0, kT0);
  off.motors_on = false;
  c.update(off, pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_FALSE(c.persistent_state().disarm_latched);
  cmd = c.update(setpoint_at({0, 0, 1}, 0, kT0), pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_TRUE(cmd.armed);
}

TEST(OuterLoopRegression, RestartedInFlightAMotorsOffDoesNotDisarm) {
  // The predecessor was flying; the new one's first setpoint is motors off (no KILL).
  PositionController c(params(), PersistentState{false, true});
  test::LagModel model;
  model.hover_at({0, 0, 1.5});
  auto off = setpoint_at({0, 0, 0}, 0, kT0);
  off.motors_on = false;
  const auto cmd = c.update(off, model.pose(kT0), kT0);
  EXPECT_TRUE(cmd.armed);
  EXPECT_EQ(cmd.mode, Mode::kSetpointLostDescent);
}

TEST(PositionControllerTest, StartsOnlyWithAPoseAndASetpointBothFresh) {
  PositionController c(params());
  c.update(std::nullopt, pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_FALSE(c.started());
  c.update(setpoint_at({0, 0, 0}, 0, kT0 - 2'000 * kMs), pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_FALSE(c.started()) << "stale setpoint";
  c.update(setpoint_at({0, 0, 0}, 0, kT0), pose_at({0, 0, 0}, 0, kT0 - 2'000 * kMs), kT0);
  EXPECT_FALSE(c.started()) << "stale pose";
  c.update(setpoint_at({0, 0, 0}, 0, kT0), pose_at({0, 0, 0}, 0, kT0), kT0);
  EXPECT_TRUE(c.started());
}

TEST(OuterLoopRegression, ParamsRejectInfiniteTimeouts) {
  for (const char* key : {"pose_lost_s", "failsafe_disarm_after_s", "setpoint_lost_s"}) {
    auto p = params();
    if (std::string(key) == "pose_lost_s") p.pose_lost_s = std::numeric_limits<double>::infinity();
    if (std::string(key) == "failsafe_disarm_after_s")
      p.failsafe_disarm_after_s = std::numeric_limits<double>::infinity();
    if (std::string(key) == "setpoint_lost_s")
      p.setpoint_lost_s = std::numeric_limits<double>::infinity();
    try {
      p.validate();
      ADD_FAILURE() << key << " = inf accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), key);
    }
  }
}

TEST(PositionControllerTest, WithThePoseLostAutonomysTouchDownMotorsOffIsHonoured) {
  // Blind failsafe descent: autonomy's IMU touch-down is the only land detector left.
  PositionController c(params());
  const auto last_pose = pose_at({0, 0, 1}, 0, kT0);
  c.update(setpoint_at({0, 0, 1}, 0, kT0), last_pose, kT0);
  const int64_t t = kT0 + 3'000 * kMs;
  ASSERT_EQ(c.update(setpoint_at({0, 0, 1}, 0, t), last_pose, t).mode, Mode::kFailsafeDescent);
  auto off = setpoint_at({0, 0, 0}, 0, t + 10 * kMs);
  off.motors_on = false;
  EXPECT_FALSE(c.update(off, last_pose, t + 10 * kMs).armed);
}

TEST(OuterLoopRegression, ATakeOffThatWaitsOnTheGroundDoesNotWindUpTheIntegrators) {
  // ArduCopter SITL in GUIDED_NOGPS lifted off about 3.5 s after the outer loop first asked for
  // thrust (mode change, arming, spool-up): integrating the take-off's height error against the
  // ground all that while, the outer loop overshot a 1.2 m take-off to 1.53 m.
  PositionController c(params());
  test::LagModel model;
  int64_t t = kT0;
  const auto sp = setpoint_at({0, 0, 1.2}, 0, t);
  const int64_t spool_end = t + 3'500 * kMs;
  double peak_m = 0.0;
  for (; t < kT0 + 10'000'000; t += 10 * kMs) {
    auto s = sp;
    s.utime = t;
    AttitudeCommand cmd = c.update(s, model.pose(t), t);
    if (t < spool_end) {
      EXPECT_EQ(c.integral().norm(), 0.0) << "on the ground at " << (t - kT0) * 1e-6 << " s";
      cmd.armed = false;  // the motors not spinning yet
    }
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
    peak_m = std::max(peak_m, model.p.z());
  }
  EXPECT_LT(peak_m, 1.2 + 0.08);  // autonomy's take-off tolerance (takeoff.reached_tol_m)
  EXPECT_NEAR(model.p.z(), 1.2, 0.02);
}

TEST(PositionControllerTest, TheIntegratorsLearnOnceTheVehicleHasLiftedOff) {
  // A nominal mass 10 % low: the altitude integral must make up for it in the air.
  auto p = params();
  p.mass_kg = 1.2 / 1.1;
  PositionController c(p);
  test::LagModel model;
  int64_t t = kT0;
  fly(c, model, setpoint_at({0, 0, 1.0}, 0, t), t, 15.0);
  EXPECT_GT(c.integral().z(), 0.5);
  EXPECT_NEAR(model.p.z(), 1.0, 0.02);
}

// A setpoint going round a circle (a platform followed on its path), with its velocity and
// acceleration fed forward, on the lag model: the largest offset over the second and third laps.
double worst_offset_on_a_circle(bool feed_acceleration) {
  const double r = 0.6, v = 0.5, w = v / r;  // 0.42 m/s^2 towards the centre
  const Vector3d c0(0, 0, 1.5);
  const auto on_circle = [&](double t, PositionSetpoint& sp) {
    const double a = w * t;
    sp.p_W = c0 + r * Vector3d(std::cos(a), std::sin(a), 0);
    sp.v_W = v * Vector3d(-std::sin(a), std::cos(a), 0);
    sp.a_W = feed_acceleration ? Vector3d(-v * w * std::cos(a), -v * w * std::sin(a), 0)
                               : Vector3d::Zero();
  };
  PositionController c(params());
  test::LagModel model;
  PositionSetpoint sp = setpoint_at(c0, 0, kT0);
  on_circle(0, sp);
  model.hover_at(sp.p_W);
  model.v = sp.v_W;
  const double lap_s = 2 * M_PI / w;
  double worst = 0;
  for (int64_t t = kT0; t < kT0 + int64_t(3 * lap_s * 1e6); t += 10 * kMs) {
    const double ts = double(t - kT0) * 1e-6;
    on_circle(ts, sp);
    sp.utime = t;
    const auto cmd = c.update(sp, model.pose(t), t);
    for (int k = 0; k < 10; ++k) model.step(cmd, 0.001);
    if (ts > lap_s) worst = std::max(worst, (model.p - sp.p_W).head<2>().norm());
  }
  return worst;
}

TEST(PositionControllerTest, FollowsATurningSetpointWithItsAccelerationFedForward) {
  // Without it the loop lags the turn by about a / kp (10 cm here), twice the moving landing's
  // match tolerance; with it, what is left is the lag model's drag and attitude lag.
  EXPECT_GT(worst_offset_on_a_circle(false), 0.06);
  EXPECT_LT(worst_offset_on_a_circle(true), 0.02);
}

}  // namespace
}  // namespace alight::outer_loop

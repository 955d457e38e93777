// LCM <-> domain conversions of the autonomy messages (no network).

#include "autonomy/convert.hpp"

#include <gtest/gtest.h>

namespace alight::autonomy {
namespace {

template <class Msg>
Msg wire(const Msg& m) {
  std::vector<uint8_t> buf(m.getEncodedSize());
  EXPECT_EQ(m.encode(buf.data(), 0, buf.size()), static_cast<int>(buf.size()));
  Msg out;
  EXPECT_EQ(out.decode(buf.data(), 0, buf.size()), static_cast<int>(buf.size()));
  return out;
}

TEST(AutonomyConvertTest, ImuAndTargetRoundTrip) {
  ImuSample imu;
  imu.utime = 17;
  imu.accel_B = {0.1, -0.2, 9.9};
  imu.gyro_B = {0.01, 0.02, 0.03};
  const auto imu2 = from_msg(wire(to_msg(imu, 3)));
  EXPECT_EQ(imu2.utime, 17);
  EXPECT_EQ(imu2.accel_B, imu.accel_B);
  EXPECT_EQ(imu2.gyro_B, imu.gyro_B);

  TargetMeasurement t;
  t.utime = 99;
  t.mission = Mission::kIngress;
  t.found = true;
  t.p_W_target = {3, 0.1, 1.2};
  t.n_W = {-1, 0, 0};
  t.size_m = {0.6, 0.55};
  const auto t2 = from_msg(wire(to_msg(t, 4)));
  EXPECT_EQ(t2.mission, Mission::kIngress);
  EXPECT_TRUE(t2.found);
  EXPECT_EQ(t2.p_W_target, t.p_W_target);
  EXPECT_EQ(t2.n_W, t.n_W);
  EXPECT_EQ(t2.size_m, t.size_m);
}

TEST(AutonomyConvertTest, OperatorCommandFromTheWireIsNeverInternal) {
  operator_cmd_t m{};
  m.utime = 5;
  m.seq = 12;
  m.sender = "gs-1";
  m.command = operator_cmd_t::CMD_GO;
  m.mission = target_t::MISSION_LANDING;
  m.auth = operator_cmd_t::AUTH_NONE;
  auto c = from_msg(wire(m));
  EXPECT_EQ(c.command, Command::kGo);
  EXPECT_EQ(c.mission, Mission::kLanding);
  EXPECT_EQ(c.seq, 12);
  EXPECT_EQ(c.sender, "gs-1");
  EXPECT_EQ(c.auth, CommandAuth::kNone);
  m.auth = 77;  // unknown auth: treated as signed (and so verified or rejected), never internal
  EXPECT_EQ(from_msg(m).auth, CommandAuth::kHmacSha256);
  m.command = operator_cmd_t::CMD_KILL;
  EXPECT_EQ(from_msg(m).command, Command::kKill);
  m.command = 42;
  EXPECT_EQ(from_msg(m).command, Command::kNone);
}

TEST(AutonomyConvertTest, StatusCarriesEveryField) {
  Status s;
  s.utime = 1234;
  s.mission = Mission::kLanding;
  s.phase = Phase::kRefinement;
  s.reason = "first waypoint";
  s.n_measurements = 7;
  s.n_rejected = 2;
  s.retries = 1;
  s.has_estimate = true;
  s.estimate_W = {1, 2, 0.2};
  s.covariance << 1, 2, 3, 2, 5, 6, 3, 6, 9;
  s.setpoint_W = {1, 2, 1.2};
  s.failsafe = Failsafe::kPoseStale;
  s.cmds_rejected = 3;
  s.last_cmd_seq = 44;
  s.geofence_clamped = true;
  s.mission_time_s = 12.5;
  const auto m = wire(to_msg(s));
  EXPECT_EQ(m.phase, autonomy_status_t::PHASE_REFINEMENT);
  EXPECT_EQ(m.phase_name, "REFINEMENT");
  EXPECT_EQ(m.mission, target_t::MISSION_LANDING);
  EXPECT_EQ(m.reason, "first waypoint");
  EXPECT_EQ(m.n_measurements, 7);
  EXPECT_EQ(m.n_rejected, 2);
  EXPECT_EQ(m.retries, 1);
  EXPECT_TRUE(m.has_estimate);
  EXPECT_EQ(m.estimate_W[2], 0.2);
  EXPECT_EQ(m.covariance[1], 2);
  EXPECT_EQ(m.covariance[5], 6);
  EXPECT_EQ(m.setpoint_W[2], 1.2);
  EXPECT_EQ(m.failsafe, autonomy_status_t::FAILSAFE_POSE_STALE);
  EXPECT_EQ(m.cmds_rejected, 3);
  EXPECT_EQ(m.last_cmd_seq, 44);
  EXPECT_TRUE(m.geofence_clamped);
  EXPECT_EQ(m.mission_time_s, 12.5);
  for (Phase p : {Phase::kIdle, Phase::kTakeoff, Phase::kHover, Phase::kDetection,
                  Phase::kRefinement, Phase::kApproach, Phase::kFinalDescent, Phase::kLanded,
                  Phase::kDone, Phase::kHold, Phase::kFailsafe, Phase::kKilled}) {
    s.phase = p;
    EXPECT_EQ(to_msg(s).phase_name, phase_name(p));
  }
  EXPECT_EQ(phase_to_msg(Phase::kKilled), autonomy_status_t::PHASE_KILLED);
  EXPECT_EQ(failsafe_to_msg(Failsafe::kKill), autonomy_status_t::FAILSAFE_KILL);
}

}  // namespace
}  // namespace alight::autonomy

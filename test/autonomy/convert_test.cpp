// LCM <-> domain conversions of the autonomy messages (no network).

#include "autonomy/convert.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <utility>

#include "common/msg_convert.hpp"

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

// Located but not measured: a partial view, and an opening seen with too little parallax. Both
// keep the target in sight; neither is averaged (autonomy_test's refinement tests).
TEST(AutonomyConvertTest, LocatedOnlyTargetsArePartial) {
  target_t m{};
  m.utime = 5;
  m.mission = target_t::MISSION_INGRESS;
  m.found = false;
  m.p_W_target[0] = 3.0;
  m.n_W[0] = -1.0;
  for (const int8_t reason : {target_t::REASON_PARTIAL_VIEW, target_t::REASON_LOW_PARALLAX,
                              target_t::REASON_TOP_PARALLAX_GAP, target_t::REASON_TOP_RUNS_ON}) {
    m.reason = reason;
    const TargetMeasurement t = from_msg(wire(m));
    EXPECT_FALSE(t.found);
    EXPECT_TRUE(t.partial) << int(reason);
    EXPECT_EQ(t.p_W_target.x(), 3.0);
    // Their size is the part in view, a lower bound, where the view was cut or the top ran on.
    EXPECT_EQ(t.cut,
              reason == target_t::REASON_PARTIAL_VIEW || reason == target_t::REASON_TOP_RUNS_ON)
        << int(reason);
  }
  for (const int8_t reason : {target_t::REASON_NO_OPENING, target_t::REASON_SMALL_BASELINE}) {
    m.reason = reason;
    EXPECT_FALSE(from_msg(wire(m)).partial) << int(reason);
  }
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
  EXPECT_EQ(failsafe_to_msg(Failsafe::kEstimateLost), autonomy_status_t::FAILSAFE_ESTIMATE_LOST);
  s.failsafe = Failsafe::kEstimateLost;
  EXPECT_EQ(wire(to_msg(s)).failsafe, autonomy_status_t::FAILSAFE_ESTIMATE_LOST);
}

// --- Issue 14: the validating conversions the node uses for every input.

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

imu_t good_imu() {
  imu_t m{};
  m.utime = 10;
  m.accel_B[2] = 9.81;
  return m;
}

// Bug: an Inf IMU sample reached the touch-down detector as an impact (motors off in the air).
TEST(AutonomyConvertRegression, ImuNonFiniteOrBeyondRangeIsRefused) {
  std::string why;
  ASSERT_TRUE(imu_from_msg(good_imu(), &why));
  for (int i = 0; i < 3; ++i) {
    for (const double bad : {kNan, kInf, -kInf, 5000.0}) {
      imu_t m = good_imu();
      m.accel_B[i] = bad;
      EXPECT_FALSE(imu_from_msg(m, &why)) << i << " " << bad;
      EXPECT_NE(why.find("accel_B"), std::string::npos) << why;
      m = good_imu();
      m.gyro_B[i] = bad;
      EXPECT_FALSE(imu_from_msg(m, &why)) << i << " " << bad;
      EXPECT_NE(why.find("gyro_B"), std::string::npos) << why;
    }
  }
  imu_t hard = good_imu();
  hard.accel_B[2] = 9.81 + 60.0;  // a real touch-down spike is kept
  EXPECT_TRUE(imu_from_msg(hard, &why));
}

target_t good_target() {
  TargetMeasurement t;
  t.utime = 99;
  t.mission = Mission::kLanding;
  t.found = true;
  t.p_W_target = {1, 0.5, 0.2};
  t.n_W = {0, 0, 2};  // not unit on the wire: normalised
  t.size_m = {0.43, 0.28};
  return to_msg(t, 1);
}

// Bug: a NaN size_m skipped the vehicle-fits check; NaN anywhere in a target is refused.
TEST(AutonomyConvertRegression, TargetWithNonFiniteFieldsIsRefused) {
  std::string why;
  const auto ok = target_from_msg(good_target(), &why);
  ASSERT_TRUE(ok) << why;
  EXPECT_NEAR(ok->n_W.norm(), 1.0, 1e-12);
  const auto expect_refused = [&](target_t m, const char* field) {
    std::string w;
    EXPECT_FALSE(target_from_msg(m, &w)) << field;
    EXPECT_NE(w.find(field), std::string::npos) << w;
  };
  for (const double bad : {kNan, kInf}) {
    for (int i = 0; i < 2; ++i) {
      target_t m = good_target();
      m.size_m[i] = bad;
      expect_refused(m, "size_m");
    }
    for (int i = 0; i < 3; ++i) {
      target_t m = good_target();
      m.p_W_target[i] = bad;
      expect_refused(m, "p_W_target");
      m = good_target();
      m.n_W[i] = bad;
      expect_refused(m, "n_W");
    }
    target_t m = good_target();
    m.target_yaw_rad = bad;
    expect_refused(m, "target_yaw_rad");
  }
  target_t m = good_target();
  m.size_m[1] = -0.3;
  expect_refused(m, "size_m");
  m = good_target();
  m.n_W[0] = m.n_W[1] = m.n_W[2] = 0;
  expect_refused(m, "n_W");
  m.found = false;  // not found: the normal is not used
  m.reason = target_t::REASON_NO_TARGET_PLANE;
  EXPECT_TRUE(target_from_msg(m, &why));
}

// Bug: a signed NUDGE of NaN / Inf passed the geofence clamp.
TEST(AutonomyConvertRegression, CommandWithNonFiniteNudgeIsRefused) {
  operator_cmd_t m{};
  m.command = operator_cmd_t::CMD_NUDGE;
  m.nudge_W[0] = 0.2;
  std::string why;
  const auto ok = command_from_msg(m, &why);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->command, Command::kNudge);
  for (const double bad : {kNan, kInf, -kInf, 1e300}) {
    for (int i = 0; i < 3; ++i) {
      operator_cmd_t c = m;
      c.nudge_W[i] = bad;
      EXPECT_FALSE(command_from_msg(c, &why)) << i << " " << bad;
      EXPECT_NE(why.find("nudge_W"), std::string::npos) << why;
    }
  }
  operator_cmd_t unknown = m;
  unknown.command = 42;
  EXPECT_FALSE(command_from_msg(unknown, &why));
  EXPECT_NE(why.find("42"), std::string::npos) << why;
}

// (common/msg_convert's pose_from_msg, tested here with the autonomy's other inputs.)
TEST(AutonomyConvertRegression, PoseWithNonFiniteValuesOrBadQuaternionIsRefused) {
  pose_t good{};
  good.utime = 5;
  good.pos[2] = 1.0;
  good.orientation[0] = 1.0;
  std::string why;
  const auto p = pose_from_msg(good, &why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->p_W_B, Vector3d(0, 0, 1.0));
  const auto expect_refused = [&](const pose_t& m, const char* what) {
    std::string w;
    EXPECT_FALSE(pose_from_msg(m, &w)) << what;
    EXPECT_NE(w.find(what), std::string::npos) << w;
  };
  for (const double bad : {kNan, kInf}) {
    for (int i = 0; i < 3; ++i) {
      pose_t m = good;
      m.pos[i] = bad;
      expect_refused(m, "position");
      m = good;
      m.vel[i] = bad;
      expect_refused(m, "velocity");
      m = good;
      m.angular_velocity_B[i] = bad;
      expect_refused(m, "angular");
    }
    for (int i = 0; i < 4; ++i) {
      pose_t m = good;
      m.orientation[i] = bad;
      expect_refused(m, "orientation");
    }
  }
  pose_t zero = good;
  zero.orientation[0] = 0.0;
  expect_refused(zero, "quaternion");
  pose_t twice = good;
  twice.orientation[0] = 2.0;
  expect_refused(twice, "quaternion");
}

// --- Issue 17: the onboard estimate's health.

state_estimate_t good_estimate() {
  EstimateHealth e;
  e.utime = 77;
  return to_msg(e, 5);
}

TEST(AutonomyConvertTest, EstimateHealthAndItsReasonsFromTheWire) {
  using E = state_estimate_t;
  using L = EstimateHealth::Level;
  for (const auto& [code, level] :
       {std::pair{E::HEALTH_OK, L::kOk}, std::pair{E::HEALTH_DEGRADED, L::kDegraded},
        std::pair{E::HEALTH_LOST, L::kLost}}) {
    state_estimate_t m = good_estimate();
    m.health = code;
    m.health_reasons = int32_t{E::REASON_NO_FLOW} | E::REASON_NO_RANGE;
    std::string why;
    const auto e = estimate_from_msg(wire(m), &why);
    ASSERT_TRUE(e) << why;
    EXPECT_EQ(e->utime, 77);
    EXPECT_EQ(e->level, level);
    EXPECT_EQ(e->reasons, static_cast<uint32_t>(int32_t{E::REASON_NO_FLOW} | E::REASON_NO_RANGE));
    EXPECT_EQ(e->text, "no_flow|no_range");
    // And back: the message form tests and tools send.
    EstimateHealth h;
    h.utime = 9;
    h.level = level;
    h.reasons = 4;
    const auto back = estimate_from_msg(wire(to_msg(h, 1)), &why);
    ASSERT_TRUE(back) << why;
    EXPECT_EQ(back->level, level);
    EXPECT_EQ(back->reasons, 4u);
    EXPECT_EQ(back->utime, 9);
  }
  EXPECT_EQ(estimate_reasons_text(0), "");
  EXPECT_EQ(estimate_reasons_text(511),
            "not_initialised|no_flow|no_range|no_baro|position_uncertain|velocity_uncertain|"
            "imu_gap|imu_stopped|height_uncertain");
  // A newer estimator's reasons are named by their bit, not dropped.
  EXPECT_EQ(estimate_reasons_text(uint32_t{E::REASON_IMU_STOPPED} | (1u << 12)),
            "imu_stopped|bit_12");
  state_estimate_t top = good_estimate();
  top.health = E::HEALTH_DEGRADED;
  top.health_reasons = std::numeric_limits<int32_t>::min();  // bit 31 on the wire
  std::string why;
  EXPECT_EQ(estimate_from_msg(top, &why)->text, "bit_31");
}

// Every field of a state_estimate_t is checked, not only the health the autonomy reads: NaN
// anywhere is a broken estimator, refused (so silent, so LOST after estimate_silent_s).
TEST(AutonomyConvertRegression, EstimateWithNonFiniteOrAbsurdValuesIsRefused) {
  std::string why;
  ASSERT_TRUE(estimate_from_msg(good_estimate(), &why)) << why;
  const auto expect_refused = [&](const state_estimate_t& m, const char* field) {
    std::string w;
    EXPECT_FALSE(estimate_from_msg(m, &w)) << field;
    EXPECT_NE(w.find(field), std::string::npos) << field << ": " << w;
  };
  for (const double bad : {kNan, kInf, -kInf}) {
    for (int i = 0; i < 3; ++i) {
      state_estimate_t m = good_estimate();
      m.pos[i] = bad;
      expect_refused(m, "pos");
      m = good_estimate();
      m.vel[i] = bad;
      expect_refused(m, "vel");
      m = good_estimate();
      m.angular_velocity_B[i] = bad;
      expect_refused(m, "angular_velocity_B");
      m = good_estimate();
      m.accel_bias_B[i] = bad;
      expect_refused(m, "accel_bias_B");
      m = good_estimate();
      m.gyro_bias_B[i] = bad;
      expect_refused(m, "gyro_bias_B");
    }
    for (int i = 0; i < 4; ++i) {
      state_estimate_t m = good_estimate();
      m.orientation[i] = bad;
      expect_refused(m, "orientation");
    }
    for (const int k : {0, 1, 40, 80}) {
      state_estimate_t m = good_estimate();
      m.cov_pva[k] = bad;
      expect_refused(m, "cov_pva");
    }
    state_estimate_t m = good_estimate();
    m.terrain_height_m = bad;
    expect_refused(m, "terrain_height_m");
    m = good_estimate();
    m.baro_offset_m = bad;
    expect_refused(m, "baro_offset_m");
  }
  for (const int8_t code : {int8_t{3}, int8_t{-1}, int8_t{127}}) {
    state_estimate_t m = good_estimate();
    m.health = code;
    expect_refused(m, "unknown health");
  }
  state_estimate_t m = good_estimate();
  m.orientation[0] = 0.0;
  expect_refused(m, "unit quaternion");
  m.orientation[0] = 2.0;
  expect_refused(m, "unit quaternion");
  m = good_estimate();
  m.cov_pva[40] = -1e-3;
  expect_refused(m, "negative variance");
  m = good_estimate();
  m.pos[1] = -1e6;
  expect_refused(m, "pos beyond");
  m = good_estimate();
  m.cov_pva[10] = 1e9;  // a 31 km standard deviation
  expect_refused(m, "position variance beyond");
}

// The position block of cov_pva reaches autonomy (its growth is the frame's drift), symmetrised.
TEST(AutonomyConvertTest, EstimatePositionCovarianceFromTheWire) {
  state_estimate_t m = good_estimate();
  m.cov_pva[0] = 0.04;
  m.cov_pva[1] = 0.01;  // (x, y)
  m.cov_pva[9] = 0.03;  // (y, x): an asymmetric sender
  m.cov_pva[10] = 0.09;
  m.cov_pva[20] = 0.0025;
  m.cov_pva[30] = 7.0;  // a velocity variance: not the position's
  std::string why;
  const auto e = estimate_from_msg(wire(m), &why);
  ASSERT_TRUE(e) << why;
  EXPECT_DOUBLE_EQ(e->position_cov(0, 0), 0.04);
  EXPECT_DOUBLE_EQ(e->position_cov(0, 1), 0.02);
  EXPECT_DOUBLE_EQ(e->position_cov(1, 0), 0.02);
  EXPECT_DOUBLE_EQ(e->position_cov(1, 1), 0.09);
  EXPECT_DOUBLE_EQ(e->position_cov(2, 2), 0.0025);
}

// The surface under the rangefinder reaches autonomy only while the estimator fuses a
// rangefinder (moving_landing.hpp step 7): none fused yet, or one gone silent (REASON_NO_RANGE),
// says nothing of what is under the vehicle.
TEST(AutonomyConvertTest, TerrainFromTheWireOnlyWhileARangefinderIsFused) {
  state_estimate_t m = good_estimate();
  m.terrain_height_m = 0.21;
  std::string why;
  EXPECT_FALSE(estimate_from_msg(wire(m), &why)->terrain_m);  // no range fused
  m.n_fused[1] = 40;
  ASSERT_TRUE(estimate_from_msg(wire(m), &why)->terrain_m);
  EXPECT_DOUBLE_EQ(*estimate_from_msg(wire(m), &why)->terrain_m, 0.21);
  m.health = state_estimate_t::HEALTH_DEGRADED;
  m.health_reasons = state_estimate_t::REASON_NO_RANGE;
  EXPECT_FALSE(estimate_from_msg(wire(m), &why)->terrain_m);
  m.health_reasons = state_estimate_t::REASON_NO_FLOW;  // another reason: the range still holds
  EXPECT_TRUE(estimate_from_msg(wire(m), &why)->terrain_m);
  EstimateHealth h;  // and back
  h.terrain_m = -0.004;
  const auto back = estimate_from_msg(wire(to_msg(h, 1)), &why);
  ASSERT_TRUE(back && back->terrain_m) << why;
  EXPECT_DOUBLE_EQ(*back->terrain_m, -0.004);
}

TEST(ConvertTest, PlatformMeasurementRoundTripsAndBadOnesAreRefusedWithAReason) {
  PlatformMeasurement p;
  p.utime = 2'000'000;
  p.ref_utime = 1'750'000;
  p.p_W = Vector3d(0.5, -0.2, 0.15);
  p.v_W = Vector3d(0.8, 0.1, -0.02);
  p.yaw_rad = 0.3;
  p.yaw_rate_rps = 0.05;
  p.size_m = Vector2d(0.43, 0.28);
  std::string why;
  const auto back = platform_from_msg(to_msg(p, 4), &why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->utime, p.utime);
  EXPECT_EQ(back->ref_utime, p.ref_utime);
  EXPECT_EQ(back->p_W, p.p_W);
  EXPECT_EQ(back->v_W, p.v_W);
  EXPECT_EQ(back->cov_p_W, p.cov_p_W);
  EXPECT_EQ(back->size_m, p.size_m);
  // Not found: nothing to fuse, nothing refused.
  auto m = to_msg(p, 4);
  m.found = false;
  why.clear();
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_TRUE(why.empty());
  // A newer version, a non-finite field, a negative variance, an earlier frame not before.
  m = to_msg(p, 4);
  m.version = platform_motion_t::VERSION + 1;
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_NE(why.find("newer"), std::string::npos) << why;
  m = to_msg(p, 4);
  m.v_W[1] = NAN;
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_NE(why.find("non-finite"), std::string::npos) << why;
  m = to_msg(p, 4);
  m.cov_p_W[4] = -1;
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_NE(why.find("negative"), std::string::npos) << why;
  m = to_msg(p, 4);
  m.ref_utime = m.utime;
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_NE(why.find("earlier frame"), std::string::npos) << why;
  // Without cameras: a version-1 message, read with the top at vision's plane.
  EXPECT_EQ(to_msg(p, 4).version, 1);
  EXPECT_FALSE(platform_from_msg(to_msg(p, 4), &why)->placed_from_cameras());
  // Version 2: the cameras and the plane come through; non-finite or a camera not above the
  // plane is refused.
  p.camera_W = Vector3d(0.6, -0.1, 1.0);
  p.ref_camera_W = Vector3d(0.4, -0.1, 1.1);
  p.plane_z_m = 0.15;
  m = to_msg(p, 4);
  EXPECT_EQ(m.version, platform_motion_t::VERSION);
  const auto placed = platform_from_msg(m, &why);
  ASSERT_TRUE(placed) << why;
  EXPECT_EQ(placed->camera_W, p.camera_W);
  EXPECT_EQ(placed->ref_camera_W, p.ref_camera_W);
  EXPECT_EQ(placed->plane_z_m, 0.15);
  m.ref_camera_W[2] = NAN;
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_NE(why.find("ref_camera_W"), std::string::npos) << why;
  m = to_msg(p, 4);
  m.camera_W[2] = 0.1;
  EXPECT_FALSE(platform_from_msg(m, &why));
  EXPECT_NE(why.find("not above"), std::string::npos) << why;
  // An older sender (version 1) is read without them, whatever the fields hold.
  m = to_msg(p, 4);
  m.version = 1;
  m.camera_W[0] = NAN;
  const auto old = platform_from_msg(m, &why);
  ASSERT_TRUE(old) << why;
  EXPECT_FALSE(old->placed_from_cameras());
}

}  // namespace
}  // namespace alight::autonomy

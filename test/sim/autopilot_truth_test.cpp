// alight-sim as a sensor renderer for a real autopilot's SITL (issue 38): the true state from
// SIM_STATE (ArduPilot) and HIL_STATE_QUATERNION (PX4) in alight's world, its smoothing, and the
// simulator following it with contact judged against the scene.
#include "sim/autopilot_truth.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "mavlink/ned_frd.hpp"
#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

namespace mav = alight::mavlink;

constexpr int32_t kLat = -353632620, kLon = 1491652370;  // ArduPilot SITL's home (degE7)
constexpr int64_t kT0 = 1'800'000'000'000'000;

/// The autopilot's side: heartbeats and truth messages as frames.
struct Sitl {
  mav::Sender tx{1, 1};
  std::vector<uint8_t> bytes;
  template <class M>
  void say(const M& m) {
    const auto f = tx.pack(m, 0);
    bytes.insert(bytes.end(), f.bytes().begin(), f.bytes().end());
  }
  void heartbeat(bool armed) {
    mav::Heartbeat hb;
    hb.autopilot = mav::mav_autopilot::kArdupilotmega;
    hb.base_mode = armed ? mav::mav_mode_flag::kSafetyArmed : 0;
    say(hb);
  }
  /// SIM_STATE of a vehicle `north_m` / `east_m` / `up_m` from home, heading `yaw_ned`.
  void sim_state(double north_m, double east_m, double up_m, double yaw_ned,
                 Vector3d v_NED = Vector3d::Zero()) {  // (Eigen leaves `{}` uninitialised)
    mav::SimState s;
    const auto q = mav::wxyz_float(Quaterniond(Eigen::AngleAxisd(yaw_ned, Vector3d::UnitZ())));
    s.q1 = q[0], s.q2 = q[1], s.q3 = q[2], s.q4 = q[3];
    // Location::offset, the inverse of the conversion under test (1e-7 deg per 1.113 cm).
    const double scale = std::cos(kLat * 1e-7 * M_PI / 180);
    s.lat_int = kLat + static_cast<int32_t>(std::lround(north_m / 0.011131884502145034));
    s.lon_int = kLon + static_cast<int32_t>(std::lround(east_m / 0.011131884502145034 / scale));
    s.lat = static_cast<float>(s.lat_int);  // ArduPilot's float lat / lon hold degE7
    s.lon = static_cast<float>(s.lon_int);
    s.alt = static_cast<float>(584.0 + up_m);
    s.vn = static_cast<float>(v_NED.x());
    s.ve = static_cast<float>(v_NED.y());
    s.vd = static_cast<float>(v_NED.z());
    say(s);
  }
  std::vector<uint8_t> take() {
    std::vector<uint8_t> out;
    out.swap(bytes);
    return out;
  }
};

AutopilotTruthParams params() {
  AutopilotTruthParams p;
  p.flavour = mav::Flavour::kArdupilot;
  p.start_W = Vector3d(0.5, -0.2, 0.209);
  p.start_yaw_rad = 0.0;  // east
  return p;
}

TEST(AutopilotTruthTest, NorthAndEastOffsetsAreTheAutopilotsOwn) {
  // ArduPilot: 0.011131884502145034 m per 1e-7 deg of latitude (libraries/AP_Common/
  // Location.h), longitude scaled by the cosine of the mean latitude.
  const Vector2d ne =
      AutopilotTruth::north_east_m(mav::Flavour::kArdupilot, kLat + 100, kLon + 100, kLat, kLon);
  EXPECT_NEAR(ne.x(), 1.1131884502145034, 1e-9);
  EXPECT_NEAR(ne.y(), 1.1131884502145034 * std::cos((kLat + 50) * 1e-7 * M_PI / 180), 1e-7);
  // PX4: a sphere of 6371 km about the reference (src/lib/geo).
  const Vector2d px = AutopilotTruth::north_east_m(mav::Flavour::kPx4, 473977420 + 100, 85455940,
                                                   473977420, 85455940);
  EXPECT_NEAR(px.x(), 6371000.0 * 1e-5 * M_PI / 180, 1e-9);
  // Across the date line.
  const Vector2d w =
      AutopilotTruth::north_east_m(mav::Flavour::kPx4, 0, -1799999990, 0, 1799999990);
  EXPECT_NEAR(w.y(), 20 * 6371000.0 * 1e-7 * M_PI / 180, 1e-6);
}

TEST(AutopilotTruthTest, TheFirstSampleIsTheStartAndTheWorldIsTurnedToItsHeading) {
  AutopilotTruth truth(params());
  Sitl sitl;
  sitl.heartbeat(false);
  // The SITL vehicle faces north (yaw 0 NED); the scenario starts facing east (world yaw 0).
  sitl.sim_state(0, 0, 0, 0.0);
  auto out = truth.update(sitl.take(), kT0);
  ASSERT_EQ(out.samples.size(), 1u);
  EXPECT_TRUE((out.samples[0].state.p_W_B - params().start_W).norm() < 1e-9);
  EXPECT_NEAR(yaw_of(out.samples[0].state.q_WB.toRotationMatrix()), 0.0, 1e-6);
  // 1 m north is 1 m forward: world +x.
  sitl.sim_state(1.0, 0, 0.5, 0.0, Vector3d(1, 0, -0.5));
  out = truth.update(sitl.take(), kT0 + 1'000'000);
  ASSERT_EQ(out.samples.size(), 1u);
  const Vector3d p = out.samples[0].state.p_W_B - params().start_W;
  // A second apart: nothing to integrate over, the measured position.
  EXPECT_NEAR(p.x(), 1.0, 0.006);
  EXPECT_NEAR(p.y(), 0.0, 0.006);
  EXPECT_NEAR(p.z(), 0.5, 1e-3);
  EXPECT_NEAR(out.samples[0].state.v_W_B.x(), 1.0, 1e-6);
  EXPECT_NEAR(out.samples[0].state.v_W_B.z(), 0.5, 1e-6);
}

TEST(AutopilotTruthTest, AQuantisedPositionIsSmoothedByTheVelocity) {
  AutopilotTruth truth(params());
  Sitl sitl;
  // 0.2 m/s east for 2 s at 100 Hz: latitude and longitude step by whole 1e-7 degrees.
  double max_step = 0, max_error = 0;
  Vector3d prev = Vector3d::Zero();
  for (int i = 0; i <= 200; ++i) {
    const double east = 0.2 * i * 0.01;
    sitl.sim_state(0, east, 1.0, M_PI / 2, Vector3d(0, 0.2, 0));
    const auto out = truth.update(sitl.take(), kT0 + i * 10'000);
    ASSERT_EQ(out.samples.size(), 1u);
    const Vector3d p = out.samples[0].state.p_W_B;
    if (i > 0) max_step = std::max(max_step, (p - prev).norm());
    // Facing east at the start: east is world +x.
    if (i > 50) max_error = std::max(max_error, std::abs(p.x() - params().start_W.x() - east));
    prev = p;
  }
  EXPECT_LT(max_step, 0.0025);  // 2 mm per 10 ms: the speed's, never a 1.1 cm quantum
  EXPECT_LT(max_error, 0.006);  // within the quantum of the truth
}

TEST(AutopilotTruthTest, TheSmoothedTrajectoryFollowsLateSamplesWithoutSteps) {
  AutopilotTruth truth(params());
  Sitl sitl;
  sitl.sim_state(0, 0, 1.0, 0.0);
  truth.update(sitl.take(), kT0);
  // Samples of a vehicle rising at 1 m/s arrive in bursts of three, 30 ms apart, all stamped
  // on arrival; advance() at every millisecond stays smooth.
  double max_jump = 0;
  VehicleState prev = truth.advance(kT0);
  int n = 1;
  for (int64_t t = kT0 + 1000; t < kT0 + 2'000'000; t += 1000) {
    if ((t - kT0) % 30'000 == 0) {
      for (int k = 0; k < 3; ++k, ++n) sitl.sim_state(0, 0, 1.0 + n * 0.01, 0.0, {0, 0, -1});
      truth.update(sitl.take(), t);
    }
    const VehicleState s = truth.advance(t);
    max_jump = std::max(max_jump, (s.p_W_B - prev.p_W_B).norm() - 0.001);
    prev = s;
  }
  EXPECT_LT(max_jump, 0.001);  // at most 1 mm beyond the 1 mm per ms of the climb
  EXPECT_NEAR(prev.v_W_B.z(), 1.0, 0.05);
}

TEST(AutopilotTruthTest, AVehicleBelowTheSitlsGroundIsHeldAtIt) {
  // PX4 SIH's ground holds a vehicle only while the net force points down: one that arrives at
  // hover thrust sinks through it. The anchor stood on that ground.
  AutopilotTruth truth(params());
  Sitl sitl;
  sitl.sim_state(0, 0, 0, 0.0);
  truth.update(sitl.take(), kT0);
  for (int i = 1; i <= 50; ++i) {
    sitl.sim_state(0, 0, -0.16 * i / 50.0, 0.0, Vector3d(0, 0, 0.25));
    const auto out = truth.update(sitl.take(), kT0 + i * 10'000);
    ASSERT_EQ(out.samples.size(), 1u);
    EXPECT_NEAR(out.samples[0].state.p_W_B.z(), params().start_W.z(), 1e-9);
    EXPECT_LE(out.samples[0].state.v_W_B.z(), 1e-9);  // not sinking
  }
}

TEST(AutopilotTruthTest, AsksForTheTruthAndFollowsTheArmedState) {
  AutopilotTruth truth(params());
  Sitl sitl;
  sitl.heartbeat(true);
  const auto out = truth.update(sitl.take(), kT0);
  EXPECT_TRUE(truth.armed());
  mav::Parser parser;
  parser.push(out.bytes);
  mav::Frame f;
  bool asked = false;
  while (parser.next(f))
    if (const auto c = mav::decode<mav::CommandLong>(f))
      asked = asked || (c->command == mav::mav_cmd::kSetMessageInterval &&
                        c->param1 == mav::SimState::kId && c->param2 == 10'000);
  EXPECT_TRUE(asked);
  EXPECT_TRUE(truth.advance(kT0).armed);
}

TEST(AutopilotTruthTest, Px4sHilStateQuaternionIsReadInItsUnits) {
  AutopilotTruthParams p = params();
  p.flavour = mav::Flavour::kPx4;
  AutopilotTruth truth(p);
  mav::Sender tx{1, 1};
  std::vector<uint8_t> bytes;
  mav::HilStateQuaternion m;
  m.lat = 473977420;
  m.lon = 85455940;
  m.alt = 488000;
  auto f = tx.pack(m, 0);
  bytes.assign(f.bytes().begin(), f.bytes().end());
  truth.update(bytes, kT0);
  m.alt = 489250;  // mm
  m.vz = -50;      // cm/s, down
  f = tx.pack(m, 0);
  bytes.assign(f.bytes().begin(), f.bytes().end());
  const auto out = truth.update(bytes, kT0 + 5'000'000);
  ASSERT_EQ(out.samples.size(), 1u);
  EXPECT_NEAR(out.samples[0].state.p_W_B.z() - p.start_W.z(), 1.25, 0.01);
  EXPECT_NEAR(out.samples[0].state.v_W_B.z(), 0.5, 1e-6);
}

TEST(AutopilotTruthTest, CorruptSamplesAreCountedNotUsed) {
  AutopilotTruth truth(params());
  Sitl sitl;
  mav::SimState s;
  s.q1 = 0;  // not an attitude
  s.lat_int = kLat;
  s.lon_int = kLon;
  sitl.say(s);
  s.q1 = 1;
  s.alt = std::numeric_limits<float>::quiet_NaN();
  sitl.say(s);
  const auto out = truth.update(sitl.take(), kT0);
  EXPECT_TRUE(out.samples.empty());
  EXPECT_EQ(truth.rejected(), 2u);
}

TEST(SimFollowTest, AVehicleRestingOnThePlatformTopAsTheSitlsGroundHasLanded) {
  // The SITL's flat ground is the platform's top: resting there, disarmed, within the top's
  // outline, is a landing; beside it, in the air at the same height, is not.
  for (const double offset : {0.0, 0.4}) {
    SCOPED_TRACE(offset);
    const Scenario sc = test::quiet(test::scenario("landing_a"));
    const VehicleParams v = test::starmac();
    Simulator sim(sc, v, 1);
    const PlatformTruth p = *sim.truth().platform;
    VehicleState s;
    s.p_W_B = p.top_center_W + Vector3d(offset, 0, sim.dynamics().resting_height(0.0));
    s.q_WB = Quaterniond(rotation_from_rpy(0, 0, p.yaw_rad));
    s.armed = false;
    sim.follow([&](int64_t) { return s; }, sim.now_utime() + 500'000, 0.01);
    const Truth t = sim.truth();
    EXPECT_EQ(t.landed, offset == 0.0);
    EXPECT_EQ(t.contact, offset == 0.0 ? Contact::kPlatformTop : Contact::kNone);
    EXPECT_FALSE(t.tipped);
  }
}

TEST(SimFollowTest, TheFollowedStateIsWhatMotionCaptureSees) {
  const Scenario sc = test::scenario("landing_a");
  Simulator sim(sc, test::starmac(), 1);
  sim.take_mocap();
  const int64_t t0 = sim.now_utime();
  const auto at = [&](int64_t t) {
    VehicleState s;
    s.p_W_B = Vector3d(0.3 * (t - t0) * 1e-6, 0, 1.0);
    s.v_W_B = Vector3d(0.3, 0, 0);
    s.armed = true;
    return s;
  };
  sim.follow(at, t0 + 1'000'000, 0.01);
  const auto mocap = sim.take_mocap();
  ASSERT_GT(mocap.size(), 80u);
  for (const auto& m : mocap) {
    if (m.pose.utime <= t0) continue;  // sampled before it followed
    EXPECT_NEAR(m.pose.p_W_B.x(), 0.3 * (m.pose.utime - t0) * 1e-6, 0.003);
    EXPECT_NEAR(m.pose.p_W_B.z(), 1.0, 0.003);
  }
  EXPECT_TRUE(sim.take_imu().empty());  // the autopilot's own IMU is the IMU
}

}  // namespace
}  // namespace alight::sim

// Every alight type survives encode -> decode -> encode byte for byte with all fields set, and
// image_t has bot_core.image_t's fingerprint (computed by lcm-gen from bot_core's layout).
#include <gtest/gtest.h>

#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/target_t.hpp>
#include <bot_core/image_t.hpp>
#include <random>
#include <set>

namespace alight {
namespace {

std::mt19937_64 rng(2011);
double d() { return std::uniform_real_distribution<double>(-100, 100)(rng); }
int64_t i64() { return static_cast<int64_t>(rng() >> 1); }
int32_t i32() { return static_cast<int32_t>(rng() >> 40); }
template <size_t N>
void fill(double (&a)[N]) {
  for (auto& x : a) x = d();
}

template <class T>
std::vector<uint8_t> encode(const T& m) {
  std::vector<uint8_t> buf(m.getEncodedSize());
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

// Decodes and re-encodes; the bytes must be identical, and every field is compared that way.
template <class T>
T round_trip(const T& m) {
  const auto bytes = encode(m);
  T back;
  EXPECT_EQ(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(encode(back), bytes);
  // A truncated buffer never decodes.
  T partial;
  EXPECT_LT(partial.decode(bytes.data(), 0, static_cast<int>(bytes.size()) - 1), 0);
  return back;
}

TEST(LcmTypesTest, ImageRoundTrip) {
  image_t m{};
  m.utime = i64();
  m.width = 4;
  m.height = 3;
  m.row_stride = 4;
  m.pixelformat = image_t::PIXEL_FORMAT_GRAY;
  m.data.resize(12);
  for (auto& b : m.data) b = static_cast<uint8_t>(rng());
  m.size = 12;
  m.metadata.resize(2);
  m.metadata[0].key = "seq";
  m.metadata[0].value = {1, 2, 3, 4, 5, 6, 7, 8};
  m.metadata[0].n = 8;
  m.metadata[1].key = "camera";
  m.metadata[1].value = {'f', 'm'};
  m.metadata[1].n = 2;
  m.nmetadata = 2;
  const auto back = round_trip(m);
  EXPECT_EQ(back.data, m.data);
  EXPECT_EQ(back.metadata[1].key, "camera");
}

TEST(LcmTypesTest, PoseImuRoundTrip) {
  pose_t p{};
  p.utime = i64();
  p.seq = i64();
  fill(p.pos);
  fill(p.vel);
  fill(p.orientation);
  fill(p.angular_velocity_B);
  p.status = pose_t::STATUS_COASTING;
  EXPECT_EQ(round_trip(p).pos[2], p.pos[2]);
  imu_t u{};
  u.utime = i64();
  u.seq = 3;
  fill(u.accel_B);
  fill(u.gyro_B);
  EXPECT_EQ(round_trip(u).gyro_B[1], u.gyro_B[1]);
}

TEST(LcmTypesTest, TargetRoundTrip) {
  target_t t{};
  t.utime = i64();
  t.ref_utime = i64();
  t.seq = 9;
  t.mission = target_t::MISSION_INGRESS;
  t.found = true;
  t.reason = target_t::REASON_OK;
  fill(t.p_W_target);
  fill(t.n_W);
  fill(t.pixel);
  t.target_height_m = d();
  fill(t.size_m);
  t.baseline_m = d();
  t.n_features = i32();
  t.n_matches = i32();
  t.n_inliers_dominant = i32();
  t.n_inliers_target = i32();
  EXPECT_EQ(round_trip(t).size_m[0], t.size_m[0]);
}

TEST(LcmTypesTest, CommandAndStatusRoundTrip) {
  operator_cmd_t c{};
  c.utime = i64();
  c.seq = 77;
  c.sender = "ground-1";
  c.command = operator_cmd_t::CMD_GO;
  c.mission = target_t::MISSION_LANDING;
  fill(c.nudge_W);
  c.auth = operator_cmd_t::AUTH_HMAC_SHA256;
  for (auto& b : c.hmac) b = static_cast<uint8_t>(rng());
  EXPECT_EQ(round_trip(c).sender, "ground-1");

  autonomy_status_t s{};
  s.utime = i64();
  s.mission = 1;
  s.phase = autonomy_status_t::PHASE_REFINEMENT;
  s.phase_name = "REFINEMENT";
  s.reason = "first waypoint";
  s.n_measurements = 7;
  s.n_rejected = 1;
  s.retries = 0;
  s.has_estimate = true;
  fill(s.estimate_W);
  fill(s.covariance);
  fill(s.setpoint_W);
  s.failsafe = autonomy_status_t::FAILSAFE_NONE;
  s.cmds_rejected = 2;
  s.last_cmd_seq = 77;
  EXPECT_EQ(round_trip(s).phase_name, "REFINEMENT");

  position_setpoint_t sp{};
  sp.utime = i64();
  fill(sp.p_W);
  fill(sp.v_W);
  sp.yaw_rad = d();
  sp.motors = position_setpoint_t::MOTORS_ON;
  round_trip(sp);

  attitude_cmd_t a{};
  a.utime = i64();
  a.roll_rad = d();
  a.pitch_rad = d();
  a.yaw_rate_radps = d();
  a.thrust_N = d();
  a.armed = true;
  a.mode = attitude_cmd_t::MODE_FAILSAFE_DESCENT;
  round_trip(a);
}

TEST(LcmTypesTest, TruthAndProcessStatusRoundTrip) {
  sim_truth_t t{};
  t.utime = i64();
  t.scenario = "landing_a";
  fill(t.pos);
  fill(t.vel);
  fill(t.orientation);
  t.has_platform = true;
  fill(t.platform_center_W);
  fill(t.platform_size_m);
  t.platform_yaw_rad = d();
  fill(t.opening_center_W);
  fill(t.opening_size_m);
  fill(t.wall_normal_W);
  t.contact = sim_truth_t::CONTACT_PLATFORM_TOP;
  t.landed = true;
  t.n_collisions = 0;
  EXPECT_EQ(round_trip(t).scenario, "landing_a");

  process_status_t ps{};
  ps.utime = i64();
  ps.launch_name = "sim_landing";
  ps.session_dir = "logs/20261122-101500-sim_landing";
  ps.processes.resize(3);
  for (int i = 0; i < 3; ++i) {
    ps.processes[i].name = "p" + std::to_string(i);
    ps.processes[i].pid = 100 + i;
    ps.processes[i].state = process_info_t::STATE_BACKOFF;
    ps.processes[i].restarts = i;
    ps.processes[i].backoff_s = 0.02;
  }
  ps.n = 3;
  EXPECT_EQ(round_trip(ps).processes[2].name, "p2");
}

TEST(LcmTypesTest, ImageFingerprintEqualsBotCoreImage) {
  EXPECT_EQ(alight::image_t::getHash(), bot_core::image_t::getHash());
  // And the wire bytes of a bot_core image decode as ours.
  bot_core::image_t b{};
  b.utime = 5;
  b.width = 2;
  b.height = 1;
  b.row_stride = 2;
  b.pixelformat = image_t::PIXEL_FORMAT_GRAY;
  b.data = {7, 9};
  b.size = 2;
  b.nmetadata = 0;
  const auto bytes = encode(b);
  image_t ours;
  ASSERT_EQ(ours.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(ours.data, b.data);
}

TEST(LcmTypesTest, DistinctTypesHaveDistinctFingerprints) {
  const std::vector<int64_t> hashes = {image_t::getHash(),
                                       pose_t::getHash(),
                                       imu_t::getHash(),
                                       target_t::getHash(),
                                       operator_cmd_t::getHash(),
                                       autonomy_status_t::getHash(),
                                       position_setpoint_t::getHash(),
                                       attitude_cmd_t::getHash(),
                                       sim_truth_t::getHash(),
                                       process_status_t::getHash()};
  std::set<int64_t> unique(hashes.begin(), hashes.end());
  EXPECT_EQ(unique.size(), hashes.size());
}

}  // namespace
}  // namespace alight

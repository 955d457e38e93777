// The tracker client without sockets: object and sensor selection, refusals, the three stamp
// sources, finite-difference and server velocities, several connections.

#include "mocap/tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "tools/vrpn_test_server.hpp"

namespace alight::mocap {
namespace {

using tools::ServedPose;
using tools::VrpnTestServer;

constexpr int64_t kT0 = 1'700'000'000'000'000;  // server stamps [us]
constexpr int32_t kPosQuat = 11, kVelocity = 12, kPelican = 7, kOther = 8;

std::vector<uint8_t> name(const std::string& n) {
  std::vector<uint8_t> p;
  vrpn::put_u32(p, static_cast<uint32_t>(n.size() + 1));
  p.insert(p.end(), n.begin(), n.end());
  p.push_back(0);
  return p;
}

void append_bytes(std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
}

std::vector<uint8_t> tracker_opening() {
  std::vector<uint8_t> s(24, 0);
  std::memcpy(s.data(), "vrpn: ver. 07.38  0", 19);
  append_bytes(s, VrpnTestServer::frame(-1, kPelican, 1, name("Pelican")));
  append_bytes(s, VrpnTestServer::frame(-1, kOther, 1, name("Other")));
  append_bytes(s, VrpnTestServer::frame(-2, kPosQuat, 1, name("vrpn_Tracker Pos_Quat")));
  append_bytes(s, VrpnTestServer::frame(-2, kVelocity, 1, name("vrpn_Tracker Velocity")));
  return s;
}

ServedPose served(int64_t stamp_us, const Vector3d& p,
                  const Quaterniond& q = Quaterniond::Identity(),
                  const std::string& object = "Pelican", int sensor = 0) {
  ServedPose s;
  s.object = object;
  s.sensor = sensor;
  s.stamp_us = stamp_us;
  for (int i = 0; i < 3; ++i) s.pos[i] = p[i];
  s.quat_xyzw[0] = q.x(), s.quat_xyzw[1] = q.y(), s.quat_xyzw[2] = q.z(), s.quat_xyzw[3] = q.w();
  return s;
}

std::vector<uint8_t> tracker_pose_frame(const ServedPose& p) {
  const int32_t sender = p.object == "Pelican" ? kPelican : kOther;
  return VrpnTestServer::frame(kPosQuat, sender, p.stamp_us, VrpnTestServer::pose_payload(p));
}

std::vector<uint8_t> velocity_frame(int64_t stamp_us, const Vector3d& v) {
  std::vector<uint8_t> p;
  vrpn::put_u32(p, 0);
  vrpn::put_u32(p, 0);
  for (double x : {v.x(), v.y(), v.z(), 0.0, 0.0, 0.0, 1.0, 0.0}) vrpn::put_f64(p, x);
  return VrpnTestServer::frame(kVelocity, kPelican, stamp_us, p);
}

MocapParams params(const std::string& stamp_source = "server") {
  MocapParams p;
  p.server.tracker = "Pelican@vicon";
  p.stamp.source = stamp_source;
  return p;
}

// Feeds the opening, then each frame as its own read at the given receipt time.
struct Feeder {
  TrackerClient client;
  explicit Feeder(const MocapParams& p) : client(p) {
    const auto o = tracker_opening();
    EXPECT_TRUE(client.on_bytes(o.data(), o.size(), kT0).empty());
  }
  std::vector<TrackerPose> feed(const std::vector<uint8_t>& bytes, int64_t recv_utime) {
    return client.on_bytes(bytes.data(), bytes.size(), recv_utime);
  }
};

TEST(TrackerClientTest, GreetingIsOurCookieAndDescriptionsOfWhatWeListenTo) {
  const TrackerClient client(params());
  const auto g = client.greeting(kT0);
  ASSERT_GE(g.size(), 24u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(g.data())), "vrpn: ver. 07.35  0");
  vrpn::StreamDecoder d;
  std::vector<vrpn::TrackerReport> out;
  ASSERT_TRUE(d.feed(g.data(), g.size(), out));
  EXPECT_EQ(d.sender_name(0), "Pelican");
  EXPECT_EQ(d.type_name(0), "vrpn_Tracker Pos_Quat");
  EXPECT_EQ(d.type_name(1), "vrpn_Tracker Velocity");
  EXPECT_EQ(d.pending_bytes(), 0u);
}

TEST(TrackerClientTest, FirstPoseIsHeldBackThenVelocitiesByDifference) {
  Feeder f(params());
  const Vector3d v(0.5, -1.0, 0.2);  // m/s
  const double yaw_rate = 0.8;       // rad/s
  std::vector<TrackerPose> got;
  for (int i = 0; i < 10; ++i) {
    const int64_t t = kT0 + i * 10'000;  // 100 Hz
    const double s = i * 0.01;
    const auto q = Quaterniond(Eigen::AngleAxisd(yaw_rate * s, Vector3d::UnitZ()));
    for (const auto& p :
         f.feed(tracker_pose_frame(served(t, Vector3d(1, 2, 3) + v * s, q)), t + 3000))
      got.push_back(p);
  }
  ASSERT_EQ(got.size(), 9u);
  EXPECT_EQ(f.client.stats().held_back, 1u);
  for (size_t k = 0; k < got.size(); ++k) {
    const auto& p = got[k].pose;
    EXPECT_EQ(p.utime, kT0 + int64_t(k + 1) * 10'000);  // "server": the stamps as they are
    EXPECT_EQ(got[k].delay_us, 3000);
    EXPECT_LT((p.v_W_B - v).norm(), 1e-9);
    EXPECT_LT((p.omega_B - Vector3d(0, 0, yaw_rate)).norm(), 1e-9);
    EXPECT_LT((p.p_W_B - (Vector3d(1, 2, 3) + v * (k + 1) * 0.01)).norm(), 1e-12);
  }
  EXPECT_EQ(f.client.stats().poses, 9u);
}

TEST(TrackerClientTest, DifferenceSpansAtLeastSpanAtHighRates) {
  MocapParams p = params();
  p.velocity.span_s = 0.01;
  Feeder f(p);
  // 400 Hz with alternating position noise of +-0.1 mm: over one sample the difference would be
  // 0.08 m/s off, over >= 10 ms it is within 0.02 m/s.
  std::vector<TrackerPose> got;
  for (int i = 0; i < 40; ++i) {
    const int64_t t = kT0 + i * 2500;
    const double noise = (i % 2 ? 1 : -1) * 1e-4;
    for (const auto& x :
         f.feed(tracker_pose_frame(served(t, Vector3d(noise + 0.3 * i * 0.0025, 0, 1))), t))
      got.push_back(x);
  }
  ASSERT_EQ(got.size(), 39u);
  for (size_t k = 4; k < got.size(); ++k) EXPECT_NEAR(got[k].pose.v_W_B.x(), 0.3, 0.021) << k;
}

TEST(TrackerClientTest, OnlyTheConfiguredObjectAndSensorAndOthersAreListed) {
  Feeder f(params());
  std::vector<uint8_t> s;
  append_bytes(s,
               tracker_pose_frame(served(kT0, Vector3d::Zero(), Quaterniond::Identity(), "Other")));
  append_bytes(
      s, tracker_pose_frame(served(kT0, Vector3d::Zero(), Quaterniond::Identity(), "Pelican", 1)));
  append_bytes(s, tracker_pose_frame(served(kT0, Vector3d::Zero())));
  append_bytes(s, tracker_pose_frame(served(kT0 + 10'000, Vector3d::Zero())));
  const auto got = f.feed(s, kT0 + 20'000);
  ASSERT_EQ(got.size(), 1u);
  const auto st = f.client.stats();
  EXPECT_EQ(st.other_objects, 2u);
  EXPECT_EQ(f.client.trackers_seen(), (std::vector<std::string>{"Other", "Pelican"}));
}

TEST(TrackerClientTest, UnusableValuesAreRefusedAndCounted) {
  Feeder f(params());
  const double nan = std::nan("");
  auto bad = served(kT0, Vector3d(nan, 0, 0));
  EXPECT_TRUE(f.feed(tracker_pose_frame(bad), kT0).empty());
  bad = served(kT0, Vector3d::Zero(), Quaterniond(0, 0, 0, 0));  // a lost object's zeros
  EXPECT_TRUE(f.feed(tracker_pose_frame(bad), kT0).empty());
  bad = served(kT0, Vector3d::Zero(), Quaterniond(1.1, 0, 0, 0));
  EXPECT_TRUE(f.feed(tracker_pose_frame(bad), kT0).empty());
  bad = served(kT0, Vector3d(5e3, 0, 0));  // 5 km
  EXPECT_TRUE(f.feed(tracker_pose_frame(bad), kT0).empty());
  const auto st = f.client.stats();
  EXPECT_EQ(st.rejected_values, 4u);
  EXPECT_EQ(st.held_back + st.poses, 0u);
  EXPECT_FALSE(st.last_refusal.empty());
}

TEST(TrackerClientTest, StampsMustIncreaseAndStayNearOurClockWithServerStamps) {
  Feeder f(params("server"));
  f.feed(tracker_pose_frame(served(kT0, Vector3d::Zero())), kT0);
  EXPECT_EQ(f.feed(tracker_pose_frame(served(kT0 + 10'000, Vector3d::Zero())), kT0 + 10'000).size(),
            1u);
  EXPECT_TRUE(
      f.feed(tracker_pose_frame(served(kT0 + 10'000, Vector3d::Zero())), kT0 + 20'000).empty());
  EXPECT_TRUE(
      f.feed(tracker_pose_frame(served(kT0 + 5'000, Vector3d::Zero())), kT0 + 20'000).empty());
  // A server clock 2 s off is refused (0.5 s allowed), with a hint.
  EXPECT_TRUE(
      f.feed(tracker_pose_frame(served(kT0 + 20'000, Vector3d::Zero())), kT0 + 2'020'000).empty());
  const auto st = f.client.stats();
  EXPECT_EQ(st.rejected_stamps, 3u);
  EXPECT_NE(st.last_refusal.find("stamp.source mapped"), std::string::npos);
}

TEST(TrackerClientTest, MappedStampsTakeTheSmallestDelayAndKeepTheServersSpacing) {
  MocapParams p = params("mapped");
  Feeder f(p);
  const int64_t offset = -5'000'000;  // the server's clock is 5 s ahead of ours
  // Delays 4, 2, 3, 2.5, 1, 6 ms: the mapped stamp is server + offset + the smallest delay so far.
  const int64_t delays[] = {4000, 2000, 3000, 2500, 1000, 6000};
  std::vector<TrackerPose> got;
  for (int i = 0; i < 6; ++i) {
    const int64_t t = kT0 + i * 10'000;
    for (const auto& x :
         f.feed(tracker_pose_frame(served(t, Vector3d::Zero())), t + offset + delays[i]))
      got.push_back(x);
  }
  ASSERT_EQ(got.size(), 5u);
  const int64_t min_so_far[] = {2000, 2000, 2000, 1000, 1000};
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(got[k].pose.utime, kT0 + (k + 1) * 10'000 + offset + min_so_far[k]) << k;
}

TEST(TrackerClientTest, MappedOffsetForgetsDelaysOlderThanItsWindow) {
  MocapParams p = params("mapped");
  p.stamp.offset_window_s = 1.0;
  ClockMap map(p.stamp);
  map.observe(kT0, kT0 + 1000);
  map.observe(kT0 + 500'000, kT0 + 500'000 + 3000);
  EXPECT_EQ(*map.offset_us(), 1000);
  map.observe(kT0 + 1'200'000, kT0 + 1'200'000 + 2000);  // the 1 ms delay is 1.2 s old
  EXPECT_EQ(*map.offset_us(), 2000);
}

TEST(TrackerClientTest, ReceiveStampsABurstWithTheServersSpacingBeforeTheReceipt) {
  MocapParams p = params("receive");
  p.stamp.latency_s = 0.004;
  Feeder f(p);
  std::vector<uint8_t> burst;
  for (int i = 0; i < 4; ++i)
    append_bytes(burst, tracker_pose_frame(served(1 + i * 10'000, Vector3d::Zero())));
  const int64_t recv = kT0 + 123;
  const auto got = f.feed(burst, recv);
  ASSERT_EQ(got.size(), 3u);  // the first is held back
  for (int k = 0; k < 3; ++k) EXPECT_EQ(got[k].pose.utime, recv - (2 - k) * 10'000 - 4000) << k;
}

TEST(TrackerClientTest, AGapLongerThanMaxGapHoldsThePoseAfterItBack) {
  Feeder f(params());
  int published = 0;
  for (int64_t t : {0, 10'000, 20'000, 220'000, 230'000})
    published +=
        f.feed(tracker_pose_frame(served(kT0 + t, Vector3d(t * 1e-6, 0, 0))), kT0 + t).size();
  EXPECT_EQ(published, 3);
  EXPECT_EQ(f.client.stats().held_back, 2u);
}

TEST(TrackerClientTest, ServerVelocityGoesWithItsPoseAndAMissingOneFallsBackToTheDifference) {
  MocapParams p = params();
  p.velocity.source = "server";
  p.room.units = "mm";
  p.body.t_M_B_m = Vector3d(0.1, 0, 0);
  Feeder f(p);
  f.feed(tracker_pose_frame(served(kT0, Vector3d::Zero())), kT0);
  // Pose, then its Velocity (as VRPN servers send them): published on the Velocity.
  EXPECT_TRUE(
      f.feed(tracker_pose_frame(served(kT0 + 10'000, Vector3d(10, 0, 0))), kT0 + 10'000).empty());
  auto got = f.feed(velocity_frame(kT0 + 10'000, Vector3d(2000, 0, 0)), kT0 + 10'000);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(got[0].server_velocity);
  EXPECT_LT((got[0].pose.v_W_B - Vector3d(2, 0, 0)).norm(), 1e-12);  // mm/s -> m/s
  // Velocity first, then its pose: published at once.
  EXPECT_TRUE(f.feed(velocity_frame(kT0 + 20'000, Vector3d(0, 1000, 0)), kT0 + 20'000).empty());
  got = f.feed(tracker_pose_frame(served(kT0 + 20'000, Vector3d(20, 0, 0))), kT0 + 20'000);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_LT((got[0].pose.v_W_B - Vector3d(0, 1, 0)).norm(), 1e-12);
  // A pose whose Velocity never comes goes out with its difference when the next pose arrives.
  EXPECT_TRUE(
      f.feed(tracker_pose_frame(served(kT0 + 30'000, Vector3d(30, 0, 0))), kT0 + 30'000).empty());
  got = f.feed(tracker_pose_frame(served(kT0 + 40'000, Vector3d(40, 0, 0))), kT0 + 40'000);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].pose.utime, kT0 + 30'000);
  EXPECT_FALSE(got[0].server_velocity);
  EXPECT_LT((got[0].pose.v_W_B - Vector3d(1, 0, 0)).norm(), 1e-9);
  EXPECT_EQ(f.client.stats().velocity_missing, 1u);
}

TEST(TrackerClientTest, ServerVelocityAddsTheLeverArmOfTheBodyOffset) {
  MocapParams p = params();
  p.velocity.source = "server";
  p.body.t_M_B_m = Vector3d(0.5, 0, 0);
  Feeder f(p);
  // Spinning at 1 rad/s about z with the object's origin at rest: the body origin, 0.5 m ahead
  // of it, moves sideways at 0.5 m/s.
  for (int i = 0; i < 3; ++i) {
    const int64_t t = kT0 + i * 10'000;
    const Quaterniond q(Eigen::AngleAxisd(i * 0.01, Vector3d::UnitZ()));
    f.feed(tracker_pose_frame(served(t, Vector3d::Zero(), q)), t);
    const auto got = f.feed(velocity_frame(t, Vector3d::Zero()), t);
    if (i == 0) continue;
    ASSERT_EQ(got.size(), 1u);
    const double yaw = i * 0.01;
    EXPECT_LT((got[0].pose.v_W_B - 0.5 * Vector3d(-std::sin(yaw), std::cos(yaw), 0)).norm(), 1e-6);
  }
}

TEST(TrackerClientTest, ConnectionsAreCountedTogetherAndATruncationIsCounted) {
  Feeder f(params());
  f.feed(tracker_pose_frame(served(kT0, Vector3d::Zero())), kT0);
  f.feed(tracker_pose_frame(served(kT0 + 10'000, Vector3d::Zero())), kT0 + 10'000);
  auto cut = tracker_pose_frame(served(kT0 + 20'000, Vector3d::Zero()));
  cut.resize(30);
  f.feed(cut, kT0 + 20'000);
  f.client.end_of_stream();
  f.client.reset();
  // The restarted server numbers its ids afresh; history is gone (first pose held back again).
  const auto o = tracker_opening();
  f.feed(o, kT0 + 500'000);
  f.feed(tracker_pose_frame(served(kT0 + 500'000, Vector3d::Zero())), kT0 + 500'000);
  EXPECT_EQ(
      f.feed(tracker_pose_frame(served(kT0 + 510'000, Vector3d::Zero())), kT0 + 510'000).size(),
      1u);
  const auto st = f.client.stats();
  EXPECT_EQ(st.truncated, 1u);
  EXPECT_EQ(st.poses, 2u);
  EXPECT_EQ(st.held_back, 2u);
  EXPECT_EQ(st.decoder.poses, 4u);
  EXPECT_EQ(st.decoder.sender_descriptions, 4u);
}

TEST(TrackerClientTest, YUpMillimetreRoomEndToEnd) {
  MocapParams p = params();
  p.room.units = "mm";
  p.room.up_axis = "y";
  p.body.rpy_M_B_deg = Vector3d(-90, 0, 0);
  Feeder f(p);
  f.feed(tracker_pose_frame(served(kT0, Vector3d(0, 1000, 0))), kT0);
  // Up 1 m -> 1.01 m in 10 ms along room y: 1 m/s up in world; 0.5 m along room z: world -y.
  const auto got =
      f.feed(tracker_pose_frame(served(kT0 + 10'000, Vector3d(0, 1010, 500))), kT0 + 10'000);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_LT((got[0].pose.p_W_B - Vector3d(0, -0.5, 1.01)).norm(), 1e-12);
  EXPECT_LT((got[0].pose.v_W_B - Vector3d(0, -50, 1)).norm(), 1e-9);
  EXPECT_NEAR(got[0].pose.q_WB.angularDistance(Quaterniond::Identity()), 0, 1e-12);
}

}  // namespace
}  // namespace alight::mocap

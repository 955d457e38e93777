// State aggregation for the page: phases, plot series, channel health, the JSON document.

#include "ground_station/state.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/channels.hpp"
#include "common/image_msg.hpp"
#include "ground_station/frame_store.hpp"
#include "ground_station/json_writer.hpp"

namespace alight::ground_station {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;

autonomy_status_t status(int64_t utime, int8_t phase) {
  autonomy_status_t s{};
  s.utime = utime;
  s.phase = phase;
  s.phase_name = "";
  return s;
}

pose_t pose(int64_t utime, double x, double y, double z) {
  pose_t p{};
  p.utime = utime;
  p.pos[0] = x;
  p.pos[1] = y;
  p.pos[2] = z;
  p.orientation[0] = 1;
  return p;
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(PhaseNameTest, NamesEveryPhase) {
  EXPECT_STREQ(phase_name(autonomy_status_t::PHASE_REFINEMENT), "REFINEMENT");
  EXPECT_STREQ(phase_name(autonomy_status_t::PHASE_KILLED), "KILLED");
  EXPECT_STREQ(phase_name(99), "UNKNOWN");
}

TEST(StationStateTest, ShowsThePhaseOfTheNewestStatus) {
  StationState state{GroundStationParams{}};
  EXPECT_TRUE(contains(state.to_json(kT0), "\"status\":\"none\""));
  state.on_status(status(kT0, autonomy_status_t::PHASE_DETECTION), kT0);
  EXPECT_TRUE(contains(state.to_json(kT0), "\"phase_name\":\"DETECTION\""));
  auto s = status(kT0 + 100'000, autonomy_status_t::PHASE_REFINEMENT);
  s.phase_name = "REFINEMENT (n=3)";
  s.n_measurements = 3;
  state.on_status(s, kT0 + 100'000);
  const std::string json = state.to_json(kT0 + 100'000);
  EXPECT_TRUE(contains(json, "\"phase_name\":\"REFINEMENT (n=3)\"")) << json;
  EXPECT_TRUE(contains(json, "\"n_measurements\":3"));
}

TEST(StationStateTest, TrackIsSampledAtTheTrackPeriodAndBounded) {
  GroundStationParams p;
  p.track_period_s = 0.1;
  p.track_max_points = 50;
  StationState state{p};
  // 100 Hz poses for 10 s: one point per 0.1 s, the newest 50 kept.
  for (int i = 0; i < 1000; ++i) {
    const int64_t t = kT0 + i * 10'000;
    state.on_pose(pose(t, 0.01 * i, 0, 1), t);
  }
  ASSERT_EQ(state.track().size(), 50u);
  EXPECT_NEAR(state.track().back().p_W[0], 9.9, 1e-9);
  EXPECT_NEAR(state.track()[1].t_s - state.track()[0].t_s, 0.1, 1e-9);
}

TEST(StationStateTest, HeightHistoryCarriesTheEstimateAndItsSpread) {
  StationState state{GroundStationParams{}};
  state.on_pose(pose(kT0, 0, 0, 2.0), kT0);
  auto s = status(kT0 + 200'000, autonomy_status_t::PHASE_REFINEMENT);
  s.has_estimate = true;
  s.estimate_W[2] = 0.6;
  s.covariance[8] = 0.0004;  // sigma_z = 2 cm
  state.on_status(s, kT0 + 200'000);
  ASSERT_EQ(state.heights().size(), 2u);
  EXPECT_TRUE(std::isnan(state.heights()[0].estimate_z_m));
  EXPECT_DOUBLE_EQ(state.heights()[1].vehicle_z_m, 2.0);
  EXPECT_DOUBLE_EQ(state.heights()[1].estimate_z_m, 0.6);
  EXPECT_NEAR(state.heights()[1].sigma_z_m, 0.02, 1e-12);
  // NaN never reaches the JSON document (it is not JSON).
  EXPECT_FALSE(contains(state.to_json(kT0), "nan"));
}

TEST(StationStateTest, KeepsOnlyFoundWaypoints) {
  StationState state{GroundStationParams{}};
  target_t t{};
  t.utime = kT0;
  t.found = false;
  t.reason = target_t::REASON_SMALL_BASELINE;
  state.on_target(t, kT0);
  EXPECT_TRUE(state.measurements().empty());
  EXPECT_TRUE(contains(state.to_json(kT0), "\"reason\":\"small baseline\""));
  t.found = true;
  t.p_W_target[0] = 3;
  state.on_target(t, kT0);
  ASSERT_EQ(state.measurements().size(), 1u);
  EXPECT_EQ(state.measurements()[0].p_W[0], 3);
}

TEST(StationStateTest, CountsTargetsByReasonWithEachGatesName) {
  StationState state{GroundStationParams{}};
  target_t t{};
  t.utime = kT0;
  for (const int8_t r : {target_t::REASON_TOP_TILTED, target_t::REASON_TOP_TILTED,
                         target_t::REASON_NO_FLOOR_AROUND_TOP, target_t::REASON_OK}) {
    t.reason = r;
    t.found = r == target_t::REASON_OK;
    state.on_target(t, kT0);
  }
  EXPECT_EQ(state.target_reasons().at(target_t::REASON_TOP_TILTED), 2u);
  EXPECT_EQ(state.target_reasons().at(target_t::REASON_NO_FLOOR_AROUND_TOP), 1u);
  const std::string json = state.to_json(kT0);
  EXPECT_TRUE(contains(json, "\"target_reasons\":{\"ok\":1,"));
  EXPECT_TRUE(contains(json, "\"top tilted\":2"));
  EXPECT_TRUE(contains(json, "\"no floor around the top\":1"));
  // Every reason the vision sends has a name.
  for (int r = target_t::REASON_OK; r <= target_t::REASON_TOP_POINTS_FEW; ++r)
    EXPECT_STRNE(target_reason_name(static_cast<int8_t>(r)), "unknown") << r;
}

TEST(StationStateTest, ChannelHealthShowsRateAgeAndStaleness) {
  StationState state{GroundStationParams{}};
  for (int i = 0; i <= 30; ++i)
    state.on_frame(channels::kCamera, kT0 + i * 33'333, kT0 + i * 33'333);
  const int64_t t_last = kT0 + 30 * 33'333;
  EXPECT_NEAR(state.channel_rate_hz(channels::kCamera, t_last), 30.0, 0.5);
  EXPECT_NEAR(*state.channel_age_s(channels::kCamera, t_last + 500'000), 0.5, 1e-9);
  EXPECT_FALSE(state.channel_age_s(channels::kVisionDiag, t_last));
  // A channel that stopped: its rate decays and it is marked stale.
  EXPECT_LT(state.channel_rate_hz(channels::kCamera, t_last + 1'500'000), 10.0);
  EXPECT_EQ(state.channel_rate_hz(channels::kCamera, t_last + 3'000'000), 0.0);
  EXPECT_TRUE(contains(state.to_json(t_last + 3'000'000), "\"stale\":true"));
  EXPECT_TRUE(contains(state.to_json(t_last + 10'000), "\"stale\":false"));
}

TEST(StationStateTest, TimeGoingBackwardsStartsANewTrack) {
  StationState state{GroundStationParams{}};
  for (int i = 0; i < 20; ++i) state.on_pose(pose(kT0 + i * 100'000, i, 0, 1), kT0);
  ASSERT_EQ(state.track().size(), 20u);
  state.on_pose(pose(kT0, 0, 0, 1), kT0);  // log replayed from the start
  EXPECT_EQ(state.track().size(), 1u);
}

TEST(StationStateTest, ProcessTableIsInTheDocument) {
  StationState state{GroundStationParams{}};
  process_status_t ps{};
  ps.utime = kT0;
  ps.launch_name = "flight";
  ps.n = 1;
  process_info_t p{};
  p.name = "vision";
  p.state = process_info_t::STATE_BACKOFF;
  p.restarts = 2;
  ps.processes.push_back(p);
  state.on_process_status(ps, kT0);
  const std::string json = state.to_json(kT0);
  EXPECT_TRUE(contains(json, "\"name\":\"vision\",\"pid\":0,\"state\":\"backoff\"")) << json;
  EXPECT_TRUE(contains(json, "\"restarts\":2"));
}

// A second publisher or a forged message refused anywhere on the bus is an alarm on the page,
// naming the node and the channel; a node that does not sign is shown as such.
TEST(StationStateTest, RefusalsForAMessagesOriginAreAnAlarm) {
  StationState state{GroundStationParams{}};
  node_status_t quiet{};
  quiet.utime = kT0;
  quiet.node = "alight-vision";
  quiet.signed_bus = true;
  channel_stats_t c{};
  c.channel = "CAMERA";
  c.received = 100;
  quiet.channels.push_back(c);
  quiet.n = 1;
  state.on_node_status(quiet, kT0);
  std::string doc = state.to_json(kT0);
  EXPECT_TRUE(contains(doc, "\"alarm\":false")) << doc;
  EXPECT_TRUE(contains(doc, "\"node\":\"alight-vision\",\"signed\":true"));
  node_status_t attacked = quiet;
  attacked.node = "alight-outer-loop";
  attacked.signed_bus = false;
  attacked.channels[0].channel = "POSITION_SETPOINT";
  attacked.channels[0].second_publisher = 3;
  state.on_node_status(attacked, kT0 + 1000);
  doc = state.to_json(kT0 + 2000);
  EXPECT_TRUE(contains(doc, "\"alarm\":true")) << doc;
  EXPECT_TRUE(contains(doc, "\"channel\":\"POSITION_SETPOINT\"")) << doc;
  EXPECT_TRUE(contains(doc, "\"second_publisher\":3")) << doc;
  // Names invented by a flood do not grow the document without bound.
  for (int i = 0; i < 1000; ++i) {
    attacked.node = "n" + std::to_string(i);
    state.on_node_status(attacked, kT0 + 3000);
  }
  EXPECT_LT(state.to_json(kT0 + 4000).size(), 64u * 400u);
}

TEST(StationStateTest, ShowsTheAutopilotsModeArmingAndAnAgeingLink) {
  StationState state{GroundStationParams{}};
  EXPECT_TRUE(contains(state.to_json(kT0), "\"autopilot\":\"none\""));
  autopilot_status_t a{};
  a.utime = kT0;
  a.link_up = true;
  a.heartbeat_age_s = 0.2;
  a.mode = "OFFBOARD";
  a.armed = true;
  a.offboard = true;
  a.engage = "FLYING";
  a.last_command = "arm";
  state.on_autopilot_status(a, kT0);
  std::string doc = state.to_json(kT0);
  EXPECT_TRUE(contains(doc, "\"autopilot\":\"PX4\",\"link_up\":true")) << doc;
  EXPECT_TRUE(contains(doc, "\"mode\":\"OFFBOARD\",\"armed\":true")) << doc;
  EXPECT_TRUE(contains(doc, "\"engage\":\"FLYING\""));
  // alight-mavlink went silent: two seconds later the link shows down and the heartbeat older.
  doc = state.to_json(kT0 + 2'000'000);
  EXPECT_TRUE(contains(doc, "\"link_up\":false,\"heartbeat_age_s\":2.2")) << doc;
}

TEST(StationStateTest, ShowsTheClockOffsetAndTheVehiclesSession) {
  GroundStationParams p;
  p.vehicle_id = "uav-1";
  StationState state(p);
  EXPECT_FALSE(state.clock_offset_s());
  EXPECT_EQ(state.vehicle_session(), 0);
  autonomy_status_t st = status(kT0, autonomy_status_t::PHASE_HOVER);
  st.vehicle_id = "uav-1";
  st.cmd_session = 99;
  st.wall_utime = kT0 - 250'000;  // the vehicle's clock is 0.25 s behind the station's
  state.on_status(st, 5'000'000, kT0);
  ASSERT_TRUE(state.clock_offset_s());
  EXPECT_NEAR(*state.clock_offset_s(), 0.25, 1e-9);
  EXPECT_EQ(state.vehicle_session(), 99);
  const std::string doc = state.to_json(5'000'000);
  EXPECT_TRUE(contains(doc, "\"clock_offset_s\":0.25")) << doc;
  EXPECT_TRUE(contains(doc, "\"clock_offset_warn\":false"));
  EXPECT_TRUE(contains(doc, "\"session_known\":true"));
  EXPECT_TRUE(contains(doc, "\"cmds_rejected_by_reason\":{}"));
  st.cmds_rejected_by_reason[autonomy_status_t::REJECT_WRONG_SESSION] = 2;
  state.on_status(st, 5'000'000, kT0);
  EXPECT_TRUE(contains(state.to_json(5'000'000), "\"wrong session (autonomy restarted?)\":2"));

  // Another vehicle's status: its session is not ours to sign for.
  st.vehicle_id = "uav-2";
  state.on_status(st, 5'100'000, kT0 + 100'000);
  EXPECT_EQ(state.vehicle_session(), 0);
  EXPECT_TRUE(contains(state.to_json(5'100'000), "\"other_vehicle_id\":\"uav-2\""));

  // Beyond clock_offset_warn_s the page warns.
  st.vehicle_id = "uav-1";
  st.wall_utime = kT0;
  state.on_status(st, 5'200'000, kT0 + 3'000'000);
  EXPECT_TRUE(contains(state.to_json(5'200'000), "\"clock_offset_warn\":true"));
}

// Regression (issue 14): the station timed everything on the system clock, so a step of it
// (NTP, an operator setting the time) froze its timers or faked ages. StationState now takes
// the steady clock as `now` and the wall clock only where a vehicle stamp is compared with it:
// a 60 s step back of the wall clock neither shows a dead link as fresh nor delays the alarm.
TEST(StationStateRegression, WallClockStepNeitherHidesADeadLinkNorDelaysTheAlarm) {
  GroundStationParams p;
  StationState state(p);
  const int64_t steady0 = 1'000'000'000;
  autonomy_status_t st = status(kT0, autonomy_status_t::PHASE_HOVER);
  st.vehicle_id = p.vehicle_id;
  st.cmd_session = 7;
  st.wall_utime = kT0;
  state.on_status(st, steady0, kT0);
  state.on_command_sent("kill", 123, 7, steady0 + 100'000);
  // 2 s later on the steady clock; the wall clock was stepped back by 60 s meanwhile.
  const int64_t steady_now = steady0 + 2'000'000;
  const auto age = state.channel_age_s(p.status_channel, steady_now);
  ASSERT_TRUE(age);
  EXPECT_NEAR(*age, 2.0, 1e-9);
  const std::string doc = state.to_json(steady_now);
  EXPECT_TRUE(contains(doc, "\"stale\":true")) << doc;
  EXPECT_TRUE(contains(doc, "\"state\":\"not_acknowledged\"")) << doc;
  EXPECT_TRUE(contains(doc, "\"alarm\":{\"name\":\"kill\""));
}

TEST(StationStateTest, CommandsShowTheirAcknowledgement) {
  GroundStationParams p;
  StationState state(p);
  autonomy_status_t st = status(kT0, autonomy_status_t::PHASE_HOVER);
  st.vehicle_id = p.vehicle_id;
  st.cmd_session = 7;
  st.last_cmd_seq = -1;
  st.last_rejected_seq = -1;
  state.on_status(st, 0);
  state.on_command_sent("go", 500, 7, 1'000);
  EXPECT_TRUE(contains(state.to_json(2'000), "\"state\":\"sent\""));
  st.last_cmd_seq = 500;
  state.on_status(st, 81'000);
  const std::string doc = state.to_json(90'000);
  EXPECT_TRUE(contains(doc, "\"state\":\"acknowledged\",\"answer_s\":0.08")) << doc;
  EXPECT_TRUE(contains(doc, "\"alarm\":\"none\""));
}

TEST(JsonWriterTest, EscapesAndNests) {
  JsonWriter w;
  w.begin_object().field("a", std::string("q\"\\\n\x01")).key("b").begin_array();
  w.value(1).value(2.5).value(std::nan("")).begin_object().end_object().end_array();
  w.field("c", true).end_object();
  EXPECT_EQ(w.str(), "{\"a\":\"q\\\"\\\\\\n\\u0001\",\"b\":[1,2.5,null,{}],\"c\":true}");
}

TEST(FrameStoreTest, EncodesRawFramesOncePerFrameAndPassesJpegThrough) {
  FrameStore store;
  std::string error;
  EXPECT_FALSE(store.jpeg_after(0, 0.0, &error));
  EXPECT_EQ(error, "no frame yet");
  cv::Mat img(48, 64, CV_8UC1, cv::Scalar(100));
  store.put(std::make_shared<const image_t>(image_to_msg(img, kT0, 1)));
  const auto a = store.jpeg_after(0, 0.0, &error);
  ASSERT_TRUE(a) << error;
  EXPECT_EQ(a->seq, 1u);
  EXPECT_EQ(a->utime, kT0);
  EXPECT_EQ(static_cast<uint8_t>((*a->bytes)[0]), 0xFF);
  EXPECT_EQ(static_cast<uint8_t>((*a->bytes)[1]), 0xD8);
  const auto again = store.jpeg_after(0, 0.0);
  EXPECT_EQ(again->bytes.get(), a->bytes.get());  // cached, not re-encoded
  // Waiting for a newer frame times out with the same frame.
  const auto same = store.jpeg_after(1, 0.01);
  EXPECT_EQ(same->seq, 1u);
  const image_t jpeg = jpeg_image_to_msg(img, kT0 + 1);
  store.put(std::make_shared<const image_t>(jpeg));
  const auto b = store.jpeg_after(1, 1.0);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->seq, 2u);
  EXPECT_EQ(*b->bytes, std::string(jpeg.data.begin(), jpeg.data.end()));
}

TEST(FrameStoreTest, BadFramesAreReportedNotServed) {
  FrameStore store;
  image_t bad{};
  bad.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  bad.size = 3;
  bad.data = {1, 2, 3};
  store.put(std::make_shared<const image_t>(bad));
  std::string error;
  EXPECT_FALSE(store.jpeg_after(0, 0.0, &error));
  EXPECT_NE(error.find("JPEG"), std::string::npos);
}

}  // namespace
}  // namespace alight::ground_station

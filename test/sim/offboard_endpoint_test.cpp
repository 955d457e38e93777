// The simulated autopilot's MAVLink side (sim/offboard_endpoint.hpp), first alone against a
// scripted companion, then closed-loop: alight-mavlink's Bridge and the endpoint exchanging bytes
// in one process, the simulator flying what crosses the link.

#include "sim/offboard_endpoint.hpp"

#include <gtest/gtest.h>

#include "mavlink/autopilot_firmware.hpp"
#include "mavlink/bridge.hpp"
#include "mavlink/ned_frd.hpp"
#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

namespace mav = alight::mavlink;
constexpr int64_t kEndpointT0 = 1'700'000'000'000'000;

/// The companion's side, scripted.
struct Companion {
  mav::Sender tx{1, 191};
  mav::Parser rx;
  std::vector<uint8_t> pending;
  std::vector<mav::Frame> heard;
  template <class M>
  void say(const M& m) {
    const auto f = tx.pack(m, 0);
    pending.insert(pending.end(), f.bytes().begin(), f.bytes().end());
  }
  void command(uint16_t id, float p1, float p2 = 0, float p3 = 0) {
    mav::CommandLong c;
    c.target_system = 1;
    c.target_component = 1;
    c.command = id;
    c.param1 = p1, c.param2 = p2, c.param3 = p3;
    say(c);
  }
  void hover_setpoint() {
    mav::SetAttitudeTarget s;
    s.target_system = 1;
    s.thrust = 0.5f;
    say(s);
  }
  std::vector<mav::CommandAck> acks() {
    std::vector<mav::CommandAck> out;
    for (const auto& f : heard)
      if (auto a = mav::decode<mav::CommandAck>(f)) out.push_back(*a);
    return out;
  }
};

struct EndpointHarness {
  OffboardEndpoint ep{OffboardEndpointParams{}, 10.0, kEndpointT0};
  Companion c;
  int64_t now = kEndpointT0;
  VehicleState state;
  bool on_ground = true;
  EndpointOutput step() {
    EndpointInput in;
    std::vector<uint8_t> bytes;
    bytes.swap(c.pending);
    in.bytes = bytes;
    in.now_utime = now;
    in.state = state;
    in.on_ground = on_ground;
    EndpointOutput out = ep.update(in);
    c.rx.push(out.bytes);
    mav::Frame f;
    while (c.rx.next(f)) c.heard.push_back(f);
    now += 10'000;
    return out;
  }
};

const uint8_t kOffboard = mav::px4_mode::kOffboard;

TEST(OffboardEndpointTest, RefusesOffboardWithoutASetpointStreamAndAcceptsItWithOne) {
  EndpointHarness h;
  h.c.command(mav::mav_cmd::kDoSetMode, 1, kOffboard);
  h.step();
  ASSERT_EQ(h.c.acks().size(), 1u);
  EXPECT_EQ(h.c.acks()[0].result, mav::mav_result::kTemporarilyRejected);
  EXPECT_FALSE(h.ep.offboard());
  for (int i = 0; i < 20; ++i) {  // 10 Hz for 0.2 s... 2 setpoints in the last second: enough
    if (i % 10 == 0) h.c.hover_setpoint();
    h.step();
  }
  h.c.heard.clear();
  h.c.command(mav::mav_cmd::kDoSetMode, 1, kOffboard);
  h.step();
  ASSERT_EQ(h.c.acks().size(), 1u);
  EXPECT_EQ(h.c.acks()[0].result, mav::mav_result::kAccepted);
  EXPECT_TRUE(h.ep.offboard());
}

TEST(OffboardEndpointTest, CommandsTheDynamicsOnlyArmedInOffboardWithThrustScaledByTheHover) {
  EndpointHarness h;
  for (int i = 0; i < 10; ++i) {
    h.c.hover_setpoint();
    EXPECT_FALSE(h.step().command);  // not offboard, not armed
  }
  h.c.command(mav::mav_cmd::kDoSetMode, 1, kOffboard);
  h.c.command(mav::mav_cmd::kComponentArmDisarm, 1);
  h.step();
  EXPECT_TRUE(h.ep.armed());
  h.c.hover_setpoint();
  const auto out = h.step();
  ASSERT_TRUE(out.command);
  EXPECT_TRUE(out.command->armed);
  EXPECT_NEAR(out.command->thrust_N, 10.0, 1e-6);  // 0.5 of 0.5 hover thrust: the weight
  EXPECT_NEAR(out.command->roll_rad, 0, 1e-6);
}

TEST(OffboardEndpointTest, DisarmIsDeniedInTheAirUnlessForced) {
  EndpointHarness h;
  h.state.armed = true;  // the dynamics' motors follow the arming
  h.c.command(mav::mav_cmd::kComponentArmDisarm, 1);
  h.step();
  h.on_ground = false;
  h.c.command(mav::mav_cmd::kComponentArmDisarm, 0);
  EXPECT_FALSE(h.step().disarm);
  EXPECT_TRUE(h.ep.armed());
  EXPECT_EQ(h.c.acks().back().result, mav::mav_result::kDenied);
  h.c.command(mav::mav_cmd::kComponentArmDisarm, 0, mav::kForceDisarmMagic);
  EXPECT_TRUE(h.step().disarm);
  EXPECT_FALSE(h.ep.armed());
}

TEST(OffboardEndpointTest, AnswersTheVersionRequestAndFliesTheTargetsAcceleration) {
  EndpointHarness h;
  h.c.command(mav::mav_cmd::kRequestMessage, mav::AutopilotVersion::kId);
  h.step();
  ASSERT_EQ(h.c.acks().size(), 1u);
  EXPECT_EQ(h.c.acks()[0].result, mav::mav_result::kAccepted);
  std::optional<mav::AutopilotVersion> v;
  for (const auto& f : h.c.heard)
    if (auto m = mav::decode<mav::AutopilotVersion>(f)) v = m;
  ASSERT_TRUE(v);
  EXPECT_TRUE(mav::takes_position_target_accel(
      mav::Flavour::kPx4, mav::FirmwareVersion::from_flight_sw_version(v->flight_sw_version)));
  h.c.command(mav::mav_cmd::kRequestMessage, 999);  // a message it does not send
  h.step();
  EXPECT_EQ(h.c.acks().back().result, mav::mav_result::kUnsupported);

  mav::SetPositionTargetLocalNed t;
  t.target_system = 1;
  t.coordinate_frame = mav::mav_frame::kLocalNed;
  t.z = -1.0f;
  t.afx = 0.4f;  // north
  t.type_mask = mav::position_target_typemask::kYawRateIgnore;
  for (int i = 0; i < 5; ++i) {
    h.c.say(t);
    h.step();
  }
  h.c.command(mav::mav_cmd::kDoSetMode, 1, kOffboard);
  h.c.command(mav::mav_cmd::kComponentArmDisarm, 1);
  h.step();
  h.c.say(t);
  auto out = h.step();
  ASSERT_TRUE(out.position);
  EXPECT_NEAR(out.position->a_W.y(), 0.4, 1e-6);  // ENU: north is y
  EXPECT_NEAR(out.position->a_W.x(), 0.0, 1e-6);
  t.type_mask |= mav::position_target_typemask::kAccelIgnore;
  h.c.say(t);
  out = h.step();
  ASSERT_TRUE(out.position);
  EXPECT_EQ(out.position->a_W, Vector3d::Zero());
}

TEST(OffboardEndpointTest, LandsWhenTheOffboardSignalIsLost) {
  EndpointHarness h;
  for (int i = 0; i < 5; ++i) {
    h.c.hover_setpoint();
    h.step();
  }
  h.c.command(mav::mav_cmd::kDoSetMode, 1, kOffboard);
  h.c.command(mav::mav_cmd::kComponentArmDisarm, 1);
  h.step();
  ASSERT_TRUE(h.ep.offboard());
  // Silence for less than COM_OF_LOSS_T: still offboard; then AUTO.LAND.
  for (int i = 0; i < 90; ++i) h.step();
  EXPECT_TRUE(h.ep.offboard());
  for (int i = 0; i < 20; ++i) h.step();
  EXPECT_FALSE(h.ep.offboard());
  EXPECT_EQ(mav::mode_name(mav::Flavour::kPx4, h.ep.custom_mode()), "AUTO.LAND");
  EXPECT_EQ(h.ep.stats().failsafes, 1u);
}

TEST(OffboardEndpointTest, SendsTelemetryInNedFrdAndAnswersMessageIntervals) {
  EndpointHarness h;
  h.state.p_W_B = Vector3d(1, 2, 3);
  h.c.command(mav::mav_cmd::kSetMessageInterval, mav::LocalPositionNed::kId, 100'000);
  h.c.command(mav::mav_cmd::kSetMessageInterval, 9999, 100'000);
  for (int i = 0; i < 100; ++i) h.step();  // 1 s
  int positions = 0;
  for (const auto& f : h.c.heard)
    if (auto l = mav::decode<mav::LocalPositionNed>(f)) {
      ++positions;
      EXPECT_FLOAT_EQ(l->x, 2);
      EXPECT_FLOAT_EQ(l->z, -3);
    }
  EXPECT_EQ(positions, 10);  // 10 Hz as asked (30 by default)
  const auto acks = h.c.acks();
  ASSERT_EQ(acks.size(), 2u);
  EXPECT_EQ(acks[0].result, mav::mav_result::kAccepted);
  EXPECT_EQ(acks[1].result, mav::mav_result::kUnsupported);
}

// Closed loop: the bridge takes a hover command from "the outer loop", engages OFFBOARD and arms
// over the link, and the simulated vehicle leaves the ground; then alight goes silent and the
// autopilot's own failsafe lands and disarms it.
TEST(OffboardEndpointTest, BridgeAndEndpointFlyTheSimulatorThroughMavlinkBytes) {
  const Scenario scenario = test::quiet(test::scenario("landing_none"));
  const VehicleParams vehicle = test::starmac();
  Simulator sim(scenario, vehicle, 1);
  OffboardEndpoint ep(OffboardEndpointParams{}, vehicle.hover_thrust_N(), sim.now_utime());
  mav::BridgeParams bp;
  bp.link = "udp-listen:127.0.0.1:14540";
  mav::Bridge bridge(bp, vehicle.hover_thrust_N());

  std::vector<uint8_t> to_bridge, to_autopilot;
  const int64_t start = sim.now_utime();
  bool was_airborne = false;
  const auto run = [&](double seconds, bool stack_alive, double climb) {
    const int64_t end = sim.now_utime() + static_cast<int64_t>(seconds * 1e6);
    while (sim.now_utime() < end) {
      sim.advance_to(sim.now_utime() + 1000);
      mav::BridgeInput bin;
      bin.link_bytes = to_bridge;
      if (stack_alive) {
        mav::AttitudeTarget t;
        t.utime = sim.now_utime();
        t.thrust_N = climb * vehicle.hover_thrust_N();
        t.armed = true;
        bin.attitude = t;
      }
      // The bridge's clocks: the sim's time stands in for both.
      const auto bout = bridge.update(bin, {sim.now_utime() - start, sim.now_utime()});
      to_bridge.clear();
      to_autopilot = bout.link_bytes;
      EndpointInput ein;
      ein.bytes = to_autopilot;
      ein.now_utime = sim.now_utime();
      ein.state = sim.state();
      const Truth truth = sim.truth();
      ein.on_ground = truth.contact == Contact::kFloor;
      ein.imu = sim.take_imu();
      const auto eout = ep.update(ein);
      if (eout.command) sim.command(*eout.command);
      to_bridge = eout.bytes;
      was_airborne = was_airborne || sim.state().p_W_B.z() > 0.5;
    }
  };
  run(5.0, true, 1.05);
  EXPECT_TRUE(ep.offboard());
  EXPECT_TRUE(ep.armed());
  EXPECT_EQ(bridge.engage_state(), mav::EngageState::kFlying);
  EXPECT_TRUE(was_airborne);
  EXPECT_GT(bridge.stats().imu_out, 500u);  // HIGHRES_IMU at 200 Hz as the bridge asked
  // alight goes silent: the bridge stops streaming, PX4's failsafe lands and disarms.
  run(25.0, false, 0);
  EXPECT_EQ(mav::mode_name(mav::Flavour::kPx4, ep.custom_mode()), "AUTO.LAND");
  EXPECT_FALSE(ep.armed());
  EXPECT_FALSE(sim.state().armed);
  EXPECT_LT(sim.state().p_W_B.z(), 0.3);  // resting on its gear
  EXPECT_NEAR(sim.state().v_W_B.z(), 0, 0.01);
  EXPECT_FALSE(sim.truth().tipped);
}

}  // namespace
}  // namespace alight::sim

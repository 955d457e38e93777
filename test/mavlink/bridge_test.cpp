// The autopilot bridge's logic (mavlink/bridge.hpp) against a scripted autopilot made of the
// MAVLink library's Sender and Parser: link state, setpoint streaming and its stop, the mode and
// arming state machine with acknowledgements, retries and the pilot's override, the conversions
// both ways, and bad input.
#include "mavlink/bridge.hpp"

#include <gtest/gtest.h>

#include <random>

#include "mavlink/ned_frd.hpp"

namespace alight::mavlink {
namespace {

constexpr double kWeightN = 1.5 * 9.81;

/// The autopilot's side of the link, scripted by the test.
struct FakeAutopilot {
  Sender tx{1, 1};
  Parser rx;
  std::vector<uint8_t> pending;  // bytes to hand to the bridge at the next step
  std::vector<Frame> heard;      // frames the bridge sent

  template <class M>
  void say(const M& m) {
    const FrameBytes f = tx.pack(m, 0);
    pending.insert(pending.end(), f.bytes().begin(), f.bytes().end());
  }
  void heartbeat(uint32_t custom_mode, bool armed, uint8_t autopilot = mav_autopilot::kPx4) {
    Heartbeat hb;
    hb.type = mav_type::kQuadrotor;
    hb.autopilot = autopilot;
    hb.base_mode = mav_mode_flag::kCustomModeEnabled | (armed ? mav_mode_flag::kSafetyArmed : 0);
    hb.custom_mode = custom_mode;
    hb.system_status = armed ? mav_state::kActive : mav_state::kStandby;
    say(hb);
  }
  void ack(uint16_t command, uint8_t result) {
    CommandAck a;
    a.command = command;
    a.result = result;
    say(a);
  }
  template <class M>
  std::vector<M> take() {
    std::vector<M> out;
    std::vector<Frame> rest;
    for (const Frame& f : heard) {
      if (auto m = decode<M>(f))
        out.push_back(*m);
      else
        rest.push_back(f);
    }
    heard = rest;
    return out;
  }
  std::vector<CommandLong> commands(uint16_t id) {
    std::vector<CommandLong> out;
    for (const auto& c : take<CommandLong>())
      if (c.command == id) out.push_back(c);
    return out;
  }
};

BridgeParams px4_params() {
  BridgeParams p;
  p.autopilot = "px4";
  p.link = "udp-listen:127.0.0.1:14540";
  p.imu_rate_hz = 0;  // no SET_MESSAGE_INTERVAL in the way, unless a test wants them
  p.attitude_rate_hz = 0;
  p.position_rate_hz = 0;
  p.landed_state_rate_hz = 0;
  p.sys_status_rate_hz = 0;
  p.check_params = false;
  return p;
}

/// Steps the bridge in 1 ms steps; the autopilot's pending bytes go in at the first.
struct Harness {
  explicit Harness(BridgeParams p = px4_params()) : params(p), bridge(p, kWeightN) {}
  BridgeOutput step(const BridgeInput& extra = {}) {
    BridgeInput in = extra;
    std::vector<uint8_t> bytes;
    bytes.swap(ap.pending);
    in.link_bytes = bytes;
    BridgeOutput out = bridge.update(in, clock());
    ap.rx.push(out.link_bytes);
    Frame f;
    while (ap.rx.next(f)) {
      // Every autopilot here answers the version request at once (a PX4 1.15), out of the
      // tests' way; BridgeAutopilotTest covers the request itself.
      const auto c = decode<CommandLong>(f);
      if (answer_version && c && c->command == mav_cmd::kRequestMessage &&
          static_cast<uint32_t>(c->param1) == AutopilotVersion::kId) {
        ap.ack(c->command, mav_result::kAccepted);
        AutopilotVersion v;
        v.flight_sw_version = 0x010F00FFu;
        ap.say(v);
        continue;
      }
      ap.heard.push_back(f);
    }
    for (auto& s : out.imu) imu.push_back(s);
    for (auto& e : out.events) events.push_back(e.text);
    t_us += 1000;
    return out;
  }
  void run_for(double s, const std::optional<AttitudeTarget>& keep = std::nullopt,
               double setpoint_period_s = 0.01) {
    const int64_t end = t_us + static_cast<int64_t>(s * 1e6);
    int64_t next_sp = t_us;
    while (t_us < end) {
      BridgeInput in;
      if (keep && t_us >= next_sp) {
        in.attitude = keep;
        next_sp += static_cast<int64_t>(setpoint_period_s * 1e6);
      }
      step(in);
    }
  }
  BridgeClock clock() const { return {t_us, 1'700'000'000'000'000 + t_us}; }

  BridgeParams params;
  Bridge bridge;
  FakeAutopilot ap;
  bool answer_version = true;
  int64_t t_us = 1'000'000;
  std::vector<ImuOut> imu;
  std::vector<std::string> events;
};

AttitudeTarget hover(bool armed = true) {
  AttitudeTarget t;
  t.thrust_N = kWeightN;
  t.armed = armed;
  return t;
}

const uint32_t kOffboard = px4_mode::custom_mode(px4_mode::kOffboard);
const uint32_t kPosctl = px4_mode::custom_mode(px4_mode::kPosctl);

void level_attitude(FakeAutopilot& ap, uint32_t boot_ms, double yaw_ned = 0) {
  AttitudeQuaternion a;
  a.time_boot_ms = boot_ms;
  const auto q = wxyz_float(Quaterniond(Eigen::AngleAxisd(yaw_ned, Vector3d::UnitZ())));
  a.q1 = q[0], a.q2 = q[1], a.q3 = q[2], a.q4 = q[3];
  ap.say(a);
}

TEST(BridgeTest, LinkComesUpOnlyOnTheAutopilotsHeartbeatAndGoesDownAfterTheTimeout) {
  Harness h;
  Heartbeat gcs;
  gcs.type = mav_type::kGcs;
  gcs.autopilot = mav_autopilot::kInvalid;
  h.ap.say(gcs);
  h.step();
  EXPECT_FALSE(h.bridge.link_up());
  EXPECT_EQ(h.bridge.stats().foreign_frames, 1u);

  h.ap.heartbeat(kPosctl, false);
  h.step();
  EXPECT_TRUE(h.bridge.link_up());
  EXPECT_EQ(h.bridge.status(h.clock()).mode, "POSCTL");

  h.run_for(h.params.heartbeat_timeout_s - 0.1);
  EXPECT_TRUE(h.bridge.link_up());
  h.run_for(0.2);
  EXPECT_FALSE(h.bridge.link_up());
  EXPECT_EQ(h.bridge.stats().link_losses, 1u);
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kNoLink);
}

TEST(BridgeTest, SendsItsOwnHeartbeatOncePerSecondAsAnOnboardController) {
  Harness h;
  h.run_for(2.5);
  const auto hbs = h.ap.take<Heartbeat>();
  ASSERT_EQ(hbs.size(), 3u);
  EXPECT_EQ(hbs[0].type, mav_type::kOnboardController);
  EXPECT_EQ(hbs[0].autopilot, mav_autopilot::kInvalid);
}

TEST(BridgeTest, StreamsTheLastSetpointAtTheStreamRateAndStopsWhenTheStackGoesSilent) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 1000);
  h.step();
  // One setpoint, then silence: the bridge repeats it at 50 Hz for setpoint_timeout_s (0.5 s),
  // then stops, so that the autopilot's own offboard-loss failsafe takes over.
  BridgeInput in;
  in.attitude = hover(false);
  h.step(in);
  h.run_for(0.4);
  const size_t while_fresh = h.ap.take<SetAttitudeTarget>().size();
  EXPECT_GE(while_fresh, 20u);
  EXPECT_LE(while_fresh, 22u);
  h.run_for(0.2);  // crosses the 0.5 s timeout
  h.ap.take<SetAttitudeTarget>();
  h.run_for(1.0);
  EXPECT_TRUE(h.ap.take<SetAttitudeTarget>().empty());
  EXPECT_FALSE(h.bridge.status(h.clock()).streaming);
}

TEST(BridgeTest, AttitudeSetpointIsTheCommandInNedFrdWithNormalisedThrust) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  const double yaw_ned = 0.3;  // the autopilot's heading: 0.3 rad east of north
  level_attitude(h.ap, 1000, yaw_ned);
  h.step();
  AttitudeTarget t;
  t.roll_rad = 0.1;
  t.pitch_rad = -0.2;
  t.yaw_rate_radps = 0.5;
  t.thrust_N = 1.2 * kWeightN;
  t.armed = true;
  BridgeInput in;
  in.attitude = t;
  h.step(in);
  const auto sps = h.ap.take<SetAttitudeTarget>();
  ASSERT_EQ(sps.size(), 1u);
  const SetAttitudeTarget& m = sps[0];
  EXPECT_NEAR(m.thrust, 1.2 * h.params.hover_thrust, 1e-6);
  EXPECT_NEAR(m.body_yaw_rate, -0.5, 1e-6);  // FLU z up -> FRD z down
  const auto q = quat_from_wxyz_float(m.q);
  ASSERT_TRUE(q);
  const Vector3d rpy = rpy_from_rotation(q_enu_flu_from_ned_frd(*q).toRotationMatrix());
  EXPECT_NEAR(rpy.x(), 0.1, 1e-5);
  EXPECT_NEAR(rpy.y(), -0.2, 1e-5);
  EXPECT_NEAR(rpy.z(), yaw_enu_from_ned(yaw_ned) + 0.5 * h.params.yaw_lead_s, 1e-5);
}

TEST(BridgeTest, ThrustIsZeroWhileTheStackSaysDisarmedAndClampedToOne) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 1000);
  h.step();
  AttitudeTarget t = hover(false);
  BridgeInput in;
  in.attitude = t;
  h.step(in);
  h.run_for(0.05);
  t.armed = true;
  t.thrust_N = 10 * kWeightN;
  in.attitude = t;
  h.step(in);
  h.run_for(0.03);  // the next stream period
  const auto sps = h.ap.take<SetAttitudeTarget>();
  ASSERT_GE(sps.size(), 2u);
  EXPECT_EQ(sps.front().thrust, 0.0f);
  EXPECT_EQ(sps.back().thrust, 1.0f);
}

TEST(BridgeTest, NoAttitudeSetpointBeforeAHeadingIsKnown) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  BridgeInput in;
  in.attitude = hover();
  h.step(in);
  h.run_for(0.1);
  EXPECT_TRUE(h.ap.take<SetAttitudeTarget>().empty());
  EXPECT_GT(h.bridge.stats().setpoints_not_sent, 0u);
  // Motion capture gives a heading as well.
  PoseSample p;
  p.utime = 1;
  in = {};
  in.mocap = p;
  h.step(in);
  h.run_for(0.1, hover());
  EXPECT_FALSE(h.ap.take<SetAttitudeTarget>().empty());
}

/// Streams a hover setpoint to a PX4 that follows the bridge's commands, and returns when the
/// bridge is FLYING (or after `limit_s`).
void engage(Harness& h, double limit_s = 5) {
  uint32_t mode = kPosctl;
  bool armed = false;
  h.ap.heartbeat(mode, armed);
  for (int i = 0; i < limit_s * 100 && h.bridge.engage_state() != EngageState::kFlying; ++i) {
    level_attitude(h.ap, static_cast<uint32_t>(h.t_us / 1000));
    h.run_for(0.01, hover());
    for (const auto& c : h.ap.take<CommandLong>()) {
      if (c.command == mav_cmd::kDoSetMode) {
        mode =
            px4_mode::custom_mode(static_cast<uint8_t>(c.param2), static_cast<uint8_t>(c.param3));
        h.ap.ack(c.command, mav_result::kAccepted);
        h.ap.heartbeat(mode, armed);
      } else if (c.command == mav_cmd::kComponentArmDisarm) {
        armed = c.param1 == 1;
        h.ap.ack(c.command, mav_result::kAccepted);
        h.ap.heartbeat(mode, armed);
      }
    }
  }
}

TEST(BridgeTest, AsksForOffboardAfterTheWarmupThenArms) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 1000);
  h.step();
  // Before the warm-up no command: PX4 refuses OFFBOARD without a setpoint stream.
  h.run_for(h.params.offboard_warmup_s - 0.1, hover());
  EXPECT_TRUE(h.ap.take<CommandLong>().empty());
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kStreaming);
  h.run_for(0.2, hover());
  const auto set_mode = h.ap.commands(mav_cmd::kDoSetMode);
  ASSERT_EQ(set_mode.size(), 1u);
  EXPECT_EQ(set_mode[0].param1, mav_mode_flag::kCustomModeEnabled);
  EXPECT_EQ(set_mode[0].param2, px4_mode::kOffboard);
  EXPECT_EQ(set_mode[0].target_system, 1);
  EXPECT_EQ(set_mode[0].target_component, 1);
  h.ap.ack(mav_cmd::kDoSetMode, mav_result::kAccepted);
  h.run_for(0.1, hover());
  // No arming before the heartbeat shows OFFBOARD.
  EXPECT_TRUE(h.ap.take<CommandLong>().empty());
  h.ap.heartbeat(kOffboard, false);
  h.run_for(0.05, hover());
  const auto arm = h.ap.commands(mav_cmd::kComponentArmDisarm);
  ASSERT_EQ(arm.size(), 1u);
  EXPECT_EQ(arm[0].param1, 1.0f);
  h.ap.ack(mav_cmd::kComponentArmDisarm, mav_result::kAccepted);
  h.ap.heartbeat(kOffboard, true);
  h.run_for(0.05, hover());
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kFlying);
  const auto s = h.bridge.status(h.clock());
  EXPECT_TRUE(s.armed);
  EXPECT_TRUE(s.offboard);
  EXPECT_EQ(s.mode, "OFFBOARD");
}

TEST(BridgeTest, ResendsAnUnansweredCommandWithARisingConfirmationThenBacksOff) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 1000);
  h.step();
  // Keep the link up with heartbeats, never answer the command.
  std::vector<CommandLong> sent;
  for (int i = 0; i < 60; ++i) {
    h.ap.heartbeat(kPosctl, false);
    level_attitude(h.ap, 1000 + i * 100);
    h.run_for(0.1, hover());
    for (const auto& c : h.ap.commands(mav_cmd::kDoSetMode)) sent.push_back(c);
    if (h.bridge.stats().commands_failed > 0) break;
  }
  ASSERT_EQ(sent.size(), static_cast<size_t>(h.params.command_retries + 1));
  for (size_t i = 0; i < sent.size(); ++i) EXPECT_EQ(sent[i].confirmation, i);
  EXPECT_EQ(h.bridge.stats().commands_failed, 1u);
  EXPECT_EQ(h.bridge.status(h.clock()).last_result, -1);
  // Nothing during the back-off.
  h.ap.heartbeat(kPosctl, false);
  h.run_for(h.params.command_backoff_s - 0.1, hover());
  EXPECT_TRUE(h.ap.commands(mav_cmd::kDoSetMode).empty());
}

TEST(BridgeTest, ARefusedModeIsCountedAndAskedAgainOnlyAfterTheBackoff) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 1000);
  h.step();
  h.run_for(h.params.offboard_warmup_s + 0.05, hover());
  ASSERT_EQ(h.ap.commands(mav_cmd::kDoSetMode).size(), 1u);
  h.ap.ack(mav_cmd::kDoSetMode, mav_result::kDenied);
  h.run_for(0.01, hover());
  EXPECT_EQ(h.bridge.stats().commands_failed, 1u);
  EXPECT_EQ(h.bridge.status(h.clock()).last_result, mav_result::kDenied);
  for (int i = 0; i < 9; ++i) {
    h.ap.heartbeat(kPosctl, false);
    level_attitude(h.ap, 2000 + i * 100);
    h.run_for(0.1, hover());
  }
  EXPECT_TRUE(h.ap.commands(mav_cmd::kDoSetMode).empty());
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 3000);
  h.run_for(0.2, hover());
  EXPECT_EQ(h.ap.commands(mav_cmd::kDoSetMode).size(), 1u);
}

TEST(BridgeTest, ThePilotsOverrideWinsUntilTheVehicleIsDisarmed) {
  Harness h;
  engage(h);
  ASSERT_EQ(h.bridge.engage_state(), EngageState::kFlying);
  h.ap.take<CommandLong>();
  // The pilot flips the switch to POSCTL in the air.
  for (int i = 0; i < 30; ++i) {
    h.ap.heartbeat(kPosctl, true);
    level_attitude(h.ap, 10000 + i * 100);
    h.run_for(0.1, hover());
  }
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kOverride);
  EXPECT_TRUE(h.ap.commands(mav_cmd::kDoSetMode).empty());
  // Landed and disarmed by the pilot. The stack still saying motors on is not a new arming: no
  // OFFBOARD, however long it says so.
  for (int i = 0; i < 70; ++i) {
    h.ap.heartbeat(kPosctl, false);
    level_attitude(h.ap, 14000 + i * 100);
    h.run_for(0.1, hover());
  }
  EXPECT_TRUE(h.ap.commands(mav_cmd::kDoSetMode).empty());
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kCooldown);
  // The stack's motors off, then on again after the cool-down: that engages.
  h.run_for(0.1, hover(false));
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 22000);
  h.run_for(1.2, hover());
  EXPECT_FALSE(h.ap.commands(mav_cmd::kDoSetMode).empty());
}

TEST(BridgeTest, AfterALinkLossAnArmedVehicleInTheAutopilotsFailsafeIsLeftAlone) {
  Harness h;
  engage(h);
  ASSERT_EQ(h.bridge.engage_state(), EngageState::kFlying);
  h.ap.take<CommandLong>();
  // The link drops; meanwhile the autopilot's failsafe switched to AUTO.LAND.
  h.run_for(h.params.heartbeat_timeout_s + 0.5, hover());
  ASSERT_FALSE(h.bridge.link_up());
  const uint32_t land = px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kLand);
  for (int i = 0; i < 30; ++i) {
    h.ap.heartbeat(land, true);
    level_attitude(h.ap, 50000 + i * 100);
    h.run_for(0.1, hover());
  }
  EXPECT_TRUE(h.bridge.link_up());
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kOverride);
  EXPECT_TRUE(h.ap.commands(mav_cmd::kDoSetMode).empty());
  EXPECT_TRUE(h.ap.commands(mav_cmd::kComponentArmDisarm).empty());
}

TEST(BridgeTest, KillIsAForcedDisarmAtOnce) {
  Harness h;
  engage(h);
  ASSERT_EQ(h.bridge.engage_state(), EngageState::kFlying);
  h.ap.take<CommandLong>();
  PositionTarget kill;
  kill.motors = Motors::kKill;
  kill.kill_authorised = true;
  BridgeInput in;
  in.position = kill;
  h.step(in);
  const auto c = h.ap.commands(mav_cmd::kComponentArmDisarm);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].param1, 0.0f);
  EXPECT_EQ(c[0].param2, kForceDisarmMagic);
}

TEST(BridgeTest, TheStacksMotorsOffInOffboardIsAPlainDisarm) {
  Harness h;
  engage(h);
  ASSERT_EQ(h.bridge.engage_state(), EngageState::kFlying);
  h.ap.take<CommandLong>();
  h.ap.heartbeat(kOffboard, true);
  level_attitude(h.ap, 20000);
  h.run_for(0.05, hover(false));
  const auto c = h.ap.commands(mav_cmd::kComponentArmDisarm);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].param1, 0.0f);
  EXPECT_EQ(c[0].param2, 0.0f);
}

TEST(BridgeTest, OperatorEngageNeverSwitchesModesOrArms) {
  BridgeParams p = px4_params();
  p.engage = "operator";
  Harness h(p);
  h.ap.heartbeat(kPosctl, false);
  level_attitude(h.ap, 1000);
  h.step();
  h.run_for(3, hover());
  EXPECT_TRUE(h.ap.take<CommandLong>().empty());
  EXPECT_FALSE(h.ap.take<SetAttitudeTarget>().empty());
  EXPECT_EQ(h.bridge.engage_state(), EngageState::kOperator);
}

TEST(BridgeTest, ArduPilotIsAskedForGuidedNoGpsWithItsModeNumber) {
  BridgeParams p = px4_params();
  p.autopilot = "ardupilot";
  Harness h(p);
  h.ap.heartbeat(copter_mode::kStabilize, false, mav_autopilot::kArdupilotmega);
  level_attitude(h.ap, 1000);
  h.step();
  h.run_for(p.offboard_warmup_s + 0.1, hover());
  const auto c = h.ap.commands(mav_cmd::kDoSetMode);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].param2, static_cast<float>(copter_mode::kGuidedNoGps));
  EXPECT_EQ(h.bridge.status(h.clock()).mode, "STABILIZE");
}

TEST(BridgeTest, PositionSetpointGoesOutInNedWithYawFromNorth) {
  BridgeParams p = px4_params();
  p.control = "position";
  Harness h(p);
  h.ap.heartbeat(kPosctl, false);
  h.step();
  PositionTarget t;
  t.p_W = Vector3d(1, 2, 3);  // 1 m east, 2 m north, 3 m up
  t.v_W = Vector3d(0.1, 0, -0.2);
  t.a_W = Vector3d(0.3, -0.4, 0.5);
  t.yaw_rad = 0;           // facing east
  t.yaw_rate_radps = 0.2;  // turning left
  t.motors = Motors::kOn;
  BridgeInput in;
  in.position = t;
  h.step(in);
  const auto m = h.ap.take<SetPositionTargetLocalNed>();
  ASSERT_EQ(m.size(), 1u);
  EXPECT_FLOAT_EQ(m[0].x, 2);
  EXPECT_FLOAT_EQ(m[0].y, 1);
  EXPECT_FLOAT_EQ(m[0].z, -3);
  EXPECT_FLOAT_EQ(m[0].vy, 0.1f);
  EXPECT_FLOAT_EQ(m[0].vz, 0.2f);
  EXPECT_NEAR(m[0].yaw, M_PI / 2, 1e-6);
  EXPECT_EQ(m[0].coordinate_frame, mav_frame::kLocalNed);
  EXPECT_FALSE(m[0].type_mask & position_target_typemask::kXIgnore);
  EXPECT_FALSE(m[0].type_mask & position_target_typemask::kYawRateIgnore);
  EXPECT_FLOAT_EQ(m[0].yaw_rate, -0.2f);  // about z down: a left turn is negative
  // The harness's autopilot said PX4 1.15: the acceleration goes too, in NED.
  EXPECT_FALSE(m[0].type_mask & position_target_typemask::kAccelIgnore);
  EXPECT_FLOAT_EQ(m[0].afx, -0.4f);
  EXPECT_FLOAT_EQ(m[0].afy, 0.3f);
  EXPECT_FLOAT_EQ(m[0].afz, -0.5f);
  EXPECT_EQ(h.bridge.status(h.clock()).firmware, "1.15.0");
  EXPECT_TRUE(h.bridge.status(h.clock()).accel_feedforward);
}

// After the stack's motors-off, while the autopilot is still armed: sideways the stack's target
// (where the vehicle rests, on a moving deck too), no higher than the last MOTORS_ON target, and
// a descent commanded (PX4's land detector needs one); disarmed, the stack's target unchanged.
TEST(BridgeTest, AfterMotorsOffTheTargetPressesTheArmedVehicleDown) {
  BridgeParams p = px4_params();
  p.control = "position";
  Harness h(p);
  h.ap.heartbeat(kOffboard, false);  // armed after the bridge came up: its own flight
  h.step();
  const auto send = [&](const Vector3d& p_W, Motors motors) {
    PositionTarget t;
    t.p_W = p_W;
    t.motors = motors;
    std::vector<SetPositionTargetLocalNed> m;
    for (int i = 0; i < 100 && m.empty(); ++i) {  // until the stream's next period
      BridgeInput in;
      in.position = t;
      h.step(in);
      m = h.ap.take<SetPositionTargetLocalNed>();
    }
    EXPECT_FALSE(m.empty());
    return m.empty() ? SetPositionTargetLocalNed{} : m.back();
  };
  send(Vector3d(1.0, 2.0, 1.0), Motors::kOn);
  h.ap.heartbeat(kOffboard, true);
  h.step();
  send(Vector3d(1.0, 2.0, 0.1), Motors::kOn);  // the final descent's end, below the top
  const auto m = send(Vector3d(1.05, 2.02, 0.4), Motors::kOff);
  EXPECT_FLOAT_EQ(m.x, 2.02f);  // NED: north, east, down
  EXPECT_FLOAT_EQ(m.y, 1.05f);
  EXPECT_FLOAT_EQ(m.z, -0.1f);
  EXPECT_FLOAT_EQ(m.vz, 0.5f);
  EXPECT_FALSE(m.type_mask & position_target_typemask::kVzIgnore);
  h.ap.heartbeat(kOffboard, false);
  h.step();
  const auto d = send(Vector3d(1.05, 2.02, 0.4), Motors::kOff);
  EXPECT_FLOAT_EQ(d.z, -0.4f);
  EXPECT_FLOAT_EQ(d.vz, 0.0f);
}

TEST(BridgeTest, PositionTargetsGoWithoutAccelerationUntilTheVersionIsKnown) {
  BridgeParams p = px4_params();
  p.control = "position";
  Harness h(p);
  h.answer_version = false;
  h.ap.heartbeat(kPosctl, false);
  PositionTarget t;
  t.p_W = Vector3d(1, 2, 3);
  t.a_W = Vector3d(0.3, -0.4, 0.5);
  t.motors = Motors::kOn;
  BridgeInput in;
  in.position = t;
  h.step(in);
  const auto requests = h.ap.commands(mav_cmd::kRequestMessage);
  ASSERT_EQ(requests.size(), 1u);
  EXPECT_EQ(requests[0].param1, AutopilotVersion::kId);
  const auto m = h.ap.take<SetPositionTargetLocalNed>();
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].type_mask & position_target_typemask::kAccelIgnore,
            position_target_typemask::kAccelIgnore);
  EXPECT_EQ(h.bridge.status(h.clock()).firmware, "");
  EXPECT_FALSE(h.bridge.status(h.clock()).accel_feedforward);
}

TEST(BridgeTest, MotionCaptureGoesToTheEstimatorInNedAtTheConfiguredRate) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  PoseSample p;
  p.utime = 1'700'000'000'000'000;
  p.p_W_B = Vector3d(1, 2, 3);
  p.q_WB = Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()));  // facing north
  for (int i = 0; i < 100; ++i) {  // 100 poses in 1 s (every 10 ms)
    BridgeInput in;
    p.utime += 10000;
    in.mocap = p;
    h.step(in);
    for (int k = 0; k < 9; ++k) h.step();
  }
  const auto m = h.ap.take<AttPosMocap>();
  EXPECT_EQ(m.size(), 50u);  // mocap_rate_hz
  EXPECT_FLOAT_EQ(m[0].x, 2);
  EXPECT_FLOAT_EQ(m[0].y, 1);
  EXPECT_FLOAT_EQ(m[0].z, -3);
  const auto q = quat_from_wxyz_float(m[0].q);
  ASSERT_TRUE(q);
  EXPECT_NEAR(yaw_of(q->toRotationMatrix()), 0, 1e-6);  // north in NED
  EXPECT_TRUE(std::isnan(m[0].covariance[0]));
}

TEST(BridgeTest, OdometryCarriesThePoseInLocalFrdAndTheTwistInTheBody) {
  BridgeParams params = px4_params();
  params.mocap_message = "odometry";
  Harness h(params);
  h.ap.heartbeat(kPosctl, false);
  h.step();
  PoseSample p;
  p.utime = 1'700'000'000'000'000;
  p.p_W_B = Vector3d(1, 2, 3);
  p.q_WB = Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()));  // facing north
  p.v_W_B = Vector3d(0, 1, 0.5);                                         // forward and up
  BridgeInput in;
  in.mocap = p;
  h.step(in);
  const auto m = h.ap.take<Odometry>();
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].frame_id, mav_frame::kLocalFrd);
  EXPECT_EQ(m[0].child_frame_id, mav_frame::kBodyFrd);
  EXPECT_FLOAT_EQ(m[0].x, 2);
  EXPECT_NEAR(m[0].vx, 1, 1e-6);     // forward
  EXPECT_NEAR(m[0].vz, -0.5, 1e-6);  // up is -z in FRD
  EXPECT_EQ(m[0].estimator_type, mav_estimator_type::kVision);
}

TEST(BridgeTest, ImuIsPublishedInFluWithUnixStampsKeptAndBootStampsMapped) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  HighresImu imu;
  imu.time_usec = static_cast<uint64_t>(h.clock().wall_us - 2000);  // Unix time
  imu.xacc = 0.1f, imu.yacc = 0.2f, imu.zacc = -9.81f;              // FRD at rest
  imu.xgyro = 0.01f, imu.ygyro = 0.02f, imu.zgyro = 0.03f;
  h.ap.say(imu);
  h.step();
  ASSERT_EQ(h.imu.size(), 1u);
  EXPECT_EQ(h.imu[0].utime, static_cast<int64_t>(imu.time_usec));
  EXPECT_NEAR(h.imu[0].accel_B.z(), 9.81, 1e-5);
  EXPECT_NEAR(h.imu[0].accel_B.y(), -0.2, 1e-6);
  EXPECT_NEAR(h.imu[0].gyro_B.z(), -0.03, 1e-6);

  // Boot time: the second sample arrives 4 ms sooner after its sampling than the first did; the
  // mapping keeps the smallest delay, so the two stamps are 10 - 4 ms apart, not 10.
  Harness b;
  b.ap.heartbeat(kPosctl, false);
  b.step();
  imu.time_usec = 10'000'000;
  b.ap.say(imu);
  b.step();
  const int64_t wall_1 = b.clock().wall_us - 1000;  // the step that handled it
  imu.time_usec = 10'010'000;
  b.t_us += 10'000 - 4000 - 1000;
  b.ap.say(imu);
  b.step();
  ASSERT_EQ(b.imu.size(), 2u);
  EXPECT_EQ(b.imu[0].utime, wall_1);
  EXPECT_EQ(b.imu[1].utime - b.imu[0].utime, 10'000 - 4000 + 0);
}

TEST(BridgeTest, BootStampsFollowAnAutopilotClockThatRunsSlowerThanTheWallClock) {
  // PX4 SIH's lockstep clock ran at 0.93 of the wall clock on a loaded machine: its IMU must
  // not fall behind motion capture (stamped on the wall clock) as the minutes go by.
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  HighresImu imu;
  imu.zacc = -9.81f;
  const int64_t t0 = h.t_us;
  for (int i = 0; i < 12'000; ++i) {  // 60 s at 200 Hz
    imu.time_usec = 5'000'000 + static_cast<uint64_t>(0.93 * (h.t_us - t0));
    h.ap.say(imu);
    h.step();
    h.t_us += 4000;  // 5 ms a sample with the step's 1 ms
  }
  ASSERT_GT(h.imu.size(), 11'000u);
  // The last sample was received at the previous step's wall time.
  const int64_t received = h.clock().wall_us - 5000;
  EXPECT_NEAR(static_cast<double>(h.imu.back().utime), static_cast<double>(received), 2000.0);
}

TEST(BridgeTest, ARebootIsNoticedAndTheMappingStartsAgain) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  level_attitude(h.ap, 600'000);
  h.step();
  level_attitude(h.ap, 2'000);  // boot time back by ten minutes
  h.step();
  EXPECT_EQ(h.bridge.stats().reboots, 1u);
}

TEST(BridgeTest, RefusesNonFiniteAndAbsurdTelemetry) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  HighresImu imu;
  imu.time_usec = static_cast<uint64_t>(h.clock().wall_us);
  imu.xacc = std::numeric_limits<float>::quiet_NaN();
  h.ap.say(imu);
  imu.xacc = 0;
  imu.zgyro = 1e6f;
  h.ap.say(imu);
  AttitudeQuaternion a;  // zero quaternion: not an attitude
  a.q1 = 0;
  h.ap.say(a);
  imu.zgyro = 0;
  imu.time_usec = static_cast<uint64_t>(h.clock().wall_us) + 3'600'000'000ull;  // an hour ahead
  h.ap.say(imu);
  h.step();
  EXPECT_TRUE(h.imu.empty());
  EXPECT_EQ(h.bridge.stats().rejected_values, 3u);
  EXPECT_EQ(h.bridge.stats().rejected_stamps, 1u);
}

TEST(BridgeTest, AnswersTheAutopilotsTimesyncRequestsWithItsWallClock) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  Timesync req;
  req.ts1 = 123456789;
  h.ap.say(req);
  h.step();
  const auto r = h.ap.take<Timesync>();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].ts1, 123456789);
  EXPECT_EQ(r[0].tc1, (h.clock().wall_us - 1000) * 1000);
  EXPECT_EQ(r[0].target_system, 1);
}

TEST(BridgeTest, AsksForTheTelemetryRatesOneAtATime) {
  BridgeParams p = px4_params();
  p.imu_rate_hz = 200;
  p.attitude_rate_hz = 100;
  Harness h(p);
  h.ap.heartbeat(kPosctl, false);
  h.step();
  auto c = h.ap.commands(mav_cmd::kSetMessageInterval);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].param1, HighresImu::kId);
  EXPECT_EQ(c[0].param2, 5000.0f);
  h.ap.ack(mav_cmd::kSetMessageInterval, mav_result::kAccepted);
  h.step();
  c = h.ap.commands(mav_cmd::kSetMessageInterval);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].param1, AttitudeQuaternion::kId);
}

TEST(BridgeTest, FramesFromOtherSystemsAreIgnored) {
  Harness h;
  h.ap.heartbeat(kPosctl, false);
  h.step();
  Sender other(7, 1);
  Heartbeat hb;
  hb.autopilot = mav_autopilot::kPx4;
  hb.base_mode = mav_mode_flag::kSafetyArmed;
  const FrameBytes f = other.pack(hb, 0);
  h.ap.pending.insert(h.ap.pending.end(), f.bytes().begin(), f.bytes().end());
  h.step();
  EXPECT_FALSE(h.bridge.status(h.clock()).armed);
  EXPECT_EQ(h.bridge.stats().foreign_frames, 1u);
}

TEST(BridgeTest, SurvivesNoiseAndKeepsTheFramesBetweenIt) {
  Harness h;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 200; ++i) {
    for (int k = 0; k < 50; ++k) h.ap.pending.push_back(static_cast<uint8_t>(byte(rng)));
    h.ap.heartbeat(kPosctl, false);
    h.step();
  }
  EXPECT_TRUE(h.bridge.link_up());
  EXPECT_GE(h.bridge.stats().heartbeats, 195u);  // a random byte run may swallow a few
  EXPECT_GT(h.bridge.parser_stats().bytes_dropped, 0u);
}

TEST(BridgeTest, RandomBytesNeverCrashOrArm) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  Harness h;
  for (int i = 0; i < 2000; ++i) {
    const int n = byte(rng);
    for (int k = 0; k < n; ++k) h.ap.pending.push_back(static_cast<uint8_t>(byte(rng)));
    h.step();
  }
  EXPECT_TRUE(h.ap.commands(mav_cmd::kComponentArmDisarm).empty());
}

}  // namespace
}  // namespace alight::mavlink

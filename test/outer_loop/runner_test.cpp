// The outer loop node's input handling (Runner): the boundary, restart and timer behaviour,
// with injected clocks (no LCM, no sleeping).

#include "outer_loop/runner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "common/channels.hpp"
#include "common/msg_convert.hpp"
#include "common/operator_auth.hpp"
#include "common/stamp_guard.hpp"
#include "lag_model.hpp"
#include "outer_loop/convert.hpp"

namespace alight::outer_loop {
namespace {

constexpr int64_t kRunnerT0 = 1'700'000'000'000'000;
constexpr int64_t kRunnerMs = 1000;

OuterLoopParams runner_params() {
  OuterLoopParams p;
  p.mass_kg = 1.2;
  return p;
}

// A node's boundary with clocks the test moves: steady from 0, wall = kRunnerT0 + steady (the
// stamps of the test's inputs run on the same clock, as the simulator's do at real time).
struct Harness {
  int64_t steady_us = 0;
  StampGuard guard;
  std::map<std::string, int> rejected_values, rejected_stamps;
  Runner runner;
  test::LagModel model;
  std::optional<AttitudeCommand> last;
  int published = 0;

  // The operator's key and this vehicle's id, as the node loads them from the vehicle file.
  OperatorKey key{std::vector<uint8_t>(32, 0x42)};
  KillVerifier kills{key, "alight", 2'000'000};

  explicit Harness(PersistentState restored = {}, OuterLoopParams p = runner_params())
      : runner(p, restored, gate()) {}

  InputGate gate() {
    InputGate g;
    g.reject_value = [this](const std::string& ch, const std::string&) {
      ++rejected_values[ch];
      return false;
    };
    g.accept_stamp = [this](const std::string& ch, int64_t utime) {
      const bool ok = stamp_ok(guard.check(ch, utime, steady_us, kRunnerT0 + steady_us));
      if (!ok) ++rejected_stamps[ch];
      return ok;
    };
    g.authorise_kill = [this](const operator_cmd_t& cmd) -> std::string {
      const KillCheck c = kills.check(cmd, now());
      return c == KillCheck::kAuthorised ? "" : kill_check_name(c);
    };
    return g;
  }
  // The operator's KILL as the ground station signs it and autonomy passes it on.
  operator_cmd_t signed_kill(const std::string& vehicle = "alight", int64_t age_us = 0) const {
    operator_cmd_t k{};
    k.utime = now() - age_us;
    k.seq = 7;
    k.sender = "gs";
    k.vehicle_id = vehicle;
    k.session = 1;
    k.command = operator_cmd_t::CMD_KILL;
    sign(k, key);
    return k;
  }
  void kill_setpoint(const Vector3d& p, const std::optional<operator_cmd_t>& authority) {
    for (int k = 0; k < 10; ++k) model.step(last.value_or(AttitudeCommand{}), 0.001);
    steady_us += 10 * kRunnerMs;
    pose();
    PositionSetpoint sp;
    sp.utime = now();
    sp.p_W = p;
    sp.kill = true;
    position_setpoint_t m = to_msg(sp);
    if (authority) m.kill_authority = *authority;
    take(runner.on_setpoint(m, steady_us));
    tick();
  }
  int64_t now() const { return kRunnerT0 + steady_us; }
  void take(const std::optional<AttitudeCommand>& c) {
    if (!c) return;
    last = c;
    ++published;
  }
  void pose(pose_t m) { take(runner.on_pose(m, steady_us)); }
  void pose() { pose(alight::to_msg(model.pose(now()), 0)); }
  void setpoint(const PositionSetpoint& sp) { take(runner.on_setpoint(to_msg(sp), steady_us)); }
  void tick() { take(runner.tick(steady_us)); }
  // 10 ms of flight: model, then pose, setpoint (if any) and the 100 Hz timer tick.
  void step(const std::optional<PositionSetpoint>& sp, bool with_pose = true) {
    for (int k = 0; k < 10; ++k) model.step(last.value_or(AttitudeCommand{}), 0.001);
    steady_us += 10 * kRunnerMs;
    if (with_pose) pose();
    if (sp) {
      auto s = *sp;
      s.utime = now();
      setpoint(s);
    }
    tick();
  }
};

PositionSetpoint hover_sp(const Vector3d& p) {
  PositionSetpoint sp;
  sp.p_W = p;
  sp.motors_on = true;
  return sp;
}

TEST(OuterLoopRegression, NanPoseIsRefusedCountedAndTheLastGoodKept) {
  Harness h;
  h.model.hover_at({0, 0, 1});
  h.model.floor = false;
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1}));
  ASSERT_TRUE(h.last && h.last->armed);
  const int before = h.published;
  pose_t bad = alight::to_msg(h.model.pose(h.now()), 0);
  bad.pos[2] = std::nan("");
  h.pose(bad);
  EXPECT_EQ(h.rejected_values[channels::kMocapPose], 1);
  EXPECT_EQ(h.published, before) << "a refused pose steps nothing";
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1}));
  EXPECT_TRUE(std::isfinite(h.last->thrust_N));
  EXPECT_TRUE(h.runner.controller().integral().allFinite());
  EXPECT_NEAR(h.model.p.z(), 1.0, 0.05);
}

TEST(OuterLoopRegression, SetpointStampedZeroWithMotorsOffDoesNotDisarm) {
  Harness h;
  h.model.hover_at({0, 0, 1});
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1}));
  ASSERT_TRUE(h.last->armed);
  position_setpoint_t off = to_msg(hover_sp({0, 0, 1}));
  off.utime = 0;
  off.motors = position_setpoint_t::MOTORS_OFF;
  h.take(h.runner.on_setpoint(off, h.steady_us));
  EXPECT_EQ(h.rejected_stamps[channels::kPositionSetpoint], 1);
  for (int i = 0; i < 10; ++i) h.step(hover_sp({0, 0, 1}));
  EXPECT_TRUE(h.last->armed);
  EXPECT_NEAR(h.model.p.z(), 1.0, 0.05);
}

TEST(OuterLoopRegression, PoseStampedAnHourAheadDoesNotPoisonLaterPoses) {
  Harness h;
  h.model.hover_at({0, 0, 1});
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1}));
  pose_t ahead = alight::to_msg(h.model.pose(h.now() + 3'600'000'000LL), 0);
  h.pose(ahead);
  EXPECT_EQ(h.rejected_stamps[channels::kMocapPose], 1);
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1}));
  EXPECT_EQ(h.rejected_stamps[channels::kMocapPose], 1) << "later poses accepted";
  EXPECT_EQ(h.last->mode, Mode::kNormal);
  EXPECT_TRUE(h.last->armed);
}

TEST(OuterLoopRegression, RestartedOuterLoopPublishesNothingUntilPoseAndSetpointAreFresh) {
  // A restart in flight: poses arrive first (autonomy's next setpoint comes later).
  Harness h(PersistentState{false, true});
  h.model.hover_at({0, 0, 1});
  h.model.floor = false;
  for (int i = 0; i < 20; ++i) {
    for (int k = 0; k < 10; ++k) h.model.step(AttitudeCommand{1, 0, 0, 0, 1.2 * 9.81, true}, 0.001);
    h.steady_us += 10 * kRunnerMs;
    h.pose();
    h.tick();
  }
  EXPECT_EQ(h.published, 0) << "no armed=false on the first pose";
  h.step(hover_sp({0, 0, 1}));
  ASSERT_EQ(h.published, 1) << "from the first fresh setpoint on";
  EXPECT_TRUE(h.last->armed);
}

TEST(OuterLoopRegression, FailsafeRunsOnItsTimerWhenPoseAndSetpointsBothStop) {
  Harness h;
  h.model.hover_at({0, 0, 2});
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 2}));
  ASSERT_TRUE(h.last->armed);
  // Motion capture and autonomy both gone: only the timer ticks.
  bool saw_hold = false, saw_descent = false, disarmed_in_air = false;
  const int published_before = h.published;
  for (int i = 0; i < 3000; ++i) {
    h.step(std::nullopt, false);
    saw_hold |= h.last->mode == Mode::kHoldLevel;
    saw_descent |= h.last->mode == Mode::kFailsafeDescent;
    if (!h.last->armed && h.model.p.z() > 0.3) disarmed_in_air = true;
  }
  EXPECT_GT(h.published - published_before, 1000) << "publishes on its timer";
  EXPECT_TRUE(saw_hold);
  EXPECT_TRUE(saw_descent);
  EXPECT_FALSE(h.last->armed) << "disarmed after failsafe_disarm_after_s";
  EXPECT_FALSE(disarmed_in_air);
  EXPECT_NEAR(h.model.p.z(), 0.0, 1e-9);
  EXPECT_TRUE(h.runner.controller().persistent_state().disarm_latched);
}

TEST(OuterLoopRegression, KillFromAutonomyDisarmsInTheAirButAPlainMotorsOffLands) {
  Harness h;
  h.model.hover_at({0, 0, 1.5});
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1.5}));
  auto off = hover_sp({0, 0, 1.5});
  off.motors_on = false;
  h.step(off);
  EXPECT_TRUE(h.last->armed);
  h.kill_setpoint({0, 0, 1.5}, h.signed_kill());
  EXPECT_FALSE(h.last->armed);
  ASSERT_TRUE(h.runner.kill_authority());
  EXPECT_EQ(h.runner.kill_authority()->command, operator_cmd_t::CMD_KILL);
  EXPECT_EQ(h.runner.kills_refused(), 0u);
}

// Regression: one unsigned POSITION_SETPOINT with MOTORS_KILL sent from the network stopped the
// motors at 1.6 m. A KILL without the operator's signature (none, forged, for another vehicle,
// or stale) is a motors-off: the vehicle lands and disarms on the ground.
TEST(OuterLoopRegression, AKillWithoutTheOperatorsSignatureLandsInsteadOfStoppingTheMotors) {
  for (int variant = 0; variant < 4; ++variant) {
    Harness h;
    h.model.hover_at({0, 0, 1.6});
    for (int i = 0; i < 100; ++i) h.step(hover_sp({0, 0, 1.6}));
    std::optional<operator_cmd_t> authority;
    if (variant == 1) {
      authority = h.signed_kill();
      authority->hmac[0] ^= 1;  // forged
    }
    if (variant == 2) authority = h.signed_kill("another-vehicle");
    if (variant == 3) authority = h.signed_kill("alight", 10'000'000);  // recorded 10 s ago
    bool disarmed_in_air = false;
    for (int i = 0; i < 1500; ++i) {
      h.kill_setpoint({0, 0, 1.6}, authority);
      if (!h.last->armed && h.model.p.z() > 0.05) disarmed_in_air = true;
    }
    EXPECT_FALSE(disarmed_in_air) << "variant " << variant;
    EXPECT_LT(h.model.p.z(), 0.01) << "landed, variant " << variant;
    EXPECT_FALSE(h.last->armed) << "disarmed on the ground, variant " << variant;
    EXPECT_GT(h.runner.kills_refused(), 0u);
    EXPECT_FALSE(h.runner.kill_authority());
  }
}

// Regression: every MOCAP_POSE re-sent shifted by 30 cm landed the vehicle beside the platform.
// A pose off its prediction is refused; a stream that keeps disagreeing latches the gate and the
// vehicle holds level, then descends, never re-centred on the new stream.
TEST(OuterLoopRegression, APoseOffItsPredictionIsRefusedAndASustainedOneIsAFailsafe) {
  Harness h;
  h.model.hover_at({0.5, 0, 1.6});
  for (int i = 0; i < 100; ++i) h.step(hover_sp({0.5, 0, 1.6}));
  // Interleaved: each genuine pose followed by one shifted 30 cm.
  for (int i = 0; i < 100; ++i) {
    h.step(hover_sp({0.5, 0, 1.6}));
    pose_t forged = alight::to_msg(h.model.pose(h.now()), 0);
    forged.pos[0] += 0.3;
    h.pose(forged);
  }
  EXPECT_EQ(h.rejected_values[channels::kMocapPose], 100);
  EXPECT_EQ(h.last->mode, Mode::kNormal);
  EXPECT_NEAR(h.model.p.x(), 0.5, 0.01) << "the forged poses moved nothing";
  // Replaced: only shifted poses from now on.
  bool saw_hold = false, saw_descent = false;
  double max_dx = 0;
  for (int i = 0; i < 300; ++i) {
    for (int k = 0; k < 10; ++k) h.model.step(h.last.value_or(AttitudeCommand{}), 0.001);
    h.steady_us += 10 * kRunnerMs;
    pose_t forged = alight::to_msg(h.model.pose(h.now()), 0);
    forged.pos[0] += 0.3;
    h.pose(forged);
    auto sp = hover_sp({0.5, 0, 1.6});
    sp.utime = h.now();
    h.setpoint(sp);
    h.tick();
    saw_hold |= h.last->mode == Mode::kHoldLevel;
    saw_descent |= h.last->mode == Mode::kFailsafeDescent;
    max_dx = std::max(max_dx, std::abs(h.model.p.x() - 0.5));
  }
  EXPECT_TRUE(h.runner.pose_gate().latched());
  EXPECT_TRUE(saw_hold);
  EXPECT_TRUE(saw_descent);
  EXPECT_NE(std::string(h.last->reason).find("innovation gate"), std::string::npos)
      << h.last->reason;
  EXPECT_LT(max_dx, 0.1) << "never flown toward the shifted poses";
}

// Regression: setpoints from a second publisher for 8 s flew the vehicle out of the flying area.
// The outer loop keeps its own geofence and speed limit: a far setpoint is approached at no more
// than max_speed_xy_mps and stops 0.2 m inside the fence.
TEST(OuterLoopRegression, AFarSetpointIsFlownSlowlyAndStopsInsideTheGeofence) {
  OuterLoopParams p = runner_params();
  p.geofence_min_W_m = Vector3d(-3, -3, -0.5);
  p.geofence_max_W_m = Vector3d(4.7, 3, 2.6);
  Harness h({}, p);
  h.model.hover_at({0, 0, 1.2});
  double max_speed = 0, max_x = 0;
  for (int i = 0; i < 1500; ++i) {
    h.step(hover_sp({25, 0, 1.2}));
    max_speed = std::max(max_speed, h.model.v.head<2>().norm());
    max_x = std::max(max_x, h.model.p.x());
  }
  EXPECT_LE(max_speed, p.max_speed_xy_mps * 1.1);
  EXPECT_LE(max_x, p.geofence_max_W_m.x());
  EXPECT_NEAR(h.model.p.x(), p.geofence_max_W_m.x() - kFenceInsetM, 0.05);
  EXPECT_EQ(h.last->mode, Mode::kNormal);
}

// A moving setpoint (a platform followed, its velocity fed forward) is followed at its own speed
// beyond max_speed_xy_mps, up to max_feedforward_xy_mps; faster, it falls behind, and the
// vehicle never flies faster than the two together.
TEST(OuterLoopTest, AMovingSetpointIsFollowedUpToTheFeedForwardBound) {
  for (const double v_mps : {1.5, 3.0}) {
    OuterLoopParams p = runner_params();
    p.geofence_min_W_m = Vector3d(-100, -3, -0.5);
    p.geofence_max_W_m = Vector3d(100, 3, 2.6);
    ASSERT_LT(p.max_speed_xy_mps, 1.5);
    ASSERT_GT(p.max_feedforward_xy_mps, 1.5);
    ASSERT_LT(p.max_feedforward_xy_mps, 3.0);
    Harness h({}, p);
    h.model.hover_at({0, 0, 1.2});
    double max_speed = 0;
    for (int i = 0; i < 1000; ++i) {  // 10 s
      PositionSetpoint sp = hover_sp({v_mps * 0.01 * i, 0, 1.2});
      sp.v_W = Vector3d(v_mps, 0, 0);
      h.step(sp);
      max_speed = std::max(max_speed, h.model.v.head<2>().norm());
    }
    const double lag_m = v_mps * 0.01 * 999 - h.model.p.x();
    EXPECT_LE(max_speed, (p.max_speed_xy_mps + p.max_feedforward_xy_mps) * 1.05) << v_mps;
    if (v_mps <= p.max_feedforward_xy_mps) {
      EXPECT_NEAR(h.model.v.x(), v_mps, 0.05) << "followed at its own speed";
      EXPECT_LT(std::abs(lag_m), 0.1) << v_mps;
    } else {
      EXPECT_GT(lag_m, 1.0) << "beyond what the vehicle follows: left behind";
    }
    EXPECT_EQ(h.last->mode, Mode::kNormal) << v_mps;
  }
}

// Pushed out of the flying area (a gust, a wrong pose): hold, then land and disarm there.
TEST(OuterLoopRegression, LeavingTheGeofenceHoldsThenLands) {
  OuterLoopParams p = runner_params();
  p.geofence_min_W_m = Vector3d(-3, -3, -0.5);
  p.geofence_max_W_m = Vector3d(4.7, 3, 2.6);
  Harness h({}, p);
  h.model.hover_at({4.5, 0, 1.2});
  for (int i = 0; i < 50; ++i) h.step(hover_sp({4.5, 0, 1.2}));
  h.model.v.x() = 1.5;  // a gust carries it out
  bool saw_hold = false, disarmed_in_air = false;
  for (int i = 0; i < 3000; ++i) {
    h.step(hover_sp({4.5, 0, 1.2}));
    if (h.last->mode == Mode::kFailsafeLand && h.steady_us < 2'500'000)
      saw_hold |= std::abs(h.model.p.z() - 1.2) < 0.05;
    if (!h.last->armed && h.model.p.z() > 0.05) disarmed_in_air = true;
  }
  EXPECT_TRUE(saw_hold);
  EXPECT_FALSE(disarmed_in_air);
  EXPECT_LT(h.model.p.z(), 0.01);
  EXPECT_FALSE(h.last->armed);
  EXPECT_LE(h.model.p.x(), p.geofence_max_W_m.x()) << "held inside the fence";
}

// Regression: a moving platform's follow ran on an unmeasured prediction towards a wall of the
// room, the vehicle catching it up at nearly twice its speed, and overshot the setpoint, held at
// the fence's inset, out of the room. Towards a wall the loop asks only for a speed it stops
// from before the inset.
TEST(OuterLoopRegression, AFollowRunningIntoTheFenceStopsInsideIt) {
  OuterLoopParams p = runner_params();
  p.geofence_min_W_m = Vector3d(-3, -3, -0.5);
  p.geofence_max_W_m = Vector3d(3, 3, 2.6);
  Harness h({}, p);
  h.model.hover_at({1.2, 1.0, 1.2});
  double max_x = -10, max_speed = 0;
  for (int i = 0; i < 500; ++i) {  // 5 s
    PositionSetpoint sp = hover_sp({1.7 + 0.96 * 0.01 * i, 1.4, 1.2});
    sp.v_W = Vector3d(0.96, 0.0, 0.0);
    h.step(sp);
    max_x = std::max(max_x, h.model.p.x());
    max_speed = std::max(max_speed, h.model.v.head<2>().norm());
  }
  EXPECT_GT(max_speed, 1.3) << "the catch-up that overshot";
  EXPECT_LE(max_x, p.geofence_max_W_m.x() - 0.5 * kFenceInsetM) << "within half the inset";
  EXPECT_NEAR(h.model.p.x(), p.geofence_max_W_m.x() - kFenceInsetM, 0.05);
  EXPECT_NEAR(h.model.p.y(), 1.4, 0.05) << "the other axis followed as ever";
  EXPECT_EQ(h.last->mode, Mode::kNormal);
}

TEST(FenceStoppingSpeed, StopsWithinTheDistanceAndIsZeroAtTheWall) {
  EXPECT_EQ(fence_stopping_speed(0.0, 1.8, 0.3), 0.0);
  EXPECT_EQ(fence_stopping_speed(-0.5, 1.8, 0.3), 0.0);
  for (const double d : {0.05, 0.3, 1.0, 4.0}) {
    const double v = fence_stopping_speed(d, 1.8, 0.3);
    EXPECT_NEAR(v * 0.3 + v * v / (2 * 1.8), d, 1e-12) << d;
  }
  EXPECT_NEAR(fence_stopping_speed(1.0, 2.0, 0.0), 2.0, 1e-12);  // no lag: sqrt(2 a d)
}

}  // namespace
}  // namespace alight::outer_loop

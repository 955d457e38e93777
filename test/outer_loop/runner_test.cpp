// The outer loop node's input handling (Runner): the boundary, restart and timer behaviour,
// with injected clocks (no LCM, no sleeping).

#include "outer_loop/runner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "common/channels.hpp"
#include "common/msg_convert.hpp"
#include "common/stamp_guard.hpp"
#include "lag_model.hpp"
#include "outer_loop/convert.hpp"

namespace alight::outer_loop {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kMs = 1000;

OuterLoopParams params() {
  OuterLoopParams p;
  p.mass_kg = 1.2;
  return p;
}

// A node's boundary with clocks the test moves: steady from 0, wall = kT0 + steady (the stamps
// of the test's inputs run on the same clock, as the simulator's do at real time).
struct Harness {
  int64_t steady_us = 0;
  StampGuard guard;
  std::map<std::string, int> rejected_values, rejected_stamps;
  Runner runner;
  test::LagModel model;
  std::optional<AttitudeCommand> last;
  int published = 0;

  explicit Harness(PersistentState restored = {}) : runner(params(), restored, gate()) {}

  InputGate gate() {
    InputGate g;
    g.reject_value = [this](const std::string& ch, const std::string&) {
      ++rejected_values[ch];
      return false;
    };
    g.accept_stamp = [this](const std::string& ch, int64_t utime) {
      const bool ok = stamp_ok(guard.check(ch, utime, steady_us, kT0 + steady_us));
      if (!ok) ++rejected_stamps[ch];
      return ok;
    };
    return g;
  }
  int64_t now() const { return kT0 + steady_us; }
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
    steady_us += 10 * kMs;
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
    h.steady_us += 10 * kMs;
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
  off.kill = true;
  h.step(off);
  EXPECT_FALSE(h.last->armed);
}

}  // namespace
}  // namespace alight::outer_loop

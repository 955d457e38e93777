// The simulated autopilot's command-loss failsafe (PX4's offboard loss, ArduPilot's guided
// timeout): when ATTITUDE_CMD stops, level, then descend, then disarm on the ground; and the
// ATTITUDE_CMD input boundary.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "sim/sim_msgs.hpp"
#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::hover;
using test::place;

constexpr int64_t kMs = 1000;

class SimCommandLossTest : public ::testing::Test {
 protected:
  Scenario scenario_ = test::quiet(test::scenario("landing_none"));
  VehicleParams vehicle_ = test::starmac();
};

double tilt_deg(const VehicleState& s) {
  return std::acos(std::clamp(s.q_WB.toRotationMatrix()(2, 2), -1.0, 1.0)) * 180.0 / M_PI;
}

TEST_F(SimCommandLossTest, CommandLossLevelsThenDescendsThenDisarmsOnTheGround) {
  // Given a vehicle at 2 m whose last command was a tilted climb
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 2.0));
  AttitudeCommand last = hover(vehicle_);
  last.roll_rad = 0.2;
  last.thrust_N = 1.1 * vehicle_.hover_thrust_N();
  sim.step(last, sim.now_utime() + 10 * kMs);
  const int64_t t_lost = sim.now_utime();
  // When ATTITUDE_CMD stops: within the timeout the autopilot still follows the last command
  sim.advance_to(t_lost + static_cast<int64_t>(vehicle_.cmd_loss_timeout_s * 0.9e6));
  EXPECT_GT(tilt_deg(sim.state()), 8.0);
  EXPECT_FALSE(sim.truth().command_lost);
  // Then it levels and stops climbing
  const int64_t t_fs = t_lost + static_cast<int64_t>(vehicle_.cmd_loss_timeout_s * 1e6);
  sim.advance_to(t_fs + static_cast<int64_t>(vehicle_.cmd_loss_level_s * 0.9e6));
  EXPECT_TRUE(sim.truth().command_lost);
  EXPECT_LT(tilt_deg(sim.state()), 1.0);
  EXPECT_LT(std::abs(sim.state().v_W_B.z()), 0.1);
  EXPECT_TRUE(sim.state().armed);
  // Then it descends at the configured rate
  sim.advance_to(sim.now_utime() + 2000 * kMs);
  EXPECT_NEAR(sim.state().v_W_B.z(), -vehicle_.cmd_loss_descent_mps, 0.05);
  EXPECT_TRUE(sim.state().armed);
  // And ends on the ground, disarmed, upright
  bool disarmed_in_air = false;
  for (int i = 0; i < 200 && sim.state().armed; ++i) {
    sim.advance_to(sim.now_utime() + 100 * kMs);
    if (!sim.state().armed && sim.state().p_W_B.z() > 0.3) disarmed_in_air = true;
  }
  EXPECT_FALSE(sim.state().armed);
  EXPECT_FALSE(disarmed_in_air);
  EXPECT_LT(sim.state().p_W_B.z(), 0.2);
  EXPECT_FALSE(sim.truth().tipped);
  // A restarted outer loop's armed command does not re-arm it; a disarmed one first does.
  sim.step(last, sim.now_utime() + 500 * kMs);
  EXPECT_FALSE(sim.state().armed);
  sim.step(AttitudeCommand{}, sim.now_utime() + 10 * kMs);
  sim.step(hover(vehicle_), sim.now_utime() + 10 * kMs);
  EXPECT_TRUE(sim.state().armed);
}

// Regression: a forged ATTITUDE_CMD{armed = false} dropped the simulated vehicle from 1.6 m. As
// PX4 and ArduPilot do, the simulated autopilot refuses a disarm in flight unless it is forced
// (the node forces it only for the operator's signed KILL); on the ground it disarms.
TEST_F(SimCommandLossTest, ADisarmInTheAirIsRefusedUnlessForced) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 1.6));
  sim.command(hover(vehicle_));
  sim.advance_to(sim.now_utime() + 100 * kMs);
  ASSERT_TRUE(sim.state().armed);
  for (int i = 0; i < 50; ++i) {
    sim.command(AttitudeCommand{sim.now_utime()});  // armed false, not forced
    sim.advance_to(sim.now_utime() + 10 * kMs);
  }
  EXPECT_TRUE(sim.state().armed);
  EXPECT_EQ(sim.disarms_refused(), 50u);
  EXPECT_NEAR(sim.state().p_W_B.z(), 1.6, 0.05) << "kept flying the last armed command";
  AttitudeCommand kill{sim.now_utime()};
  kill.forced = true;
  sim.command(kill);
  sim.advance_to(sim.now_utime() + 10 * kMs);
  EXPECT_FALSE(sim.state().armed);
}

TEST_F(SimCommandLossTest, ADisarmOnTheGroundIsTaken) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 1.0));
  AttitudeCommand down = hover(vehicle_);
  down.thrust_N = 0.6 * vehicle_.hover_thrust_N();
  for (int i = 0; i < 300; ++i) {
    sim.command(down);
    sim.advance_to(sim.now_utime() + 10 * kMs);
  }
  ASSERT_LT(sim.state().p_W_B.z(), 0.2);
  sim.command(AttitudeCommand{sim.now_utime()});
  sim.advance_to(sim.now_utime() + 10 * kMs);
  EXPECT_FALSE(sim.state().armed);
  EXPECT_EQ(sim.disarms_refused(), 0u);
}

TEST_F(SimCommandLossTest, StepHoldsACommandAsIfReceivedAllTheWhile) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 1.5));
  sim.step(hover(vehicle_), sim.now_utime() + 5000 * kMs);
  EXPECT_FALSE(sim.truth().command_lost);
  EXPECT_LT((sim.state().p_W_B - Vector3d(0, 0, 1.5)).norm(), 1e-3);
}

TEST_F(SimCommandLossTest, CommandsComingBackEndTheFailsafe) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 2.0));
  sim.command(hover(vehicle_));
  sim.advance_to(sim.now_utime() + 2500 * kMs);
  ASSERT_TRUE(sim.truth().command_lost);
  AttitudeCommand climb = hover(vehicle_);
  climb.thrust_N *= 1.2;
  for (int i = 0; i < 50; ++i) {
    sim.command(climb);
    sim.advance_to(sim.now_utime() + 10 * kMs);
  }
  EXPECT_FALSE(sim.truth().command_lost);
  EXPECT_GT(sim.state().v_W_B.z(), 0.3) << "follows the commands again";
}

TEST_F(SimCommandLossTest, ADisarmedVehicleStaysDisarmedWithoutCommands) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, vehicle_.gear_height_m), false);
  sim.command(AttitudeCommand{});
  sim.advance_to(sim.now_utime() + 5000 * kMs);
  EXPECT_FALSE(sim.state().armed);
  EXPECT_FALSE(sim.truth().command_lost);
  EXPECT_EQ(sim.state().thrust_N, 0.0);
}

TEST(SimRegression, NonFiniteAttitudeCommandIsRefused) {
  attitude_cmd_t m{};
  m.utime = 1;
  m.armed = true;
  m.thrust_N = 10;
  std::string why;
  ASSERT_TRUE(command_from_msg(m, &why));
  for (int field = 0; field < 4; ++field) {
    for (double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
      attitude_cmd_t b = m;
      if (field == 0) b.roll_rad = bad;
      if (field == 1) b.pitch_rad = bad;
      if (field == 2) b.yaw_rate_radps = bad;
      if (field == 3) b.thrust_N = bad;
      EXPECT_FALSE(command_from_msg(b, &why)) << field;
      EXPECT_NE(why.find("non-finite"), std::string::npos);
    }
  }
}

// Regression (issue 14, fault campaign replay_old_log): an old session log played onto the live
// port carried the old run's ATTITUDE_CMD{armed = false}; the simulated autopilot obeyed it and
// the vehicle fell from 1.1 m. A command stamped further from the autopilot's clock than its
// command-loss timeout is refused, whichever way, and a hostile stamp cannot overflow the check.
TEST(SimRegression, CommandsStampedFarFromTheAutopilotClockAreRefused) {
  attitude_cmd_t m{};
  m.armed = false;
  const int64_t now = 1'795'597'967'000'000;
  const double max_age_s = 0.5;
  std::string why;
  m.utime = now - 200'000;  // in flight through LCM: fine
  EXPECT_TRUE(command_from_msg(m, now, max_age_s, &why)) << why;
  m.utime = now - 1'130'000'000;  // the old log, 1130 s before
  EXPECT_FALSE(command_from_msg(m, now, max_age_s, &why));
  EXPECT_NE(why.find("before the autopilot's clock"), std::string::npos) << why;
  m.utime = now + 3'600'000'000;
  EXPECT_FALSE(command_from_msg(m, now, max_age_s, &why));
  EXPECT_NE(why.find("after"), std::string::npos) << why;
  // Ahead by a starved simulator's lag (the outer loop's clock extrapolated on steady time) and
  // then back again when the next pose arrives: both taken (a monotonic stamp rule refused the
  // second for seconds, and the vehicle drifted out of the area in the autopilot's failsafe).
  m.utime = now + 2'700'000;
  EXPECT_TRUE(command_from_msg(m, now, max_age_s, &why)) << why;
  m.utime = now - 10'000;
  EXPECT_TRUE(command_from_msg(m, now, max_age_s, &why)) << why;
  for (const int64_t bad :
       {std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max(), int64_t{0}}) {
    m.utime = bad;
    EXPECT_FALSE(command_from_msg(m, now, max_age_s, &why)) << bad;
  }
  m.utime = now;
  m.thrust_N = std::nan("");
  EXPECT_FALSE(command_from_msg(m, now, max_age_s, &why));
  EXPECT_NE(why.find("non-finite"), std::string::npos);
}

TEST(SimRegression, CommandLossParametersAreBoundedAndFinite) {
  const auto dir =
      std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim_command_loss";
  std::filesystem::create_directories(dir);
  for (const char* kv :
       {"cmd_loss_timeout_s: .inf", "cmd_loss_timeout_s: 0", "cmd_loss_timeout_s: 11",
        "cmd_loss_level_s: .nan", "cmd_loss_descent_mps: .inf", "cmd_loss_disarm_after_s: 1e9"}) {
    const std::string key = std::string(kv).substr(0, std::string(kv).find(':'));
    const auto path = (dir / (key + ".yaml")).string();
    std::ofstream(path) << "vehicle:\n  " << kv << "\n";
    try {
      load_vehicle_params(path);
      ADD_FAILURE() << kv << " accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), "vehicle." + key) << kv;
      EXPECT_EQ(e.file(), path);
    }
  }
}

}  // namespace
}  // namespace alight::sim

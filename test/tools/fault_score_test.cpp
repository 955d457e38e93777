#include "tools/fault_score.hpp"

#include <gtest/gtest.h>

namespace alight::tools {
namespace {

constexpr int64_t kFaultT0 = 1'790'000'000'000'000;
constexpr int64_t kS = 1'000'000;  // one second [us]
constexpr double kRestZ = 0.05;    // body origin above the floor at rest

sim_truth_t fault_truth(int64_t t, double x, double z, bool armed, double vz = 0) {
  sim_truth_t m{};
  m.utime = t;
  m.scenario = "synthetic";
  m.pos[0] = x;
  m.pos[2] = z;
  m.vel[2] = vz;
  m.orientation[0] = 1;
  m.has_platform = true;  // 1 x 1 m, top 0.2 m, centred at x = 2
  m.platform_center_W[0] = 2.0;
  m.platform_center_W[2] = 0.2;
  m.platform_size_m[0] = m.platform_size_m[1] = 1.0;
  m.platform_size_m[2] = 0.2;
  m.armed = armed;
  m.contact = z <= kRestZ + 1e-9 ? sim_truth_t::CONTACT_FLOOR : sim_truth_t::CONTACT_NONE;
  return m;
}

autonomy_status_t fault_status(int64_t t, int8_t phase, const std::string& name) {
  autonomy_status_t s{};
  s.utime = t;
  s.mission = target_t::MISSION_LANDING;
  s.phase = phase;
  s.phase_name = name;
  return s;
}

attitude_cmd_t cmd(int64_t t, int8_t mode, bool armed = true) {
  attitude_cmd_t c{};
  c.utime = t;
  c.thrust_N = 10;
  c.armed = armed;
  c.mode = mode;
  return c;
}

process_info_t proc(const std::string& name, int8_t state, int32_t restarts, int32_t sig = 0,
                    int32_t code = 0) {
  process_info_t p{};
  p.name = name;
  p.pid = 100 + restarts;
  p.state = state;
  p.restarts = restarts;
  p.signal = sig;
  p.exit_code = code;
  p.started_utime = kFaultT0;
  return p;
}

process_status_t processes(int64_t t, std::vector<process_info_t> ps) {
  process_status_t m{};
  m.utime = t;
  m.launch_name = "faults_landing";
  m.processes = std::move(ps);
  m.n = static_cast<int32_t>(m.processes.size());
  return m;
}

constexpr int8_t kRun = process_info_t::STATE_RUNNING;

// Take-off from the floor, 10 s up at 1 m with the given final attitude mode and phase.
FaultScorer airborne_run(int8_t final_mode, int8_t final_phase, const std::string& phase_name,
                         double final_vz = 0, FaultScoreParams p = {}) {
  FaultScorer sc(p);
  sc.add(fault_truth(kFaultT0, 0, kRestZ, false), kFaultT0);
  for (int i = 1; i <= 10; ++i) {
    const int64_t t = kFaultT0 + i * kS;
    sc.add(fault_truth(t, 0, 1.0, true, i == 10 ? final_vz : 0), t);
    sc.add(cmd(t, i == 10 ? final_mode : attitude_cmd_t::MODE_NORMAL), t);
    sc.add(fault_status(t, i == 10 ? final_phase : autonomy_status_t::PHASE_REFINEMENT,
                        i == 10 ? phase_name : "REFINEMENT"),
           t);
  }
  return sc;
}

TEST(FaultScoreTest, AHoverInHoldIsASafeHold) {
  const auto r =
      airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD").result();
  EXPECT_EQ(r.outcome, "safe_hold");
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.disarms, 0);
  EXPECT_NEAR(r.final_height_m, 1.0 - kRestZ, 1e-9);
}

TEST(FaultScoreTest, AnOuterLoopDescentModeIsAFailsafeDescent) {
  const auto r = airborne_run(attitude_cmd_t::MODE_FAILSAFE_DESCENT,
                              autonomy_status_t::PHASE_FAILSAFE, "FAILSAFE", -0.3)
                     .result();
  EXPECT_EQ(r.outcome, "failsafe_descent");
  EXPECT_TRUE(r.ok);
  EXPECT_TRUE(r.failsafe_descent_seen);
}

TEST(FaultScoreTest, StillFlyingTheMissionAtTheEndIsNotAPass) {
  const auto r =
      airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_APPROACH, "APPROACH")
          .result();
  EXPECT_EQ(r.outcome, "in_mission");
  EXPECT_FALSE(r.ok);
}

TEST(FaultScoreTest, SinkingWithoutAttitudeCommandsIsTheAutopilotsFailsafe) {
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD");
  for (int i = 11; i <= 13; ++i)  // the outer loop is gone: truth only
    sc.add(fault_truth(kFaultT0 + i * kS, 0, 0.8, true, -0.4), kFaultT0 + i * kS);
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "failsafe_descent");
  EXPECT_TRUE(r.ok);
}

TEST(FaultScoreTest, ADisarmAboveThirtyCentimetresFailsTheRun) {
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD");
  sc.add(fault_truth(kFaultT0 + 11 * kS, 0, 1.0, false), kFaultT0 + 11 * kS);
  sc.add(fault_truth(kFaultT0 + 12 * kS, 0, kRestZ, false), kFaultT0 + 12 * kS);  // fell
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "disarmed_in_air");
  EXPECT_FALSE(r.ok);
  ASSERT_TRUE(r.max_disarm_height_m);
  EXPECT_NEAR(*r.max_disarm_height_m, 1.0 - kRestZ, 1e-9);
}

TEST(FaultScoreTest, HeightIsMeasuredAboveThePlatformTopWhenOverIt) {
  FaultScorer sc;
  sc.add(fault_truth(kFaultT0, 0, kRestZ, false), kFaultT0);
  sc.add(fault_truth(kFaultT0 + kS, 2.0, 0.2 + kRestZ + 0.1, true), kFaultT0 + kS);
  sc.add(fault_truth(kFaultT0 + 2 * kS, 2.0, 0.2 + kRestZ + 0.1, false),
         kFaultT0 + 2 * kS);  // 10 cm up
  sc.add(fault_truth(kFaultT0 + 3 * kS, 2.0, 0.2 + kRestZ, false), kFaultT0 + 3 * kS);
  const auto r = sc.result();
  ASSERT_TRUE(r.max_disarm_height_m);
  EXPECT_NEAR(*r.max_disarm_height_m, 0.1, 1e-9);
  EXPECT_TRUE(r.ok) << r.to_json();
  EXPECT_EQ(r.outcome, "grounded");  // on the platform, but the simulator never said landed
}

TEST(FaultScoreTest, ComingDownWithoutALandingOrFailsafeIsNotAPass) {
  // Seen with future-stamped messages: normal mode, the vehicle sinks to the floor at 1.2 m/s
  // and disarms on the impact, 0 m up.
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_DETECTION,
                                "DETECTION", -1.2);
  sc.add(fault_truth(kFaultT0 + 11 * kS, 0, 0.3, true, -1.2), kFaultT0 + 11 * kS);
  sc.add(fault_truth(kFaultT0 + 12 * kS, 0, kRestZ, false), kFaultT0 + 12 * kS);
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "came_down");
  EXPECT_FALSE(r.ok);
  ASSERT_TRUE(r.max_touchdown_speed_mps);
  EXPECT_NEAR(*r.max_touchdown_speed_mps, 1.2, 1e-9);
  ASSERT_TRUE(r.max_disarm_height_m);
  EXPECT_LT(*r.max_disarm_height_m, 0.3);
}

TEST(FaultScoreTest, NeverLeavingTheGroundIsGrounded) {
  FaultScorer sc;
  for (int i = 0; i < 5; ++i)
    sc.add(fault_truth(kFaultT0 + i * kS, 0, kRestZ, false), kFaultT0 + i * kS);
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "grounded");
  EXPECT_TRUE(r.ok);
}

TEST(FaultScoreTest, TheKilledProcessIsExpectedAndAnyOtherExitIsNot) {
  FaultScoreParams p;
  p.expected_exit = "vision";
  FaultScorer sc =
      airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD", 0, p);
  const int64_t t = kFaultT0 + 10 * kS;
  sc.add(processes(t + 1, {proc("vision", kRun, 0), proc("autonomy", kRun, 0)}), t + 1);
  sc.add(processes(t + 2, {proc("vision", process_info_t::STATE_BACKOFF, 0, 9),
                           proc("autonomy", kRun, 0)}),
         t + 2);
  sc.add(processes(t + 3, {proc("vision", kRun, 1, 9), proc("autonomy", kRun, 0)}), t + 3);
  auto r = sc.result();
  EXPECT_TRUE(r.ok) << r.to_json();
  ASSERT_EQ(r.exits.size(), 1u);
  EXPECT_TRUE(r.exits[0].expected);
  // Autonomy crashed, and its BACKOFF status was lost: the restart counter still tells.
  sc.add(processes(t + 4, {proc("vision", kRun, 1, 9), proc("autonomy", kRun, 1, 0, 1)}), t + 4);
  r = sc.result();
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.unexpected_exits, 1);
  ASSERT_EQ(r.exits.size(), 2u);
  EXPECT_EQ(r.exits[1].name, "autonomy");
  EXPECT_EQ(r.exits[1].exit_code, 1);
}

TEST(FaultScoreTest, AKillThatNeverHappenedIsReported) {
  FaultScoreParams p;
  p.expected_exit = "outer_loop";
  const auto r =
      airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD", 0, p)
          .result();
  EXPECT_FALSE(r.ok);
}

TEST(FaultScoreTest, TheShutdownIsNotAnExit) {
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD");
  const int64_t t = kFaultT0 + 10 * kS;
  sc.add(processes(t + 1, {proc("sim", kRun, 0)}), t + 1);
  sc.add(processes(t + 2, {proc("sim", process_info_t::STATE_STOPPED, 0, 2)}), t + 2);
  EXPECT_TRUE(sc.result().ok);
}

TEST(FaultScoreTest, InjectedAndReplayedMessagesDoNotFoolTheReferee) {
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD");
  const int64_t t = kFaultT0 + 10 * kS;
  sc.add(processes(t, {proc("vision", kRun, 0)}), t);
  // A future-stamped status, an old one replayed, and the same for the launcher's report.
  sc.add(fault_status(t + 3600 * kS, autonomy_status_t::PHASE_KILLED, "KILLED"), t + 1);
  sc.add(fault_status(t - 3600 * kS, autonomy_status_t::PHASE_APPROACH, "APPROACH"), t + 2);
  sc.add(processes(t - 3600 * kS, {proc("vision", process_info_t::STATE_BACKOFF, 0, 11)}), t + 3);
  sc.add(processes(0, {proc("vision", process_info_t::STATE_FAILED, 0, 6)}), t + 4);
  sc.add(cmd(t - 100 * kS, attitude_cmd_t::MODE_DISARMED, false), t + 5);
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "safe_hold");
  EXPECT_EQ(r.final_phase, "HOLD");
  EXPECT_TRUE(r.exits.empty());
  EXPECT_EQ(r.refused_messages, 5);
  EXPECT_TRUE(r.ok) << r.to_json();
}

TEST(FaultScoreTest, ARunningNodeThatStopsReportingIsHung) {
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD");
  node_status_t ns{};
  ns.node = "alight-ground-station";
  ns.pid = 100;
  for (int i = 1; i <= 4; ++i) {  // reports for 4 s, then nothing for 6 s
    ns.utime = kFaultT0 + i * kS;
    ns.uptime_s = i;
    sc.add(ns, kFaultT0 + i * kS);
    sc.add(ns,
           kFaultT0 + i * kS + 10);  // a copy (injected): refused, the node's uptime did not grow
  }
  sc.add(processes(kFaultT0 + 10 * kS, {proc("ground_station", kRun, 0)}), kFaultT0 + 10 * kS);
  const auto r = sc.result();
  ASSERT_EQ(r.silent_nodes.size(), 1u);
  EXPECT_EQ(r.silent_nodes[0], "alight-ground-station");
  EXPECT_FALSE(r.ok);
}

TEST(FaultScoreTest, ALandingOnTheTargetMeetsTheGoal) {
  FaultScorer sc;
  sc.add(fault_truth(kFaultT0, 0, kRestZ, false), kFaultT0);
  sc.add(fault_status(kFaultT0 + kS, autonomy_status_t::PHASE_DETECTION, "DETECTION"),
         kFaultT0 + kS);
  sc.add(fault_truth(kFaultT0 + 2 * kS, 2.0, 0.5, true), kFaultT0 + 2 * kS);
  sc.add(fault_status(kFaultT0 + 3 * kS, autonomy_status_t::PHASE_LANDED, "LANDED"),
         kFaultT0 + 3 * kS);
  auto t = fault_truth(kFaultT0 + 3 * kS, 2.0, 0.2 + kRestZ, false);
  t.landed = true;
  t.contact = sim_truth_t::CONTACT_PLATFORM_TOP;
  sc.add(t, kFaultT0 + 3 * kS);
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "landed");
  EXPECT_TRUE(r.ok) << r.to_json();
}

TEST(FaultScoreTest, ACollisionFailsTheRun) {
  FaultScorer sc = airborne_run(attitude_cmd_t::MODE_NORMAL, autonomy_status_t::PHASE_HOLD, "HOLD");
  auto t = fault_truth(kFaultT0 + 11 * kS, 0, 1.0, true);
  t.collided = true;
  sc.add(t, kFaultT0 + 11 * kS);
  const auto r = sc.result();
  EXPECT_EQ(r.outcome, "collision");
  EXPECT_FALSE(r.ok);
}

}  // namespace
}  // namespace alight::tools

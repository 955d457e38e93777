#include "tools/monitor.hpp"

#include <gtest/gtest.h>

namespace alight::tools {
namespace {

constexpr int64_t kMonitorT0 = 1'790'000'000'000'000;

autonomy_status_t st(double t_s, int8_t phase, const char* name, int n = 0) {
  autonomy_status_t s{};
  s.utime = kMonitorT0 + static_cast<int64_t>(t_s * 1e6);
  s.mission = 1;
  s.phase = phase;
  s.phase_name = name;
  s.n_measurements = n;
  s.has_estimate = n > 0;
  s.estimate_W[0] = 1.02;
  s.estimate_W[1] = -0.5;
  s.estimate_W[2] = 0.23;
  return s;
}

sim_truth_t truth(bool tipped = false) {
  sim_truth_t t{};
  t.utime = kMonitorT0;
  t.has_platform = true;
  t.platform_center_W[0] = 1.0;
  t.platform_center_W[1] = -0.5;
  t.platform_center_W[2] = 0.219;
  t.tipped = tipped;
  return t;
}

TEST(MonitorTest, ReportsPhasesProgressAndTheLanding) {
  MissionMonitor m;
  m.add(truth());
  auto lines = m.add(st(0, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "[    0.0 s] DETECTION");
  lines = m.add(st(5, autonomy_status_t::PHASE_REFINEMENT, "REFINEMENT", 1));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("n = 1, estimate (1.020, -0.500, 0.230) m"), std::string::npos)
      << lines[0];
  EXPECT_NE(lines[0].find("lateral 2.0 cm, height +1.1 cm"), std::string::npos) << lines[0];
  // Progress lines are rate-limited: a new count within 2 s says nothing.
  EXPECT_TRUE(m.add(st(6, autonomy_status_t::PHASE_REFINEMENT, "REFINEMENT", 2)).empty());
  EXPECT_EQ(m.add(st(7.5, autonomy_status_t::PHASE_REFINEMENT, "REFINEMENT", 3)).size(), 1u);
  lines = m.add(st(20, autonomy_status_t::PHASE_LANDED, "LANDED", 12));
  ASSERT_EQ(lines.size(), 1u);  // motors off; the simulator's verdict follows
  EXPECT_EQ(m.end(), MissionMonitor::End::kNone);
  sim_truth_t at_rest = truth();
  at_rest.utime = kMonitorT0 + 20'400'000;
  at_rest.landed = true;
  lines = m.add(at_rest);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "mission complete: landed");
  EXPECT_EQ(m.end(), MissionMonitor::End::kSuccess);
  EXPECT_TRUE(m.add(st(21, autonomy_status_t::PHASE_LANDED, "LANDED", 12)).empty());
}

// The demo stopped the processes the moment autonomy said LANDED, before the simulator had
// seen the vehicle at rest, and the score said not_landed after a good landing.
TEST(MonitorTest, RegressionLandedWaitsForTheSimulatorsVerdict) {
  MissionMonitor m;
  m.add(truth());
  m.add(st(20, autonomy_status_t::PHASE_LANDED, "LANDED", 12));
  EXPECT_EQ(m.end(), MissionMonitor::End::kNone);
  m.add(st(22, autonomy_status_t::PHASE_LANDED, "LANDED", 12));
  EXPECT_EQ(m.end(), MissionMonitor::End::kNone);
  const auto lines = m.add(st(23.5, autonomy_status_t::PHASE_LANDED, "LANDED", 12));
  EXPECT_EQ(m.end(), MissionMonitor::End::kFailure);  // never at rest on the platform top
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "mission failed: motors off, but not at rest on the platform top");

  MissionMonitor real;  // no simulator: autonomy's touch-down detection stands
  real.add(st(20, autonomy_status_t::PHASE_LANDED, "LANDED", 12));
  EXPECT_EQ(real.end(), MissionMonitor::End::kSuccess);
}

TEST(MonitorTest, TipOffTheEdgeIsAFailure) {
  MissionMonitor m;
  m.add(st(0, autonomy_status_t::PHASE_APPROACH, "APPROACH", 10));
  const auto lines = m.add(truth(true));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(m.end(), MissionMonitor::End::kFailure);
}

TEST(MonitorTest, LeavingTheFlyingAreaIsAFailure) {
  MissionMonitor m;
  m.add(st(0, autonomy_status_t::PHASE_APPROACH, "APPROACH", 10));
  EXPECT_TRUE(m.add(truth()).empty());
  sim_truth_t out = truth();
  out.out_of_area = true;
  const auto lines = m.add(out);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "mission failed: the vehicle left the flying area");
  EXPECT_EQ(m.end(), MissionMonitor::End::kFailure);
}

TEST(MonitorTest, HoldAndTimeoutAreFailures) {
  MissionMonitor hold;
  auto s = st(0, autonomy_status_t::PHASE_HOLD, "HOLD");
  s.reason = "target lost, 3 retries used";
  hold.add(s);
  EXPECT_EQ(hold.end(), MissionMonitor::End::kFailure);
  EXPECT_EQ(hold.end_reason(), "holding: target lost, 3 retries used");

  MissionMonitor slow(MonitorParams{10.0, 2.0});
  slow.add(st(0, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
  EXPECT_EQ(slow.end(), MissionMonitor::End::kNone);
  slow.add(st(10.5, autonomy_status_t::PHASE_DETECTION, "DETECTION"));
  EXPECT_EQ(slow.end(), MissionMonitor::End::kFailure);
}

}  // namespace
}  // namespace alight::tools

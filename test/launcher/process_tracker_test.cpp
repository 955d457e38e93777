#include "launcher/process_tracker.hpp"

#include <gtest/gtest.h>

namespace alight::launcher {
namespace {

ProcessSpec spec(RestartPolicy policy, int max_restarts = -1) {
  ProcessSpec s;
  s.name = "p";
  s.command = {"p"};
  s.restart = policy;
  s.max_restarts = max_restarts;
  return s;
}

TEST(ProcessTrackerTest, CrashLoopBacksOffFrom10msDoublingTo1s) {
  ProcessTracker t(spec(RestartPolicy::kOnFailure), BackoffParams{});
  int64_t now = 0;
  std::vector<double> delays;
  for (int i = 0; i < 10; ++i) {
    t.started(100 + i, now);
    now += 1000;  // crashes 1 ms after starting
    t.exited(1, 0, now);
    ASSERT_EQ(t.state(), ProcState::kBackoff);
    delays.push_back(t.backoff_s());
    EXPECT_FALSE(t.restart_due(now + static_cast<int64_t>(t.backoff_s() * 1e6) - 1));
    now += static_cast<int64_t>(t.backoff_s() * 1e6);
    EXPECT_TRUE(t.restart_due(now));
  }
  const std::vector<double> expected{0.01, 0.02, 0.04, 0.08, 0.16, 0.32, 0.64, 1.0, 1.0, 1.0};
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(delays[i], expected[i], 1e-12) << i;
  EXPECT_EQ(t.restarts(), 9);  // the 10th restart has not happened yet
}

// Regression: a vehicle file naming a camera_info path that does not exist made vision exit
// with code 2 at start; the launcher restarted it every second for the whole 300 s demo.
TEST(ProcessTrackerTest, ConfigurationErrorIsNotRestarted) {
  for (const auto policy : {RestartPolicy::kOnFailure, RestartPolicy::kAlways}) {
    ProcessTracker t(spec(policy), BackoffParams{});
    t.started(1, 0);
    t.exited(kConfigErrorExitCode, 0, 1000);
    EXPECT_EQ(t.state(), ProcState::kFailed);
    EXPECT_FALSE(t.restart_due(10'000'000));
    EXPECT_NE(t.last_reason().find("configuration error"), std::string::npos) << t.last_reason();
  }
}

TEST(ProcessTrackerTest, HealthyRunResetsTheBackoff) {
  ProcessTracker t(spec(RestartPolicy::kOnFailure), BackoffParams{});
  t.started(1, 0);
  t.exited(1, 0, 1000);
  t.started(2, 20'000);
  t.exited(1, 0, 21'000);
  EXPECT_NEAR(t.backoff_s(), 0.02, 1e-12);
  t.started(3, 100'000);
  t.exited(1, 0, 100'000 + 11'000'000);  // ran 11 s > reset_after_s
  EXPECT_NEAR(t.backoff_s(), 0.01, 1e-12);
}

TEST(ProcessTrackerTest, PoliciesDecideWhatARestartNeeds) {
  ProcessTracker never(spec(RestartPolicy::kNever), {});
  never.started(1, 0);
  never.exited(2, 0, 10);
  EXPECT_EQ(never.state(), ProcState::kFailed);

  ProcessTracker on_failure(spec(RestartPolicy::kOnFailure), {});
  on_failure.started(1, 0);
  on_failure.exited(0, 0, 10);
  EXPECT_EQ(on_failure.state(), ProcState::kExited);
  ProcessTracker killed(spec(RestartPolicy::kOnFailure), {});
  killed.started(1, 0);
  killed.exited(0, 11, 10);  // SIGSEGV
  EXPECT_EQ(killed.state(), ProcState::kBackoff);
  EXPECT_EQ(killed.last_reason(), "killed by signal 11");

  ProcessTracker always(spec(RestartPolicy::kAlways), {});
  always.started(1, 0);
  always.exited(0, 0, 10);
  EXPECT_EQ(always.state(), ProcState::kBackoff);
}

TEST(ProcessTrackerTest, RestartLimitEndsInFailed) {
  ProcessTracker t(spec(RestartPolicy::kOnFailure, 2), {});
  int64_t now = 0;
  for (int i = 0; i < 3; ++i) {
    t.started(1 + i, now);
    t.exited(1, 0, now + 10);
    now += 2'000'000;
  }
  EXPECT_EQ(t.state(), ProcState::kFailed);
  EXPECT_EQ(t.restarts(), 2);
  EXPECT_NE(t.last_reason().find("restart limit 2"), std::string::npos);
}

TEST(ProcessTrackerTest, StoppingPreventsRestartsAndMarksStopped) {
  ProcessTracker t(spec(RestartPolicy::kAlways), {});
  t.started(1, 0);
  t.stopping();
  t.exited(0, 2, 10);  // SIGINT from the launcher
  EXPECT_EQ(t.state(), ProcState::kStopped);
  EXPECT_FALSE(t.restart_due(10'000'000));
  EXPECT_EQ(t.info().state, process_info_t::STATE_STOPPED);
}

TEST(ProcessTrackerTest, ShutdownOnExitEndsTheSession) {
  ProcessSpec s = spec(RestartPolicy::kAlways);
  s.shutdown_on_exit = true;
  ProcessTracker t(s, {});
  t.started(1, 0);
  t.exited(3, 0, 10);
  EXPECT_TRUE(t.ends_session());
  EXPECT_EQ(t.state(), ProcState::kFailed);
  EXPECT_EQ(t.info().exit_code, 3);
}

TEST(ProcessTrackerTest, ExecFailureCountsAsACrashWithItsReason) {
  ProcessTracker t(spec(RestartPolicy::kOnFailure), {});
  t.start_failed("program not found: nope", 0);
  EXPECT_EQ(t.state(), ProcState::kBackoff);
  EXPECT_EQ(t.last_reason(), "program not found: nope");
  EXPECT_EQ(t.info().exit_code, 127);
}

TEST(ProcessTrackerTest, RegressionRepeatedExecFailureBacksOffAndHitsTheLimit) {
  // A missing program used to be retried every 10 ms forever: failed starts did not count.
  ProcessTracker t(spec(RestartPolicy::kOnFailure, 3), {});
  int64_t now = 0;
  t.start_failed("program not found: nope", now);
  std::vector<double> delays{t.backoff_s()};
  while (t.state() == ProcState::kBackoff) {
    now += static_cast<int64_t>(t.backoff_s() * 1e6);
    ASSERT_TRUE(t.restart_due(now));
    t.start_failed("program not found: nope", now);
    delays.push_back(t.backoff_s());
  }
  EXPECT_EQ(t.state(), ProcState::kFailed);
  EXPECT_EQ(t.restarts(), 3);
  EXPECT_NEAR(delays[1], 0.02, 1e-12);
  EXPECT_NEAR(delays[2], 0.04, 1e-12);
}

// Regression (issue 14): `command_max_age_s: 1e-7` made autonomy abort (SIGABRT) at start, and
// the launcher restarted it forever, once a second, for the whole session. Like systemd's
// StartLimitBurst, quick failures in a window now end in FAILED, reported on PROCESS_STATUS.
TEST(ProcessTrackerRegression, AbortAtStartIsNotRestartedForever) {
  BackoffParams backoff;  // defaults: 12 quick failures within 30 s
  ProcessTracker t(spec(RestartPolicy::kOnFailure), backoff);
  int64_t now = 1'000'000;
  int failures = 0;
  for (int i = 0; i < 100 && t.state() != ProcState::kFailed; ++i) {
    t.started(100 + i, now);
    now += 5'000;         // aborts 5 ms after starting
    t.exited(0, 6, now);  // SIGABRT
    ++failures;
    if (t.state() == ProcState::kBackoff) {
      now += static_cast<int64_t>(t.backoff_s() * 1e6);
      ASSERT_TRUE(t.restart_due(now));
    }
  }
  EXPECT_EQ(t.state(), ProcState::kFailed);
  EXPECT_EQ(failures, backoff.start_limit_burst);
  EXPECT_NE(t.last_reason().find("start limit"), std::string::npos) << t.last_reason();
  EXPECT_FALSE(t.restart_due(now + 3'600'000'000LL));
  EXPECT_EQ(t.info().state, process_info_t::STATE_FAILED);
  EXPECT_EQ(t.info().signal, 6);
}

TEST(ProcessTrackerTest, FailuresSpreadBeyondTheStartLimitWindowKeepRestarting) {
  // A process that runs a while before each crash (longer than reset_after_s) is restarted
  // every time: only quick failures count against the start limit.
  ProcessTracker t(spec(RestartPolicy::kOnFailure), BackoffParams{});
  int64_t now = 0;
  for (int i = 0; i < 50; ++i) {
    t.started(100 + i, now);
    now += 11'000'000;  // ran 11 s > reset_after_s
    t.exited(1, 0, now);
    ASSERT_EQ(t.state(), ProcState::kBackoff) << i;
    now += static_cast<int64_t>(t.backoff_s() * 1e6);
  }
}

TEST(ProcessTrackerTest, StartLimitZeroDisablesIt) {
  BackoffParams backoff;
  backoff.start_limit_burst = 0;
  ProcessTracker t(spec(RestartPolicy::kOnFailure), backoff);
  int64_t now = 0;
  for (int i = 0; i < 100; ++i) {
    t.started(100 + i, now);
    now += 1000;
    t.exited(1, 0, now);
    ASSERT_EQ(t.state(), ProcState::kBackoff) << i;
    now += static_cast<int64_t>(t.backoff_s() * 1e6);
  }
}

}  // namespace
}  // namespace alight::launcher

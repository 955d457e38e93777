// alight-launch run for real: a crash loop restarted with backoff, a process with a grandchild,
// and one that ignores SIGINT; SIGTERM to the launcher must leave no process behind (checked by
// pid), and the session log must exist and replay.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <alight/process_status_t.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "common/build_paths.hpp"
#include "common/node.hpp"

namespace fs = std::filesystem;

namespace alight {
namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7712?ttl=0";

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Alive means: exists and is not a zombie waiting for a parent that is not us.
bool alive(int pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  if (!stat) return false;
  std::string line;
  std::getline(stat, line);
  const auto close_paren = line.rfind(')');
  return close_paren != std::string::npos && line.size() > close_paren + 2 &&
         line[close_paren + 2] != 'Z';
}

// Every pid whose process group is `pgid`.
std::vector<int> group_members(int pgid) {
  std::vector<int> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(e.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const auto close_paren = line.rfind(')');
    if (close_paren == std::string::npos) continue;
    std::istringstream rest(line.substr(close_paren + 2));
    char state;
    int ppid, pg;
    rest >> state >> ppid >> pg;
    if (pg == pgid && state != 'Z') out.push_back(std::stoi(name));
  }
  return out;
}

class LauncherIntegrationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("alight_launch_test_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (launcher_pid_ > 0) {
      kill(launcher_pid_, SIGKILL);
      waitpid(launcher_pid_, nullptr, 0);
    }
    fs::remove_all(dir_);
  }

  void write_launch_file(const std::string& text) { std::ofstream(dir_ / "test.yaml") << text; }

  void start_launcher() {
    launcher_pid_ = fork();
    ASSERT_GE(launcher_pid_, 0);
    if (launcher_pid_ == 0) {
      const std::string out = (dir_ / "stdout.txt").string();
      freopen(out.c_str(), "w", stdout);
      dup2(fileno(stdout), 2);
      for (const auto& [k, v] : env_) setenv(k.c_str(), v.c_str(), 1);
      const std::string bin = std::string(alight::build::binary_dir()) + "/bin/alight-launch";
      execl(bin.c_str(), bin.c_str(), (dir_ / "test.yaml").c_str(), "--log-root",
            (dir_ / "logs").c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
  }

  std::string output() const { return slurp(dir_ / "stdout.txt"); }

  // Waits for the launcher to exit; returns its exit status or -1 on timeout.
  int wait_exit(double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (waitpid(launcher_pid_, &status, WNOHANG) == launcher_pid_) {
        launcher_pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }

  int pid_of(const std::string& name) const {
    std::smatch m;
    const std::string out = output();
    if (std::regex_search(out, m, std::regex(name + ": running \\(pid ([0-9]+)\\)")))
      return std::stoi(m[1]);
    return -1;
  }

  fs::path session_dir() const {
    for (const auto& e : fs::directory_iterator(dir_ / "logs")) return e.path();
    return {};
  }

  fs::path dir_;
  pid_t launcher_pid_ = -1;
  std::vector<std::pair<std::string, std::string>> env_;  // extra environment of the launcher
};

TEST_F(LauncherIntegrationTest, RestartsWithBackoffStopsEverythingAndRecordsAReplayableLog) {
  write_launch_file(std::string(R"(
name: itest
lcm_url: )") + kUrl +
                    R"(
record: true
stop_timeout_s: 0.5
status_period_s: 0.1
processes:
  - name: crasher
    command: [sh, -c, "echo crashing; exit 3"]
  - name: family
    command: [sh, -c, "sleep 300 & sleep 300"]
  - name: stubborn
    command: [sh, -c, "trap '' INT; sleep 300"]
)");
  start_launcher();
  // Let the crash loop run through a few restarts (0.01 + 0.02 + 0.04 + 0.08 + 0.16 s ...).
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const int family = pid_of("family");
  const int stubborn = pid_of("stubborn");
  ASSERT_GT(family, 0) << output();
  ASSERT_GT(stubborn, 0) << output();
  std::vector<int> pids = group_members(family);
  const auto stubborn_group = group_members(stubborn);
  pids.insert(pids.end(), stubborn_group.begin(), stubborn_group.end());
  ASSERT_GE(pids.size(), 3u) << "family should have a grandchild";
  for (int p : pids) ASSERT_TRUE(alive(p));

  ASSERT_EQ(kill(launcher_pid_, SIGTERM), 0);
  EXPECT_EQ(wait_exit(10.0), 0) << output();
  for (int p : pids) EXPECT_FALSE(alive(p)) << "orphan pid " << p << "\n" << output();

  const std::string out = output();
  // Backoff as bot-procman: 10 ms doubling.
  EXPECT_NE(out.find("crasher: backoff, exited with code 3; restart 1 in 0.010 s"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("restart 2 in 0.020 s"), std::string::npos) << out;
  EXPECT_NE(out.find("restart 4 in 0.080 s"), std::string::npos) << out;
  EXPECT_NE(out.find("stubborn: did not stop within"), std::string::npos) << out;

  const fs::path session = session_dir();
  ASSERT_FALSE(session.empty());
  EXPECT_TRUE(std::regex_match(session.filename().string(), std::regex("[0-9]{8}-[0-9]{6}-itest")));
  for (const char* f :
       {"session.lcmlog", "launch.yaml", "launcher.log", "crasher.log", "family.log"})
    EXPECT_TRUE(fs::exists(session / f)) << f;
  EXPECT_NE(slurp(session / "crasher.log").find("crashing"), std::string::npos);

  // The log holds the launcher's PROCESS_STATUS, the last one with everything stopped.
  lcm::LogFile log((session / "session.lcmlog").string(), "r");
  ASSERT_TRUE(log.good());
  int statuses = 0;
  process_status_t last{};
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
    if (ev->channel != channels::kProcessStatus) continue;
    ASSERT_GT(last.decode(ev->data, 0, ev->datalen), 0);
    ++statuses;
  }
  EXPECT_GE(statuses, 5);
  ASSERT_EQ(last.n, 4);  // the recorder + 3
  for (const auto& p : last.processes) {
    if (p.name == "crasher") {
      EXPECT_GE(p.restarts, 4);
    } else if (p.name != "recorder") {
      EXPECT_EQ(p.state, process_info_t::STATE_STOPPED) << p.name;
    }
  }

  // And it replays: lcm-logplayer onto another port, a node counts the statuses.
  Node listener("udpm://239.255.76.67:7713?ttl=0", "listener");
  int replayed = 0;
  listener.on<process_status_t>(channels::kProcessStatus,
                                [&](const process_status_t&) { ++replayed; });
  const std::string cmd = "lcm-logplayer -s 4 -l 'udpm://239.255.76.67:7713?ttl=0' '" +
                          (session / "session.lcmlog").string() + "' >/dev/null 2>&1 &";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const int64_t end = wall_utime() + 8'000'000;
  while (replayed < statuses && wall_utime() < end) listener.spin_once(50);
  EXPECT_EQ(replayed, statuses);
}

// Regression (issue 14): the launcher timed its restart backoff on the system clock, so a step of
// it back by 60 s (NTP, an operator setting the time) froze every pending restart for 60 s: a
// crashed autonomy stayed down. Under libfaketime the launcher's wall clock is stepped back by
// 60 s while a process crash-loops; restarts must go on at the backoff rate.
TEST_F(LauncherIntegrationTest, RegressionWallClockStepDoesNotFreezeRestarts) {
  const std::string faketime = "/usr/lib/x86_64-linux-gnu/faketime/libfaketime.so.1";
  if (!fs::exists(faketime)) GTEST_SKIP() << "libfaketime not installed (apt-get install faketime)";
  const fs::path offset = dir_ / "faketime";
  std::ofstream(offset) << "+0\n";
  env_ = {{"LD_PRELOAD", faketime},
          {"FAKETIME_TIMESTAMP_FILE", offset.string()},
          {"FAKETIME_NO_CACHE", "1"},
          {"FAKETIME_DONT_FAKE_MONOTONIC", "1"}};  // only the wall clock steps
  write_launch_file(std::string("name: clockstep\nlcm_url: ") + kUrl + R"(
record: false
backoff: {initial_s: 0.2, max_s: 0.2, reset_after_s: 100, start_limit_burst: 0}
processes:
  - name: crasher
    command: [sh, -c, "sleep 0.05; exit 3"]
)");
  start_launcher();
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  std::ofstream(offset) << "-60\n";  // the wall clock jumps back a minute
  const size_t before = output().size();
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  const std::string after = output().substr(before);
  kill(launcher_pid_, SIGINT);
  EXPECT_EQ(wait_exit(5.0), 0);
  size_t restarts = 0;
  for (size_t pos = after.find("crasher: running"); pos != std::string::npos;
       pos = after.find("crasher: running", pos + 1))
    ++restarts;
  // One every ~0.25 s (0.05 s run + 0.2 s backoff) when not frozen: about 8 in 2 s.
  std::printf("restarts in the 2 s after a 60 s step back of the wall clock: %zu\n", restarts);
  EXPECT_GE(restarts, 3u) << after;
}

TEST_F(LauncherIntegrationTest, ShutdownOnExitEndsTheSessionWithItsExitCode) {
  // The exit code comes through the launcher's environment into the command line.
  setenv("ALIGHT_TEST_EXIT_CODE", "4", 1);
  write_launch_file(std::string("name: oneshot\nlcm_url: ") + kUrl + R"(
record: false
processes:
  - name: long
    command: [sleep, "300"]
  - name: job
    command: [sh, -c, "sleep 0.2; exit ${ALIGHT_TEST_EXIT_CODE}"]
    on_exit: shutdown
)");
  start_launcher();
  EXPECT_EQ(wait_exit(10.0), 4) << output();
  const int sleeper = pid_of("long");
  ASSERT_GT(sleeper, 0);
  EXPECT_FALSE(alive(sleeper));
}

TEST_F(LauncherIntegrationTest, MissingProgramIsReportedAndRetried) {
  write_launch_file(std::string("name: missing\nlcm_url: ") + kUrl + R"(
record: false
processes:
  - name: ghost
    command: [alight-no-such-program]
    max_restarts: 2
)");
  start_launcher();
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  kill(launcher_pid_, SIGINT);
  EXPECT_EQ(wait_exit(5.0), 0);
  const std::string out = output();
  EXPECT_NE(out.find("program not found: alight-no-such-program"), std::string::npos) << out;
  EXPECT_NE(out.find("restart limit 2 reached"), std::string::npos) << out;
}

TEST_F(LauncherIntegrationTest, BadLaunchFileExitsWithTheNamedError) {
  write_launch_file("name: bad\nprocesses:\n  - {name: a, command: [a], restart: sometimes}\n");
  start_launcher();
  EXPECT_EQ(wait_exit(5.0), 2);
  EXPECT_NE(output().find("processes[0].restart = sometimes"), std::string::npos) << output();
}

}  // namespace
}  // namespace alight

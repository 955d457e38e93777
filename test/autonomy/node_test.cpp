// alight-autonomy and alight-outer-loop as processes over LCM (private UDP multicast port):
// --auto-go takes off once a pose arrives, AUTONOMY_STATUS comes at >= 10 Hz of sensor time,
// the outer loop arms and commands thrust; unsigned, forged, stale and replayed OPERATOR_CMDs are
// rejected and counted (issue 8), and a correctly signed KILL stops both.

#include "common/node.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <Eigen/Core>
#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/state_estimate_t.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "common/build_paths.hpp"
#include "common/operator_auth.hpp"
#include "test/support/scratch_dir.hpp"

extern char** environ;

namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7947?ttl=0";

class Process {
 public:
  explicit Process(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid_ = -1;
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  bool ok() const { return pid_ > 0; }
  /// SIGKILL, as a crash: no handler runs, nothing is flushed.
  void crash() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
      pid_ = -1;
    }
  }
  /// Waits for the process to exit by itself; its exit code (128 + signal when killed).
  int wait_exit() {
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
};

struct Recorder {
  std::vector<alight::autonomy_status_t> status;
  std::vector<alight::position_setpoint_t> setpoints;
  std::vector<alight::attitude_cmd_t> cmds;
  void on_status(const lcm::ReceiveBuffer*, const std::string&,
                 const alight::autonomy_status_t* m) {
    status.push_back(*m);
  }
  void on_sp(const lcm::ReceiveBuffer*, const std::string&, const alight::position_setpoint_t* m) {
    setpoints.push_back(*m);
  }
  void on_cmd(const lcm::ReceiveBuffer*, const std::string&, const alight::attitude_cmd_t* m) {
    cmds.push_back(*m);
  }
};

TEST(AutonomyNodeTest, AutoGoTakesOffStatusAtTenHertzAndKillStopsEverything) {
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/";
  const std::string config =
      std::string(alight::build::source_dir()) + "/config/vehicles/starmac.yaml";
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  Recorder rec;
  lcm.subscribe(alight::channels::kAutonomyStatus, &Recorder::on_status, &rec);
  lcm.subscribe(alight::channels::kPositionSetpoint, &Recorder::on_sp, &rec);
  lcm.subscribe(alight::channels::kAttitudeCmd, &Recorder::on_cmd, &rec);
  // The key the ground station and the vehicle share.
  const auto key_path = std::filesystem::path(alight::test::scratch_path("operator.key"));
  const std::string key_hex(64, 'a');
  {
    std::ofstream f(key_path);
    f << key_hex << "\n";
  }
  std::filesystem::permissions(
      key_path, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  const alight::OperatorKey key = alight::parse_key(key_hex, "test key");
  const auto state_path = std::filesystem::path(alight::test::scratch_path("autonomy_1.state"));
  std::filesystem::remove(state_path);
  Process autonomy({bin + "alight-autonomy", "--config", config, "--lcm-url", kUrl, "--auto-go",
                    "landing", "--log-level", "warn", "--key-file", key_path.string(),
                    "--state-file", state_path.string()});
  // Its own state file: the per-URL default would carry latches from an earlier test run.
  const auto outer_state_path = std::filesystem::path(alight::test::scratch_path("outer_1.state"));
  std::filesystem::remove(outer_state_path);
  Process outer({bin + "alight-outer-loop", "--config", config, "--lcm-url", kUrl, "--log-level",
                 "warn", "--state-file", outer_state_path.string()});
  ASSERT_TRUE(autonomy.ok());
  ASSERT_TRUE(outer.ok());
  const int64_t t0 = 1'700'000'000'000'000;
  int64_t t = t0;
  const auto publish_sensors = [&](int n) {
    for (int i = 0; i < n; ++i) {
      t += 10'000;
      alight::pose_t pose{};
      pose.utime = t;
      pose.seq = (t - t0) / 10'000;
      pose.pos[2] = 0.12;
      pose.orientation[0] = 1.0;
      lcm.publish(alight::channels::kMocapPose, &pose);
      alight::imu_t imu{};
      imu.utime = t;
      imu.seq = pose.seq;
      imu.accel_B[2] = 9.81;
      lcm.publish(alight::channels::kImu, &imu);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      while (lcm.handleTimeout(0) > 0) {
      }
    }
  };
  // Until both nodes are up (a loaded machine may take a while to start them): sensor messages
  // at rest until the first status and attitude command arrive, then forget what came so far.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while ((rec.status.empty() || rec.cmds.empty()) && std::chrono::steady_clock::now() < deadline) {
    publish_sensors(5);
    lcm.handleTimeout(20);
  }
  ASSERT_FALSE(rec.status.empty()) << "alight-autonomy never answered";
  ASSERT_FALSE(rec.cmds.empty()) << "alight-outer-loop never answered";
  publish_sensors(200);  // 2 s of sensor time
  for (int i = 0; i < 20; ++i) lcm.handleTimeout(10);
  rec.status.erase(rec.status.begin(), rec.status.begin() + 1);

  ASSERT_FALSE(rec.status.empty());
  EXPECT_EQ(rec.status.back().phase, alight::autonomy_status_t::PHASE_TAKEOFF)
      << rec.status.back().phase_name << ": " << rec.status.back().reason;
  // >= 10 Hz in sensor time: no gap longer than 0.1 s between statuses.
  for (size_t i = 1; i < rec.status.size(); ++i) {
    EXPECT_LE(rec.status[i].utime - rec.status[i - 1].utime, 100'000) << i;
  }
  // (the newest ones may still be in flight on a loaded machine)
  EXPECT_GE(rec.status.back().utime - rec.status.front().utime, 1'500'000);
  ASSERT_FALSE(rec.setpoints.empty());
  EXPECT_EQ(rec.setpoints.back().motors, alight::position_setpoint_t::MOTORS_ON);
  EXPECT_GT(rec.setpoints.back().p_W[2], 0.12) << "climbing";
  ASSERT_FALSE(rec.cmds.empty());
  EXPECT_TRUE(rec.cmds.back().armed);
  EXPECT_GT(rec.cmds.back().thrust_N, 9.81) << "thrust to climb";

  // Four KILLs that must not be obeyed: unsigned (the vehicle file refuses those), signed with
  // another key, signed but 10 s old, and (after the genuine one) the genuine one replayed.
  const auto kill_cmd = [&](int64_t seq, int64_t utime) {
    alight::operator_cmd_t c{};
    c.utime = utime;
    c.seq = seq;
    c.sender = "test-station";
    // Signed for this vehicle and this run of autonomy, as announced on AUTONOMY_STATUS.
    c.vehicle_id = rec.status.back().vehicle_id;
    c.session = rec.status.back().cmd_session;
    c.command = alight::operator_cmd_t::CMD_KILL;
    c.auth = alight::operator_cmd_t::AUTH_NONE;
    return c;
  };
  ASSERT_NE(rec.status.back().cmd_session, 0) << "a verifier announces its session";
  alight::operator_cmd_t unsigned_kill = kill_cmd(1, alight::wall_utime());
  lcm.publish(alight::channels::kOperatorCmd, &unsigned_kill);
  alight::operator_cmd_t forged = kill_cmd(2, alight::wall_utime());
  alight::sign(forged, alight::parse_key(std::string(64, 'b'), "wrong key"));
  lcm.publish(alight::channels::kOperatorCmd, &forged);
  alight::operator_cmd_t stale = kill_cmd(3, alight::wall_utime() - 10'000'000);
  alight::sign(stale, key);
  lcm.publish(alight::channels::kOperatorCmd, &stale);
  const auto reject_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    publish_sensors(5);
    for (int i = 0; i < 5; ++i) lcm.handleTimeout(10);
  } while (rec.status.back().cmds_rejected < 3 &&
           std::chrono::steady_clock::now() < reject_deadline);
  EXPECT_EQ(rec.status.back().cmds_rejected, 3);
  EXPECT_EQ(rec.status.back().phase, alight::autonomy_status_t::PHASE_TAKEOFF)
      << "a rejected command was obeyed: " << rec.status.back().reason;
  EXPECT_TRUE(rec.cmds.back().armed);

  alight::operator_cmd_t kill = kill_cmd(4, alight::wall_utime());
  alight::sign(kill, key);
  lcm.publish(alight::channels::kOperatorCmd, &kill);
  const auto kill_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    publish_sensors(5);
    for (int i = 0; i < 5; ++i) lcm.handleTimeout(10);
  } while ((rec.status.back().phase != alight::autonomy_status_t::PHASE_KILLED ||
            rec.cmds.back().armed) &&
           std::chrono::steady_clock::now() < kill_deadline);
  EXPECT_EQ(rec.status.back().phase, alight::autonomy_status_t::PHASE_KILLED)
      << rec.status.back().reason;
  EXPECT_EQ(rec.status.back().failsafe, alight::autonomy_status_t::FAILSAFE_KILL);
  EXPECT_EQ(rec.setpoints.back().motors, alight::position_setpoint_t::MOTORS_KILL);
  EXPECT_FALSE(rec.cmds.back().armed);
  EXPECT_EQ(rec.cmds.back().thrust_N, 0.0);
  EXPECT_EQ(rec.status.back().last_cmd_seq, 4);

  lcm.publish(alight::channels::kOperatorCmd, &kill);  // replayed
  const auto replay_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    publish_sensors(5);
    for (int i = 0; i < 5; ++i) lcm.handleTimeout(10);
  } while (rec.status.back().cmds_rejected < 4 &&
           std::chrono::steady_clock::now() < replay_deadline);
  EXPECT_EQ(rec.status.back().cmds_rejected, 4);
  // Issue 14: the station learns which command was refused and why.
  using S = alight::autonomy_status_t;
  EXPECT_EQ(rec.status.back().last_rejected_seq, 4);
  EXPECT_EQ(rec.status.back().last_reject_reason, S::REJECT_REPLAYED);
  EXPECT_EQ(rec.status.back().cmds_rejected_by_reason[S::REJECT_UNSIGNED], 1);
  EXPECT_EQ(rec.status.back().cmds_rejected_by_reason[S::REJECT_BAD_SIGNATURE], 1);
  EXPECT_EQ(rec.status.back().cmds_rejected_by_reason[S::REJECT_STALE], 1);
  EXPECT_EQ(rec.status.back().cmds_rejected_by_reason[S::REJECT_REPLAYED], 1);
  EXPECT_GT(rec.status.back().wall_utime, 0);
  std::filesystem::remove(key_path);
  std::filesystem::remove(state_path);
}

// --- Issue 14: the input boundary and restarts, with the real process.

// Feeds MOCAP_POSE + IMU at 100 Hz of sensor time and records what alight-autonomy answers.
struct Bench {
  lcm::LCM lcm{kUrl};
  Recorder rec;
  int64_t t = 1'700'000'000'000'000;
  Eigen::Vector3d p{0, 0, 0.12};
  Eigen::Vector3d v{0, 0, 0};
  /// STATE_ESTIMATE with each pose (issue 17) when set: its health and reasons.
  std::optional<alight::state_estimate_t> estimate;
  Bench() {
    lcm.subscribe(alight::channels::kAutonomyStatus, &Recorder::on_status, &rec);
    lcm.subscribe(alight::channels::kPositionSetpoint, &Recorder::on_sp, &rec);
  }
  void publish_sensors(int n) {
    for (int i = 0; i < n; ++i) {
      t += 10'000;
      alight::pose_t pose{};
      pose.utime = t;
      for (int k = 0; k < 3; ++k) {
        pose.pos[k] = p[k];
        pose.vel[k] = v[k];
      }
      pose.orientation[0] = 1.0;
      lcm.publish(alight::channels::kMocapPose, &pose);
      alight::imu_t imu{};
      imu.utime = t;
      imu.accel_B[2] = 9.81;
      lcm.publish(alight::channels::kImu, &imu);
      if (estimate) {
        estimate->utime = t;
        ++estimate->seq;
        lcm.publish(alight::channels::kStateEstimate, &*estimate);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      while (lcm.handleTimeout(0) > 0) {
      }
    }
  }
  /// Poses that climb (or sink) to `z` at `speed` [m/s], as a flying vehicle's do: the node's
  /// pose innovation gate refuses a pose that jumps.
  void glide_to_z(double z, double speed) {
    const double dz = z - p.z();
    const int n = std::max(1, static_cast<int>(std::abs(dz) / speed / 0.01));
    v.z() = dz > 0 ? speed : -speed;
    const double z0 = p.z();
    for (int i = 1; i <= n; ++i) {
      p.z() = z0 + dz * i / n;
      publish_sensors(1);
    }
  }
  /// Sensors until the node has answered (a loaded machine may take a while to start it).
  bool wait_for_status(int seconds = 20) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    while (rec.status.empty() && std::chrono::steady_clock::now() < deadline) {
      publish_sensors(5);
      lcm.handleTimeout(20);
    }
    return !rec.status.empty();
  }
  template <class Pred>
  bool sensors_until(Pred pred, int seconds = 10) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    while (!pred() && std::chrono::steady_clock::now() < deadline) {
      publish_sensors(5);
      for (int i = 0; i < 5; ++i) lcm.handleTimeout(5);
    }
    return pred();
  }
};

std::string temp_file(const std::string& name) {
  const std::filesystem::path path = alight::test::scratch_path(name);
  std::filesystem::remove(path);
  return path.string();
}

// Bug: one IMU message stamped an hour ahead moved the autonomy's clock an hour on, so every
// pose after it was an hour old: FAILSAFE for good. Now the stamp guard refuses that message
// and the clock never moves.
TEST(AutonomyNodeRegression, ImuStampedAnHourAheadDoesNotHoldFailsafe) {
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/";
  const std::string config =
      std::string(alight::build::source_dir()) + "/config/vehicles/starmac.yaml";
  const std::string state = temp_file("future.state");
  Bench b;
  ASSERT_TRUE(b.lcm.good());
  Process autonomy({bin + "alight-autonomy", "--config", config, "--lcm-url", kUrl, "--auto-go",
                    "landing", "--log-level", "error", "--state-file", state});
  ASSERT_TRUE(autonomy.ok());
  ASSERT_TRUE(b.wait_for_status()) << "alight-autonomy never answered";
  ASSERT_TRUE(b.sensors_until(
      [&] { return b.rec.status.back().phase == alight::autonomy_status_t::PHASE_TAKEOFF; }));
  alight::imu_t future{};
  future.utime = b.t + 3600'000'000LL;
  future.accel_B[2] = 9.81;
  b.lcm.publish(alight::channels::kImu, &future);
  b.publish_sensors(200);  // 2 s of sensor time: twice pose_lost_s
  for (int i = 0; i < 20; ++i) b.lcm.handleTimeout(10);
  ASSERT_FALSE(b.rec.status.empty());
  const auto& last = b.rec.status.back();
  EXPECT_NE(last.phase, alight::autonomy_status_t::PHASE_FAILSAFE) << last.reason;
  EXPECT_EQ(last.phase, alight::autonomy_status_t::PHASE_TAKEOFF) << last.reason;
  EXPECT_LT(last.utime, b.t + 1'000'000) << "the clock never jumped ahead";
  EXPECT_EQ(b.rec.setpoints.back().motors, alight::position_setpoint_t::MOTORS_ON);
  std::filesystem::remove(state);
}

// Bug: a restarted autonomy's first setpoint was motors-off (the outer loop disarmed in the
// air), and with --auto-go it took off and started the mission again, even after a KILL. Now:
// killed (SIGKILL) in flight and started again with the same arguments, it holds where the
// vehicle is with the motors on; after a KILL it keeps the motors off, even on the ground.
TEST(AutonomyNodeRegression, RestartedInFlightHoldsAndKillSurvivesRestarts) {
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/";
  const std::string config =
      std::string(alight::build::source_dir()) + "/config/vehicles/starmac.yaml";
  const std::string state = temp_file("restart.state");
  const std::string key_path = temp_file("restart.key");
  const std::string key_hex(64, 'c');
  {
    std::ofstream f(key_path);
    f << key_hex << "\n";
  }
  std::filesystem::permissions(
      key_path, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  const alight::OperatorKey key = alight::parse_key(key_hex, "test key");
  const std::vector<std::string> args = {bin + "alight-autonomy",
                                         "--config",
                                         config,
                                         "--lcm-url",
                                         kUrl,
                                         "--auto-go",
                                         "landing",
                                         "--log-level",
                                         "error",
                                         "--key-file",
                                         key_path,
                                         "--state-file",
                                         state};
  Bench b;
  ASSERT_TRUE(b.lcm.good());
  const auto phase_is = [&](int8_t phase) {
    return !b.rec.status.empty() && b.rec.status.back().phase == phase;
  };
  {
    Process first(args);
    ASSERT_TRUE(first.ok());
    ASSERT_TRUE(b.wait_for_status()) << "alight-autonomy never answered";
    ASSERT_TRUE(
        b.sensors_until([&] { return phase_is(alight::autonomy_status_t::PHASE_TAKEOFF); }));
    b.glide_to_z(0.9, 0.4);  // climbing
    b.publish_sensors(150);
    ASSERT_TRUE(phase_is(alight::autonomy_status_t::PHASE_TAKEOFF));
    first.crash();
  }
  // What the killed process published last may still be on its way to this test: only what
  // answers sensor time after the crash comes from the restarted one.
  const auto restarted = [](const auto& msgs, int64_t after) {
    std::remove_cvref_t<decltype(msgs)> out;
    for (const auto& m : msgs)
      if (m.utime > after) out.push_back(m);
    return out;
  };
  int64_t crashed_at = b.t;
  b.rec = Recorder{};
  {
    Process second(args);
    ASSERT_TRUE(second.ok());
    ASSERT_TRUE(b.wait_for_status()) << "the restarted alight-autonomy never answered";
    b.publish_sensors(200);
    for (int i = 0; i < 20; ++i) b.lcm.handleTimeout(10);
    const auto setpoints = restarted(b.rec.setpoints, crashed_at);
    ASSERT_FALSE(setpoints.empty());
    for (const auto& sp : setpoints) {
      ASSERT_EQ(sp.motors, alight::position_setpoint_t::MOTORS_ON) << "motors off in the air";
      EXPECT_NEAR(sp.p_W[2], 0.9, 0.05) << "holds where it is";
    }
    for (const auto& st : restarted(b.rec.status, crashed_at)) {
      EXPECT_NE(st.phase, alight::autonomy_status_t::PHASE_TAKEOFF) << "took off again";
      EXPECT_NE(st.phase, alight::autonomy_status_t::PHASE_DETECTION) << "--auto-go ran";
    }
    EXPECT_EQ(b.rec.status.back().phase, alight::autonomy_status_t::PHASE_HOLD)
        << b.rec.status.back().reason;

    alight::operator_cmd_t kill{};
    kill.utime = alight::wall_utime();
    kill.seq = 1;
    kill.sender = "test-station";
    kill.command = alight::operator_cmd_t::CMD_KILL;
    // Signed for this vehicle and this run of autonomy, as announced on AUTONOMY_STATUS.
    kill.vehicle_id = b.rec.status.back().vehicle_id;
    kill.session = b.rec.status.back().cmd_session;
    alight::sign(kill, key);
    b.lcm.publish(alight::channels::kOperatorCmd, &kill);
    ASSERT_TRUE(b.sensors_until([&] { return phase_is(alight::autonomy_status_t::PHASE_KILLED); }));
    second.crash();
  }
  crashed_at = b.t;
  b.rec = Recorder{};
  b.p.z() = 0.12;  // it fell; on the ground, --auto-go must still not take off
  b.v.setZero();
  {
    Process third(args);
    ASSERT_TRUE(third.ok());
    ASSERT_TRUE(b.wait_for_status()) << "the restarted alight-autonomy never answered";
    b.publish_sensors(200);
    for (int i = 0; i < 20; ++i) b.lcm.handleTimeout(10);
    const auto setpoints = restarted(b.rec.setpoints, crashed_at);
    ASSERT_FALSE(setpoints.empty());
    for (const auto& sp : setpoints)
      EXPECT_EQ(sp.motors, alight::position_setpoint_t::MOTORS_KILL) << "KILL forgotten";
    for (const auto& st : restarted(b.rec.status, crashed_at))
      EXPECT_EQ(st.phase, alight::autonomy_status_t::PHASE_KILLED) << st.reason;
  }
  std::filesystem::remove(state);
  std::filesystem::remove(key_path);
}

// Issue 17: the node hears STATE_ESTIMATE. A LOST estimate (the estimator still aligning)
// holds --auto-go's TAKEOFF back, and --auto-go tries again once it is OK; a NaN estimate is
// refused at the boundary; LOST in flight is the estimate-lost failsafe on AUTONOMY_STATUS.
TEST(AutonomyNodeTest, StateEstimateHealthGatesTakeoffAndLostIsTheFailsafe) {
  using S = alight::autonomy_status_t;
  using E = alight::state_estimate_t;
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/";
  const std::string config =
      std::string(alight::build::source_dir()) + "/config/vehicles/starmac.yaml";
  const std::string state = temp_file("estimate.state");
  Bench b;
  ASSERT_TRUE(b.lcm.good());
  E lost{};
  lost.orientation[0] = 1.0;
  lost.health = E::HEALTH_LOST;
  lost.health_reasons = E::REASON_NOT_INITIALISED;
  b.estimate = lost;
  Process autonomy({bin + "alight-autonomy", "--config", config, "--lcm-url", kUrl, "--auto-go",
                    "landing", "--log-level", "error", "--state-file", state});
  ASSERT_TRUE(autonomy.ok());
  ASSERT_TRUE(b.wait_for_status()) << "alight-autonomy never answered";
  b.publish_sensors(150);  // 1.5 s of sensor time: TAKEOFF tried and refused
  for (int i = 0; i < 20; ++i) b.lcm.handleTimeout(10);
  ASSERT_FALSE(b.rec.status.empty());
  EXPECT_EQ(b.rec.status.back().phase, S::PHASE_IDLE) << b.rec.status.back().reason;
  EXPECT_NE(b.rec.status.back().reason.find("TAKEOFF refused: state estimate lost "
                                            "(not_initialised)"),
            std::string::npos)
      << b.rec.status.back().reason;
  b.estimate->health = E::HEALTH_OK;
  b.estimate->health_reasons = 0;
  ASSERT_TRUE(b.sensors_until([&] { return b.rec.status.back().phase == S::PHASE_TAKEOFF; }))
      << b.rec.status.back().reason;
  // Flying: a NaN estimate saying OK is refused, the last good one stands.
  b.glide_to_z(0.8, 0.4);
  b.estimate->pos[0] = std::numeric_limits<double>::quiet_NaN();
  b.publish_sensors(20);
  for (int i = 0; i < 10; ++i) b.lcm.handleTimeout(10);
  EXPECT_EQ(b.rec.status.back().phase, S::PHASE_TAKEOFF) << b.rec.status.back().reason;
  b.estimate->pos[0] = 0.0;
  // ... and counted on NODE_STATUS (once a second of wall time).
  struct NodeStatus {
    int64_t rejected = 0;
    void on(const lcm::ReceiveBuffer*, const std::string&, const alight::node_status_t* m) {
      if (m->node != "alight-autonomy") return;
      for (const auto& c : m->channels)
        if (c.channel == alight::channels::kStateEstimate) rejected = c.rejected_values;
    }
  } node_status;
  auto* sub = b.lcm.subscribe(alight::channels::kNodeStatus, &NodeStatus::on, &node_status);
  EXPECT_TRUE(b.sensors_until([&] { return node_status.rejected > 0; }))
      << "the NaN estimates were not counted";
  b.lcm.unsubscribe(sub);
  b.estimate->health = E::HEALTH_LOST;
  b.estimate->health_reasons = E::REASON_IMU_STOPPED;
  ASSERT_TRUE(b.sensors_until([&] { return b.rec.status.back().phase == S::PHASE_FAILSAFE; }))
      << b.rec.status.back().reason;
  EXPECT_EQ(b.rec.status.back().failsafe, S::FAILSAFE_ESTIMATE_LOST);
  EXPECT_NE(b.rec.status.back().reason.find("state estimate lost (imu_stopped)"), std::string::npos)
      << b.rec.status.back().reason;
  EXPECT_EQ(b.rec.setpoints.back().motors, alight::position_setpoint_t::MOTORS_ON)
      << "a controlled descent, motors on until touch-down";
  std::filesystem::remove(state);
}

// Bug: command_max_age_s: 1e-7 reached an assert (SIGABRT, exit 134) that the launcher
// restarted forever. Now exit 2 with file, key and value.
TEST(AutonomyNodeRegression, BadTimeoutIsExitTwoNotAnAbort) {
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/";
  std::ifstream in(std::string(alight::build::source_dir()) + "/config/vehicles/starmac.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string from = "command_max_age_s: 2.0";
  ASSERT_NE(yaml.find(from), std::string::npos);
  yaml.replace(yaml.find(from), from.size(), "command_max_age_s: 1e-7");
  const std::string config = temp_file("tiny.yaml");
  std::ofstream(config) << yaml;
  const std::string key_path = temp_file("tiny.key");
  std::ofstream(key_path) << std::string(64, 'd') << "\n";
  std::filesystem::permissions(
      key_path, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  Process autonomy({bin + "alight-autonomy", "--config", config, "--lcm-url", kUrl, "--key-file",
                    key_path, "--state-file", temp_file("tiny.state"), "--log-level", "error"});
  ASSERT_TRUE(autonomy.ok());
  EXPECT_EQ(autonomy.wait_exit(), 2);
  std::filesystem::remove(config);
  std::filesystem::remove(key_path);
}

}  // namespace

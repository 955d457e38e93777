// alight-autonomy and alight-outer-loop as processes over LCM (private UDP multicast port):
// --auto-go takes off once a pose arrives, AUTONOMY_STATUS comes at >= 10 Hz of sensor time,
// the outer loop arms and commands thrust; unsigned, forged, stale and replayed OPERATOR_CMDs are
// rejected and counted (issue 8), and a correctly signed KILL stops both.

#include "common/node.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "common/operator_auth.hpp"

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
  const std::string bin = std::string(ALIGHT_BINARY_DIR) + "/bin/";
  const std::string config = std::string(ALIGHT_SOURCE_DIR) + "/config/vehicles/starmac.yaml";
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  Recorder rec;
  lcm.subscribe("AUTONOMY_STATUS", &Recorder::on_status, &rec);
  lcm.subscribe("POSITION_SETPOINT", &Recorder::on_sp, &rec);
  lcm.subscribe("ATTITUDE_CMD", &Recorder::on_cmd, &rec);
  // The key the ground station and the vehicle share.
  const auto key_path = std::filesystem::temp_directory_path() / "alight_autonomy_node_test.key";
  const std::string key_hex(64, 'a');
  {
    std::ofstream f(key_path);
    f << key_hex << "\n";
  }
  std::filesystem::permissions(
      key_path, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  const alight::OperatorKey key = alight::parse_key(key_hex, "test key");
  Process autonomy({bin + "alight-autonomy", "--config", config, "--lcm-url", kUrl, "--auto-go",
                    "landing", "--log-level", "warn", "--key-file", key_path.string()});
  Process outer(
      {bin + "alight-outer-loop", "--config", config, "--lcm-url", kUrl, "--log-level", "warn"});
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
      lcm.publish("MOCAP_POSE", &pose);
      alight::imu_t imu{};
      imu.utime = t;
      imu.seq = pose.seq;
      imu.accel_B[2] = 9.81;
      lcm.publish("IMU", &imu);
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
  lcm.publish("OPERATOR_CMD", &unsigned_kill);
  alight::operator_cmd_t forged = kill_cmd(2, alight::wall_utime());
  alight::sign(forged, alight::parse_key(std::string(64, 'b'), "wrong key"));
  lcm.publish("OPERATOR_CMD", &forged);
  alight::operator_cmd_t stale = kill_cmd(3, alight::wall_utime() - 10'000'000);
  alight::sign(stale, key);
  lcm.publish("OPERATOR_CMD", &stale);
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
  lcm.publish("OPERATOR_CMD", &kill);
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
  EXPECT_EQ(rec.setpoints.back().motors, alight::position_setpoint_t::MOTORS_OFF);
  EXPECT_FALSE(rec.cmds.back().armed);
  EXPECT_EQ(rec.cmds.back().thrust_N, 0.0);
  EXPECT_EQ(rec.status.back().last_cmd_seq, 4);

  lcm.publish("OPERATOR_CMD", &kill);  // replayed
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
}

}  // namespace

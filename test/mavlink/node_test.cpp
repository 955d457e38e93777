// alight-mavlink as a process (issue 16): bad configuration and malformed --link addresses exit
// with code 2 and say what is wrong where; over a pseudo-terminal standing in for the autopilot's
// serial port it sends HEARTBEATs (read back with alight's own parser), publishes
// AUTOPILOT_STATUS with the link down until the autopilot answers and up once it does, and
// reopens the port after the device went away. LCM on a private port (7917). Every wait is for an
// event, with a generous deadline; no duration is asserted.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <alight/autopilot_status_t.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "common/channels.hpp"
#include "mavlink/autopilot_modes.hpp"
#include "mavlink/frame.hpp"
#include "mavlink/parser.hpp"

extern char** environ;

namespace alight::mavlink {
namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7917?ttl=0";
constexpr auto kGenerous = std::chrono::seconds(30);

std::string bin() { return std::string(alight::build::binary_dir()) + "/bin/alight-mavlink"; }
std::string source(const std::string& rel) {
  return std::string(alight::build::source_dir()) + "/" + rel;
}
std::filesystem::path tmp(const std::string& name) {
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test_tmp";
  std::filesystem::create_directories(dir);
  return dir / name;
}
std::string test_name() { return ::testing::UnitTest::GetInstance()->current_test_info()->name(); }
std::string slurp(const std::filesystem::path& p) {
  std::stringstream ss;
  ss << std::ifstream(p).rdbuf();
  return ss.str();
}

/// Runs the node to completion; its exit code, its output in *output.
int run(const std::string& args, std::string* output) {
  const auto out = tmp("mavlink_node_" + test_name() + ".txt");
  const int status = std::system((bin() + " " + args + " > " + out.string() + " 2>&1").c_str());
  *output = slurp(out);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// The node running in the background, its output in a file; SIGTERM and reaped at the end.
class Process {
 public:
  Process(std::vector<std::string> args, const std::filesystem::path& output) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    if (posix_spawn(&pid_, argv[0], &fa, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  bool ok() const { return pid_ > 0; }
  /// Waits for it to exit by itself (up to kGenerous): its exit code, -1 when it did not.
  int wait_exit() {
    const auto deadline = std::chrono::steady_clock::now() + kGenerous;
    while (running() && std::chrono::steady_clock::now() < deadline) usleep(10'000);
    return exit_code_;
  }
  /// Whether it is still running (it must not exit by itself).
  bool running() const {
    int status = 0;
    if (pid_ <= 0) return false;
    if (waitpid(pid_, &status, WNOHANG) == 0) return true;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    pid_ = -1;  // reaped
    return false;
  }

 private:
  mutable pid_t pid_ = -1;
  mutable int exit_code_ = -1;
};

/// A pseudo-terminal: the test is the autopilot on the master side.
struct Pty {
  int master = -1;
  std::string slave;
  Pty() {
    master = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) return;
    if (const char* n = ptsname(master)) slave = n;
    fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
  }
  ~Pty() { close(); }
  void close() {
    if (master >= 0) ::close(master);
    master = -1;
  }
  bool ok() const { return master >= 0 && !slave.empty(); }
};

/// Points `link` at the pty's slave, as udev's /dev/serial/by-id names point at the current
/// ttyACMn: the node is configured with the stable name.
void point(const std::filesystem::path& link, const Pty& pty) {
  std::filesystem::remove(link);
  std::filesystem::create_symlink(pty.slave, link);
}

struct StatusRecorder {
  std::vector<autopilot_status_t> status;
  void on(const lcm::ReceiveBuffer*, const std::string&, const autopilot_status_t* m) {
    status.push_back(*m);
  }
};

/// The autopilot's side: parses what the node sends, answers with heartbeats.
struct FakeAutopilot {
  Parser parser;
  std::vector<std::pair<Frame, Heartbeat>> heartbeats;
  Sender sender{1, 1};  // MAV_COMP_ID_AUTOPILOT1 of system 1
  void drain(int master) {
    uint8_t buf[1024];
    for (;;) {
      const ssize_t n = ::read(master, buf, sizeof buf);
      if (n <= 0) break;
      parser.push(std::span<const uint8_t>(buf, static_cast<size_t>(n)));
    }
    Frame f;
    while (parser.next(f))
      if (const auto hb = decode<Heartbeat>(f)) heartbeats.emplace_back(f, *hb);
  }
  void send_heartbeat(int master) {
    Heartbeat hb;
    hb.type = mav_type::kQuadrotor;
    hb.autopilot = mav_autopilot::kPx4;
    hb.custom_mode = px4_mode::custom_mode(px4_mode::kPosctl);
    hb.system_status = mav_state::kStandby;
    const FrameBytes b = sender.pack(hb, 0);
    (void)!::write(master, b.data.data(), b.size);
  }
};

/// Spins LCM and the pty until `done` holds or kGenerous has passed; false on the deadline.
bool wait_for(lcm::LCM& lcm, const std::function<void()>& each, const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + kGenerous;
  while (std::chrono::steady_clock::now() < deadline) {
    lcm.handleTimeout(20);
    each();
    if (done()) return true;
  }
  return false;
}

TEST(MavlinkNodeTest, ABadConfigKeyOrValueExitsWithCode2NamingFileKeyAndValue) {
  struct Case {
    std::string yaml, key, value;
  };
  const std::vector<Case> cases = {
      {"mavlink:\n  autopilot: px4\n  stream_rate: 50\n", "mavlink.stream_rate", "50"},
      {"mavlink:\n  stream_rate_hz: 500\n", "mavlink.stream_rate_hz", "500"},
      {"mavlink:\n  autopilot: inav\n", "mavlink.autopilot", "inav"},
      {"mavlink:\n  link: serial:/dev/ttyACM0:9600\n", "mavlink.link", "serial:/dev/ttyACM0:9600"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].yaml);
    const auto file = tmp("mavlink_bad_" + std::to_string(i) + ".yaml");
    std::ofstream(file) << cases[i].yaml;
    std::string out;
    EXPECT_EQ(run("--config " + file.string() + " --vehicle " +
                      source("config/vehicles/pelican.yaml") + " --lcm-url '" + kUrl + "'",
                  &out),
              2);
    EXPECT_NE(out.find(file.string()), std::string::npos) << out;
    EXPECT_NE(out.find(cases[i].key), std::string::npos) << out;
    EXPECT_NE(out.find(cases[i].value), std::string::npos) << out;
  }
}

TEST(MavlinkNodeTest, AMalformedLinkAddressExitsWithCode2NamingIt) {
  for (const std::string link :
       {"serial:/dev/ttyACM0:9600", "serial:/dev/ttyACM0", "tcp:127.0.0.1:14540",
        "udp:127.0.0.1:99999", "udp-listen:0.0.0.0:14540:14550", "14540"}) {
    SCOPED_TRACE(link);
    std::string out;
    EXPECT_EQ(run("--config " + source("config/autopilot/px4.yaml") + " --vehicle " +
                      source("config/vehicles/pelican.yaml") + " --lcm-url '" + kUrl +
                      "' --link '" + link + "'",
                  &out),
              2);
    EXPECT_NE(out.find("--link"), std::string::npos) << out;
    EXPECT_NE(out.find(link), std::string::npos) << out;
  }
}

TEST(MavlinkNodeTest, OverAPtyItSendsHeartbeatsReportsTheLinkAndReopensALostDevice) {
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  StatusRecorder rec;
  lcm.subscribe(channels::kAutopilotStatus, &StatusRecorder::on, &rec);
  auto pty = std::make_unique<Pty>();
  ASSERT_TRUE(pty->ok());
  const auto link = tmp("mavlink_node_test_tty");
  point(link, *pty);
  const auto output = tmp("mavlink_node_" + test_name() + ".txt");
  Process node({bin(), "--config", source("config/autopilot/px4.yaml"), "--vehicle",
                source("config/vehicles/pelican.yaml"), "--link",
                "serial:" + link.string() + ":921600", "--lcm-url", kUrl, "--log-level", "info"},
               output);
  ASSERT_TRUE(node.ok());
  FakeAutopilot ap;
  const auto drain = [&] { ap.drain(pty->master); };

  // 1. Nobody answers: heartbeats go out, the status says the link is down.
  const bool silent_seen =
      wait_for(lcm, drain, [&] { return ap.heartbeats.size() >= 2 && !rec.status.empty(); });
  ASSERT_TRUE(silent_seen) << "heartbeats " << ap.heartbeats.size() << ", status "
                           << rec.status.size() << "\n"
                           << slurp(output);
  for (const auto& [f, hb] : ap.heartbeats) {
    EXPECT_EQ(f.sysid, 1);     // own_sysid
    EXPECT_EQ(f.compid, 191);  // MAV_COMP_ID_ONBOARD_COMPUTER
    EXPECT_EQ(hb.type, mav_type::kOnboardController);
    EXPECT_EQ(hb.autopilot, mav_autopilot::kInvalid);
  }
  EXPECT_EQ(ap.parser.stats().crc_errors, 0u);
  const autopilot_status_t down = rec.status.back();
  EXPECT_FALSE(down.link_up);
  EXPECT_EQ(down.heartbeat_age_s, -1);
  EXPECT_EQ(down.engage, "NO_LINK");
  EXPECT_EQ(down.sysid, 0);
  EXPECT_EQ(down.autopilot, autopilot_status_t::AUTOPILOT_PX4);
  EXPECT_EQ(down.control, autopilot_status_t::CONTROL_ATTITUDE);
  EXPECT_GE(down.frames_sent, 1);

  // 2. The autopilot answers (a heartbeat per pass): the link comes up with its mode.
  const bool up_seen = wait_for(
      lcm,
      [&] {
        drain();
        ap.send_heartbeat(pty->master);
      },
      [&] { return !rec.status.empty() && rec.status.back().link_up; });
  ASSERT_TRUE(up_seen) << slurp(output);
  EXPECT_EQ(rec.status.back().sysid, 1);
  EXPECT_EQ(rec.status.back().mode, "POSCTL");
  EXPECT_GE(rec.status.back().frames_received, 1);
  EXPECT_EQ(rec.status.back().reopens, 0);

  // 3. The device goes away (master closed: the tty hangs up) and comes back under the same
  // name: the node reopens it and heartbeats flow on the new one.
  pty->close();
  pty = std::make_unique<Pty>();
  ASSERT_TRUE(pty->ok());
  point(link, *pty);
  FakeAutopilot again;
  const bool reopened = wait_for(
      lcm, [&] { again.drain(pty->master); },
      [&] { return !again.heartbeats.empty() && rec.status.back().reopens >= 1; });
  EXPECT_TRUE(reopened) << "heartbeats on the new device " << again.heartbeats.size()
                        << ", reopens " << rec.status.back().reopens << "\n"
                        << slurp(output);
  EXPECT_TRUE(node.running()) << slurp(output);
  EXPECT_NE(slurp(output).find("reopening"), std::string::npos) << slurp(output);
  std::filesystem::remove(link);
}

TEST(MavlinkNodeTest, SetupSigningGivesTheAutopilotTheKeyAndEndsOnceItSigns) {
  const std::string hex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
  const auto key_file = tmp("mavlink_node_signing.key");
  std::ofstream(key_file) << hex << "\n";
  auto pty = std::make_unique<Pty>();
  ASSERT_TRUE(pty->ok());
  const auto link = tmp("mavlink_node_test_tty_signing");
  point(link, *pty);
  const auto config = tmp("mavlink_node_signing.yaml");
  std::ofstream(config) << "mavlink:\n  autopilot: px4\n  link: serial:" << link.string()
                        << ":921600\n  signing_key_file: " << key_file.string() << "\n";
  const auto output = tmp("mavlink_node_" + test_name() + ".txt");
  Process node({bin(), "--config", config.string(), "--setup-signing", "--lcm-url", kUrl}, output);
  ASSERT_TRUE(node.ok());
  const SigningKey key = *signing_key_from_hex(hex);
  Parser parser;
  std::optional<SetupSigning> setup;
  Sender plain{1, 1};
  Sender signer{1, 1, SigningConfig{key, 0}};
  lcm::LCM lcm(kUrl);
  // The autopilot's unsigned heartbeats until SETUP_SIGNING comes, then signed ones.
  const bool done = wait_for(
      lcm,
      [&] {
        uint8_t buf[1024];
        for (;;) {
          const ssize_t n = ::read(pty->master, buf, sizeof buf);
          if (n <= 0) break;
          parser.push(std::span<const uint8_t>(buf, static_cast<size_t>(n)));
        }
        Frame f;
        while (parser.next(f))
          if (const auto m = decode<SetupSigning>(f)) setup = m;
        Heartbeat hb;
        hb.type = mav_type::kQuadrotor;
        hb.autopilot = mav_autopilot::kPx4;
        const FrameBytes b = setup ? signer.pack(hb, 1'800'000'000'000'000) : plain.pack(hb, 0);
        (void)!::write(pty->master, b.data.data(), b.size);
      },
      [&] { return !node.running(); });
  ASSERT_TRUE(done) << slurp(output);
  ASSERT_TRUE(setup) << slurp(output);
  EXPECT_EQ(setup->secret_key, key);
  EXPECT_EQ(setup->target_system, 1);
  EXPECT_GT(setup->initial_timestamp, 0u);
  EXPECT_EQ(node.wait_exit(), 0) << slurp(output);
  std::filesystem::remove(link);
}

}  // namespace
}  // namespace alight::mavlink

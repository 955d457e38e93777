// alight-mocap as a process against the VRPN test server (written from the protocol description,
// tools/vrpn_test_server.hpp) over TCP on 127.0.0.1, publishing on a private LCM port (7935):
// poses at 100 Hz and 360 Hz arrive as MOCAP_POSE transformed from a y-up millimetre room, field
// by field; garbage, a truncated message, refused messages and a server restart are survived and
// counted on NODE_STATUS; a bad file is exit 2 and an unreachable server with a start timeout
// exit 3. Nothing here depends on how fast the machine is: every wait is for an event, with a
// generous deadline.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <alight/node_status_t.hpp>
#include <alight/pose_t.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "common/build_paths.hpp"
#include "common/channels.hpp"
#include "test/support/scratch_dir.hpp"
#include "tools/vrpn_test_server.hpp"

extern char** environ;

namespace {

using alight::tools::ServedPose;
using alight::tools::VrpnTestServer;

constexpr const char* kUrl = "udpm://239.255.76.67:7935?ttl=0";

class Process {
 public:
  Process(std::vector<std::string> args, const std::string& output = "") {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!output.empty()) {
      posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                       0644);
      posix_spawn_file_actions_adddup2(&actions, 1, 2);
    }
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  bool ok() const { return pid_ > 0; }
  bool running() {
    int status = 0;
    return pid_ > 0 && waitpid(pid_, &status, WNOHANG) == 0;
  }
  int wait_exit() {
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
};

std::string read_file(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string temp_path(const std::string& name) { return alight::test::scratch_path(name); }

// A y-up Motive-like room in millimetres, server stamps used as they are. Timeouts and bounds
// are wide: a stalled test machine must not turn into a refused stamp or a reconnection.
std::string write_config(const std::string& name, int port, const std::string& extra = "") {
  const std::string path = temp_path(name + ".yaml");
  std::ofstream f(path);
  f << "mocap:\n"
       "  server: {tracker: \"Pelican@127.0.0.1:"
    << port
    << "\", silence_timeout_s: 60.0, retry_initial_s: 0.05, retry_max_s: 0.2}\n"
       "  room: {units: mm, up_axis: y, yaw_deg: 0.0, p_W_R_m: [1.0, 2.0, 0.0]}\n"
       "  body: {rpy_M_B_deg: [-90.0, 0.0, 0.0]}\n"
       "  stamp: {source: server, max_clock_offset_s: 60.0}\n"
       "  velocity: {max_gap_s: 1.0}\n"
    << extra;
  return path;
}

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The served motion: constant velocity and yaw rate, so every finite difference is exact.
// Room (y up, mm): x = 100 + 500 t, y (height) = 1500 + 100 t, z = -800 - 250 t, turning about
// the room's up at 0.4 rad/s. In world (m): (1 + x / 1000, 2 - z / 1000, y / 1000).
constexpr double kYawRate = 0.4;
ServedPose served(int64_t stamp_us, int64_t t0_us, const std::string& object = "Pelican") {
  const double t = (stamp_us - t0_us) * 1e-6;
  ServedPose p;
  p.object = object;
  p.stamp_us = stamp_us;
  p.pos[0] = 100 + 500 * t;
  p.pos[1] = 1500 + 100 * t;
  p.pos[2] = -800 - 250 * t;
  const double yaw = 0.3 + kYawRate * t;
  p.quat_xyzw[1] = std::sin(yaw / 2);  // about room y
  p.quat_xyzw[3] = std::cos(yaw / 2);
  return p;
}

struct Expected {
  double pos[3], vel[3], q[4], omega[3];
};
Expected expected(const ServedPose& s, int64_t t0_us) {
  Expected e{};
  e.pos[0] = 1.0 + s.pos[0] / 1000, e.pos[1] = 2.0 - s.pos[2] / 1000, e.pos[2] = s.pos[1] / 1000;
  e.vel[0] = 0.5, e.vel[1] = 0.25, e.vel[2] = 0.1;
  const double yaw = 0.3 + kYawRate * (s.stamp_us - t0_us) * 1e-6;
  e.q[0] = std::cos(yaw / 2), e.q[3] = std::sin(yaw / 2);  // about world z
  e.omega[2] = kYawRate;
  return e;
}

struct Listener {
  // A deep socket buffer: a few hundred small datagrams overflow the default one.
  lcm::LCM lcm{std::string(kUrl) + "&recv_buf_size=4194304"};
  std::vector<alight::pose_t> poses;
  std::vector<alight::node_status_t> status;
  Listener() {
    lcm.subscribe(alight::channels::kMocapPose, &Listener::on_pose, this);
    lcm.subscribe(alight::channels::kNodeStatus, &Listener::on_status, this);
  }
  void on_pose(const lcm::ReceiveBuffer*, const std::string&, const alight::pose_t* m) {
    poses.push_back(*m);
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const alight::node_status_t* m) {
    if (m->node == "alight-mocap") status.push_back(*m);
  }
  /// Handles messages until `done` or the deadline; true when done.
  bool until(const std::function<bool()>& done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!done()) {
      if (std::chrono::steady_clock::now() > end) return false;
      lcm.handleTimeout(20);
    }
    return true;
  }
  std::optional<alight::channel_stats_t> input(const std::string& name) const {
    if (status.empty()) return std::nullopt;
    for (const auto& c : status.back().channels)
      if (c.channel == name) return c;
    return std::nullopt;
  }
};

// Streams `n` poses of Pelican (and one of Other every tenth) at `rate_hz` from a thread, while
// the caller's thread keeps handling LCM (a listener that does not would lose messages in its
// socket buffer).
class Streamer {
 public:
  Streamer(VrpnTestServer& server, int n, double rate_hz, int64_t t0_us,
           std::vector<ServedPose>& sent)
      : thread_([this, &server, n, rate_hz, t0_us, &sent] {
          auto next = std::chrono::steady_clock::now();
          for (int i = 0; i < n; ++i) {
            const auto p = served(now_us(), t0_us);
            if (!server.send_pose(p)) break;
            sent.push_back(p);
            if (i % 10 == 0) server.send_pose(served(p.stamp_us, t0_us, "Other"));
            next += std::chrono::microseconds(static_cast<int64_t>(1e6 / rate_hz));
            std::this_thread::sleep_until(next);
          }
          done_ = true;
        }) {}
  ~Streamer() { thread_.join(); }
  bool done() const { return done_; }

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

void stream(Listener& rx, VrpnTestServer& server, int n, double rate_hz, int64_t t0_us,
            std::vector<ServedPose>& sent) {
  Streamer s(server, n, rate_hz, t0_us, sent);
  rx.until([&] { return s.done(); }, 120.0);
}

const std::string kBin = std::string(alight::build::binary_dir()) + "/bin/alight-mocap";

TEST(MocapNodeTest, PosesAt100And360HzArriveTransformedFieldByField) {
  VrpnTestServer server;
  ASSERT_TRUE(server.listen());
  const std::string config = write_config("stream", server.port());
  Listener rx;
  ASSERT_TRUE(rx.lcm.good());
  Process node({kBin, "--config", config, "--lcm-url", kUrl, "--log-level", "warn"});
  ASSERT_TRUE(node.ok());
  ASSERT_TRUE(server.accept(20.0, {"Other", "Pelican"}));
  // The client greets as VRPN clients do: our major version, then what it listens to.
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(server.client_cookie().data()), 14),
            "vrpn: ver. 07.");
  const auto names = server.client_descriptions(2.0);
  EXPECT_NE(std::find(names.begin(), names.end(), "Pelican"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "vrpn_Tracker Pos_Quat"), names.end());

  const int64_t t0 = now_us();
  std::vector<ServedPose> sent;
  stream(rx, server, 100, 100.0, t0, sent);  // 1 s at 100 Hz
  stream(rx, server, 360, 360.0, t0, sent);  // then 1 s at 360 Hz
  ASSERT_EQ(sent.size(), 460u);
  // Every pose but those held back for want of a velocity (the first; any after a stall of the
  // test machine longer than max_gap_s) arrives, up to the last one sent.
  const std::string input = "vrpn:Pelican@127.0.0.1:" + std::to_string(server.port());
  ASSERT_TRUE(rx.until(
      [&] {
        const auto c = rx.input(input);
        return !rx.poses.empty() && rx.poses.back().utime == sent.back().stamp_us && c &&
               c->received + c->skipped == static_cast<int64_t>(sent.size());
      },
      30.0))
      << rx.poses.size() << " of " << sent.size();
  const auto c = rx.input(input);
  EXPECT_EQ(c->received, static_cast<int64_t>(rx.poses.size()));
  EXPECT_GE(c->skipped, 1);
  EXPECT_LE(c->skipped, 5);
  EXPECT_EQ(c->decode_errors + c->rejected_values + c->rejected_stamps, 0);
  std::map<int64_t, const ServedPose*> by_stamp;
  for (const auto& p : sent) by_stamp[p.stamp_us] = &p;
  int64_t last_seq = -1;
  for (const auto& m : rx.poses) {
    const auto it = by_stamp.find(m.utime);
    ASSERT_NE(it, by_stamp.end()) << "utime " << m.utime << " was never sent";
    const Expected e = expected(*it->second, t0);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(m.pos[i], e.pos[i], 1e-9) << i;
      EXPECT_NEAR(m.vel[i], e.vel[i], 1e-6) << i;
      EXPECT_NEAR(m.angular_velocity_B[i], e.omega[i], 1e-6) << i;
    }
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.orientation[i], e.q[i], 1e-9) << i;
    EXPECT_EQ(m.status, alight::pose_t::STATUS_OK);
    EXPECT_EQ(m.seq, last_seq + 1);
    last_seq = m.seq;
  }
  EXPECT_TRUE(node.running());
}

TEST(MocapNodeTest, SurvivesGarbageTruncationRefusalsAndARestartAndCountsThem) {
  VrpnTestServer server;
  ASSERT_TRUE(server.listen());
  const int port = server.port();
  const std::string config = write_config("faults", port);
  Listener rx;
  Process node({kBin, "--config", config, "--lcm-url", kUrl, "--log-level", "error"});
  ASSERT_TRUE(node.ok());
  const int64_t t0 = now_us();
  std::vector<ServedPose> sent;
  // Waits until the last pose sent has arrived (poses held back for want of a velocity never do).
  const auto stream_and_wait = [&](const char* phase) {
    stream(rx, server, 20, 200.0, t0, sent);
    ASSERT_TRUE(rx.until(
        [&] { return !rx.poses.empty() && rx.poses.back().utime == sent.back().stamp_us; }, 30.0))
        << phase << ": " << rx.poses.size() << " poses";
  };

  ASSERT_TRUE(server.accept(20.0, {"Pelican", "Other"}));
  stream_and_wait("first connection");

  // Garbage: a length no message can have. The node drops the stream and connects again.
  ASSERT_TRUE(server.send_raw(std::vector<uint8_t>(64, 0xff)));
  ASSERT_TRUE(server.accept(20.0, {"Pelican", "Other"}));
  stream_and_wait("after garbage");

  // A message cut short by the server going away.
  const auto cut =
      VrpnTestServer::frame(server.type_id("vrpn_Tracker Pos_Quat"), server.sender_id("Pelican"),
                            now_us(), VrpnTestServer::pose_payload(served(now_us(), t0)));
  ASSERT_TRUE(server.send_raw(std::vector<uint8_t>(cut.begin(), cut.begin() + 40)));
  server.drop_client();
  ASSERT_TRUE(server.accept(20.0, {"Pelican", "Other"}));
  stream_and_wait("after a truncated message");

  // Refused but framed: an undescribed type, a Pos_Quat of the wrong size. Same connection.
  ASSERT_TRUE(server.send_raw(VrpnTestServer::frame(900, server.sender_id("Pelican"), now_us(),
                                                    std::vector<uint8_t>(64, 1))));
  ASSERT_TRUE(server.send_raw(VrpnTestServer::frame(server.type_id("vrpn_Tracker Pos_Quat"),
                                                    server.sender_id("Pelican"), now_us(),
                                                    std::vector<uint8_t>(24, 0))));
  stream_and_wait("after refused messages");

  // The server stops and starts again on the same port.
  server.close();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_TRUE(server.listen());
  ASSERT_EQ(server.port(), port);
  ASSERT_TRUE(server.accept(20.0, {"Pelican", "Other"}));
  stream_and_wait("after a restart");

  // NODE_STATUS counts all of it on the stream's input: 1 framing error, 1 truncation, 2 refused
  // messages; every pose sent was published or held back (the first of each of the four
  // connections at least).
  const std::string input = "vrpn:Pelican@127.0.0.1:" + std::to_string(port);
  ASSERT_TRUE(rx.until(
      [&] {
        const auto c = rx.input(input);
        return c && c->received + c->skipped == static_cast<int64_t>(sent.size()) &&
               c->decode_errors >= 4;
      },
      15.0));
  const auto c = rx.input(input);
  EXPECT_EQ(c->decode_errors, 4);
  EXPECT_EQ(c->received, static_cast<int64_t>(rx.poses.size()));
  EXPECT_GE(c->skipped, 4);
  EXPECT_EQ(c->rejected_values + c->rejected_stamps, 0);
  EXPECT_TRUE(node.running());
  // Stamps never went backwards across the reconnections.
  for (size_t i = 1; i < rx.poses.size(); ++i) EXPECT_GT(rx.poses[i].utime, rx.poses[i - 1].utime);
}

TEST(MocapNodeTest, BadConfigurationIsExit2NamingFileKeyAndValue) {
  const std::string config = temp_path("bad.yaml");
  {
    std::ofstream f(config);
    f << "mocap:\n  server: {tracker: \"Pelican@127.0.0.1\"}\n  velocity: {source: kalman}\n";
  }
  const std::string out = temp_path("bad.log");
  Process node({kBin, "--config", config, "--lcm-url", kUrl}, out);
  EXPECT_EQ(node.wait_exit(), 2);
  const std::string text = read_file(out);
  EXPECT_NE(text.find(config), std::string::npos) << text;
  EXPECT_NE(text.find("mocap.velocity.source"), std::string::npos) << text;
  EXPECT_NE(text.find("kalman"), std::string::npos) << text;
  Process override_node(
      {kBin, "--config", write_config("good", 3883), "--lcm-url", kUrl, "--tracker", "no-at-sign"},
      out);
  EXPECT_EQ(override_node.wait_exit(), 2);
  EXPECT_NE(read_file(out).find("--tracker"), std::string::npos);
}

TEST(MocapNodeTest, UnreachableServerWithAStartTimeoutIsExit3) {
  // A port nothing listens on: bound, then closed.
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  close(fd);
  const std::string config = temp_path("unreachable.yaml");
  {
    std::ofstream f(config);
    f << "mocap:\n  server: {tracker: \"Pelican@127.0.0.1:" << ntohs(a.sin_port)
      << "\", start_timeout_s: 0.5, retry_initial_s: 0.05}\n";
  }
  const std::string out = temp_path("unreachable.log");
  Process node({kBin, "--config", config, "--lcm-url", kUrl}, out);
  EXPECT_EQ(node.wait_exit(), 3);
  const std::string text = read_file(out);
  EXPECT_NE(text.find("cannot reach the VRPN server at 127.0.0.1:"), std::string::npos) << text;
  EXPECT_NE(text.find("refused"), std::string::npos) << text;
}

}  // namespace

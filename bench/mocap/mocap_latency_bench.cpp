// Latency and rate of alight-mocap on this machine: the VRPN test server (tools/) serves poses
// over TCP on 127.0.0.1, each stamped with the wall clock just before it is written to the
// socket; alight-mocap (stamp.source server, so pose_t.utime is that send time) publishes
// MOCAP_POSE; this process receives it over LCM and takes receipt - utime. That is server send
// -> MOCAP_POSE delivered to a subscriber: the node's publish plus LCM's loopback delivery, an
// upper bound of send -> publish.
//
// The peer, in the same run: the same server and stream read by a TCP client in this process
// through the same VRPN decoder (no second process, no LCM): what the transport and decoding
// alone cost, the floor the node's figure stands on.
//
//   build/bin/mocap_latency_bench [--seconds S] [--rates 100,360,1000]

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <alight/node_status_t.hpp>
#include <alight/pose_t.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/build_paths.hpp"
#include "common/channels.hpp"
#include "mocap/vrpn.hpp"
#include "tools/vrpn_test_server.hpp"

extern char** environ;

namespace {

using alight::tools::ServedPose;
using alight::tools::VrpnTestServer;

const std::string kUrl = "udpm://239.255.76.67:7936?ttl=0";

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}

// Serves `n` poses at `rate_hz`, each stamped just before it is written.
void serve(VrpnTestServer& server, int n, double rate_hz, std::atomic<bool>& done) {
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    ServedPose p;
    p.object = "Pelican";
    p.pos[0] = 0.001 * i, p.pos[2] = 1.0;
    p.stamp_us = now_us();
    if (!server.send_pose(p)) break;
    next += std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate_hz));
    std::this_thread::sleep_until(next);
  }
  done = true;
}

struct Result {
  int sent = 0, received = 0;
  int64_t published = -1;  // by the node, from its NODE_STATUS (-1: the peer, or none heard)
  int64_t held_back = -1;
  double rate_hz = 0, p50_us = 0, p99_us = 0, max_us = 0;
};

struct Receiver {
  std::vector<double> latency_us;
  std::vector<int64_t> recv_us;
  int64_t published = -1, held_back = -1;
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const alight::node_status_t* m) {
    for (const auto& c : m->channels)
      if (c.channel.rfind("vrpn:", 0) == 0) published = c.received, held_back = c.skipped;
  }
  void on_pose(const lcm::ReceiveBuffer*, const std::string&, const alight::pose_t* m) {
    const int64_t t = now_us();
    latency_us.push_back(static_cast<double>(t - m->utime));
    recv_us.push_back(t);
  }
};

Result summarise(int sent, const std::vector<double>& latency, const std::vector<int64_t>& recv) {
  Result r;
  r.sent = sent;
  r.received = static_cast<int>(latency.size());
  if (recv.size() >= 2) r.rate_hz = (recv.size() - 1) / ((recv.back() - recv.front()) * 1e-6);
  r.p50_us = percentile(latency, 0.5);
  r.p99_us = percentile(latency, 0.99);
  r.max_us = latency.empty() ? NAN : *std::max_element(latency.begin(), latency.end());
  return r;
}

Result run_node(double rate_hz, double seconds, const std::string& bin) {
  VrpnTestServer server;
  if (!server.listen()) return {};
  const std::string config = (std::filesystem::temp_directory_path() /
                              ("alight_mocap_bench_" + std::to_string(getpid()) + ".yaml"))
                                 .string();
  {
    std::ofstream f(config);
    f << "mocap:\n  server: {tracker: \"Pelican@127.0.0.1:" << server.port()
      << "\", silence_timeout_s: 60}\n  stamp: {source: server, max_clock_offset_s: 60}\n"
         "  velocity: {max_gap_s: 1.0}\n";
  }
  lcm::LCM lcm(kUrl + "&recv_buf_size=4194304");
  Receiver rx;
  lcm.subscribe(alight::channels::kMocapPose, &Receiver::on_pose, &rx);
  lcm.subscribe(alight::channels::kNodeStatus, &Receiver::on_status, &rx);
  std::vector<std::string> args = {bin,  "--config",    config, "--lcm-url",
                                   kUrl, "--log-level", "error"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return {};
  Result r;
  if (server.accept(30.0, {"Pelican"})) {
    const int n = static_cast<int>(rate_hz * seconds);
    std::atomic<bool> done{false};
    std::thread t(serve, std::ref(server), n, rate_hz, std::ref(done));
    while (!done) lcm.handleTimeout(10);
    t.join();
    // Until the node's counters (1 Hz) show every pose published or held back, then one more
    // report for the last messages to land.
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < end && rx.published + rx.held_back < n)
      lcm.handleTimeout(10);
    const auto settle = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (std::chrono::steady_clock::now() < settle) lcm.handleTimeout(10);
    r = summarise(n, rx.latency_us, rx.recv_us);
    r.published = rx.published;
    r.held_back = rx.held_back;
  }
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  std::filesystem::remove(config);
  return r;
}

// The peer: a TCP client in this process, the same decoder, no LCM.
Result run_peer(double rate_hz, double seconds) {
  VrpnTestServer server;
  if (!server.listen()) return {};
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<uint16_t>(server.port()));
  Result r;
  std::thread connector([&] {
    connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    const auto cookie = alight::mocap::vrpn::make_cookie(0);
    (void)!write(fd, cookie.data(), cookie.size());
  });
  const bool ok = server.accept(30.0, {"Pelican"});
  connector.join();
  if (ok) {
    const int n = static_cast<int>(rate_hz * seconds);
    std::atomic<bool> done{false};
    std::thread t(serve, std::ref(server), n, rate_hz, std::ref(done));
    alight::mocap::vrpn::StreamDecoder decoder;
    std::vector<double> latency;
    std::vector<int64_t> recv;
    std::vector<alight::mocap::vrpn::TrackerReport> reports;
    std::vector<uint8_t> buf(65536);
    while (static_cast<int>(latency.size()) < n) {
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 2000) <= 0) break;
      const ssize_t got = read(fd, buf.data(), buf.size());
      if (got <= 0) break;
      const int64_t now = now_us();
      reports.clear();
      decoder.feed(buf.data(), static_cast<size_t>(got), reports);
      for (const auto& rep : reports) {
        latency.push_back(static_cast<double>(now - rep.stamp_us));
        recv.push_back(now);
      }
    }
    t.join();
    r = summarise(n, latency, recv);
  }
  close(fd);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10.0;
  std::vector<double> rates = {100, 360, 1000};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--seconds" && i + 1 < argc) {
      seconds = std::stod(argv[++i]);
    } else if (arg == "--rates" && i + 1 < argc) {
      rates.clear();
      std::stringstream s(argv[++i]);
      for (std::string r; std::getline(s, r, ',');) rates.push_back(std::stod(r));
    } else {
      std::fprintf(stderr, "usage: mocap_latency_bench [--seconds S] [--rates 100,360,1000]\n");
      return 2;
    }
  }
  const std::string bin = std::string(alight::build::binary_dir()) + "/bin/alight-mocap";
  std::printf("server send -> received, %.0f s per rate, 127.0.0.1 (latency in us)\n", seconds);
  std::printf(
      "| path | rate asked [Hz] | sent | published (held back) | received | rate achieved [Hz] | "
      "p50 | p99 | max |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (double rate : rates) {
    for (int peer = 0; peer < 2; ++peer) {
      const Result r = peer ? run_peer(rate, seconds) : run_node(rate, seconds, bin);
      const std::string published =
          r.published < 0 ? "-"
                          : std::to_string(r.published) + " (" + std::to_string(r.held_back) + ")";
      std::printf("| %s | %.0f | %d | %s | %d | %.1f | %.0f | %.0f | %.0f |\n",
                  peer ? "peer: TCP + VRPN decode in-process" : "alight-mocap -> MOCAP_POSE (LCM)",
                  rate, r.sent, published.c_str(), r.received, r.rate_hz, r.p50_us, r.p99_us,
                  r.max_us);
      std::fflush(stdout);
    }
  }
  return 0;
}

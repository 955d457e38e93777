// alight-mocap: a VRPN tracker (VICON Tracker, OptiTrack Motive, Qualisys QTM) -> MOCAP_POSE
// Glue only: the protocol, the room's frame, the stamps and the velocities
// are the TrackerClient's (mocap/tracker.hpp); this file owns the TCP socket, the clocks, LCM and
// the parameters.
//
//   alight-mocap --config config/mocap/vicon_tracker.yaml [--tracker OBJECT@HOST[:PORT]]
//
// A server that cannot be reached, goes away, stalls or sends something that is not VRPN is
// retried with a doubling delay, forever by default: a flight stack must not need a restart
// because the room's PC booted late or was restarted, and without poses the outer loop and
// autonomy already fly their failsafes. server.start_timeout_s > 0 instead ends the process with
// exit code 3 when no connection was ever made (for scripts and checks). Bad configuration: exit 2.
// NODE_STATUS reports the stream as the input "vrpn:OBJECT@HOST[:PORT]": poses published,
// messages refused, values and stamps refused, poses held back.

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>
#include <string>

#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "mocap/params.hpp"
#include "mocap/tracker.hpp"

namespace {

using alight::mocap::TrackerAddress;

/// Starts a non-blocking TCP connection; -1 and *error when it failed at once.
int start_connect(const TrackerAddress& a, std::string* error) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(a.host.c_str(), std::to_string(a.port).c_str(), &hints, &found);
  if (rc != 0) {
    *error = std::string("cannot resolve ") + a.host + ": " + gai_strerror(rc);
    return -1;
  }
  int fd = -1;
  for (addrinfo* ai = found; ai; ai = ai->ai_next) {
    fd = socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (connect(fd, ai->ai_addr, ai->ai_addrlen) == 0 || errno == EINPROGRESS) break;
    *error = std::string("connect: ") + std::strerror(errno);
    close(fd);
    fd = -1;
  }
  freeaddrinfo(found);
  return fd;
}

/// Writes all of `data` to a connected socket (the greeting: a few hundred bytes).
bool send_all(int fd, const std::vector<uint8_t>& data, std::string* error) {
  size_t sent = 0;
  while (sent < data.size()) {
    const ssize_t n = send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<size_t>(n);
    } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      pollfd p{fd, POLLOUT, 0};
      if (poll(&p, 1, 100) <= 0) {
        *error = "send: timed out";
        return false;
      }
    } else {
      *error = std::string("send: ") + std::strerror(errno);
      return false;
    }
  }
  return true;
}

alight::ChannelStats channel_stats(const alight::mocap::TrackerStats& s) {
  alight::ChannelStats c;
  c.received = s.poses;
  c.decode_errors =
      s.decoder.refused() + s.decoder.framing_errors + s.decoder.cookie_errors + s.truncated;
  c.rejected_values = s.rejected_values;
  c.rejected_stamps = s.rejected_stamps;
  c.skipped = s.held_back;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-mocap", [&]() -> int {
    using namespace alight;
    CLI::App app{"alight-mocap: a VRPN tracker's poses (VICON, Motive, QTM) -> MOCAP_POSE"};
    NodeArgs args;
    args.add_to(app, true);
    std::string tracker;
    app.add_option("--tracker", tracker,
                   "OBJECT@HOST[:PORT], instead of the file's server.tracker");
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    mocap::MocapParams params = mocap::load_params(args.config);
    if (!tracker.empty()) {
      if (!mocap::parse_tracker(tracker))
        throw ParamError("--tracker", "mocap.server.tracker", tracker,
                         "must be OBJECT@HOST or OBJECT@HOST:PORT");
      params.server.tracker = tracker;
    }
    const mocap::TrackerAddress address = *mocap::parse_tracker(params.server.tracker);
    const auto& sp = params.server;
    const std::string where = address.host + ":" + std::to_string(address.port);
    const std::string input = "vrpn:" + params.server.tracker;

    Node node(args, "alight-mocap");
    mocap::TrackerClient client(params);
    node.set_input_stats(input, {});
    spdlog::info("alight-mocap: {} sensor {} from {}, room {} {}-up, stamps {}, velocity {} -> {}",
                 address.object, sp.sensor, where, params.room.units, params.room.up_axis,
                 params.stamp.source, params.velocity.source, params.channel);

    enum class State { kIdle, kConnecting, kConnected };
    State state = State::kIdle;
    int fd = -1;
    const int64_t start = steady_utime();
    int64_t next_attempt = start, attempt_started = 0, last_rx = 0;
    double delay_s = sp.retry_initial_s;
    bool ever_connected = false, got_pose = false, warned_no_pose = false;
    uint64_t failures = 0, poses_before = 0, reports_before = 0, refusals_logged = 0;
    std::string last_error = "none yet";
    int64_t seq = 0;
    std::vector<uint8_t> buffer(65536);

    const auto drop = [&](const std::string& why) {
      if (fd >= 0) close(fd);
      fd = -1;
      if (state == State::kConnected) {
        client.end_of_stream();
        node.set_input_stats(input, channel_stats(client.stats()));
      }
      state = State::kIdle;
      last_error = why;
      // A server that was streaming and went away is tried again soon; failures back off.
      if (got_pose) {
        delay_s = sp.retry_initial_s;
        failures = 0;
      }
      got_pose = false;
      next_attempt = steady_utime() + static_cast<int64_t>(delay_s * 1e6);
      if (++failures <= 3 || failures % 20 == 0)
        spdlog::warn("alight-mocap: {}: {}; retrying in {:.1f} s ({} failures)", where, why,
                     delay_s, failures);
      delay_s = std::min(sp.retry_max_s, delay_s * 2);
    };

    while (!node.stopping()) {
      int64_t now = steady_utime();
      if (!ever_connected && sp.start_timeout_s > 0 && now - start > sp.start_timeout_s * 1e6) {
        spdlog::error(
            "alight-mocap: cannot reach the VRPN server at {} after {:.1f} s (last error: {}); "
            "check server.tracker in {}, that the room software streams VRPN, and the network",
            where, sp.start_timeout_s, last_error, args.config);
        if (fd >= 0) close(fd);
        return 3;
      }
      if (state == State::kIdle && now >= next_attempt) {
        std::string error;
        fd = start_connect(address, &error);
        if (fd < 0) {
          drop(error);
        } else {
          state = State::kConnecting;
          attempt_started = now;
        }
      }

      pollfd p{fd, static_cast<short>(state == State::kConnecting ? POLLOUT : POLLIN), 0};
      int timeout_ms = 10;
      if (state == State::kIdle)
        timeout_ms = static_cast<int>(std::clamp<int64_t>((next_attempt - now) / 1000, 0, 10));
      const int ready = poll(&p, fd >= 0 ? 1 : 0, timeout_ms);
      now = steady_utime();

      if (state == State::kConnecting) {
        if (ready > 0) {
          int err = 0;
          socklen_t len = sizeof err;
          getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
          std::string error;
          if (err != 0) {
            drop(std::string("connect: ") + std::strerror(err));
          } else if (!send_all(fd, client.greeting(wall_utime()), &error)) {
            drop(error);
          } else {
            client.reset();
            state = State::kConnected;
            ever_connected = true;
            last_rx = now;
            got_pose = warned_no_pose = false;
            poses_before = client.stats().poses;
            reports_before = client.stats().reports;
            spdlog::info("alight-mocap: connected to {}", where);
          }
        } else if (now - attempt_started > sp.connect_timeout_s * 1e6) {
          drop("connect: timed out");
        }
      } else if (state == State::kConnected) {
        bool closed = false;
        if (ready > 0) {
          for (;;) {
            const ssize_t n = recv(fd, buffer.data(), buffer.size(), 0);
            if (n > 0) {
              const int64_t recv_utime = wall_utime();
              const bool had_cookie = client.decoder().cookie_received();
              for (const auto& pose :
                   client.on_bytes(buffer.data(), static_cast<size_t>(n), recv_utime))
                node.publish(params.channel, to_msg(pose.pose, seq++));
              last_rx = now;
              if (!had_cookie && client.decoder().cookie_received())
                spdlog::info("alight-mocap: {} speaks VRPN {}", where,
                             client.decoder().cookie().version);
              if (client.failed()) break;
              if (static_cast<size_t>(n) < buffer.size()) break;
            } else if (n == 0) {
              closed = true;
              break;
            } else {
              if (errno == EINTR) continue;
              if (errno != EAGAIN && errno != EWOULDBLOCK) {
                drop(std::string("recv: ") + std::strerror(errno));
              }
              break;
            }
          }
        }
        const auto stats = client.stats();
        node.set_input_stats(input, channel_stats(stats));
        // Refusals are counted on NODE_STATUS; the log has the first and every 100th.
        const uint64_t refusals =
            stats.decoder.refused() + stats.rejected_values + stats.rejected_stamps;
        if (refusals > refusals_logged &&
            (refusals_logged == 0 || refusals / 100 > refusals_logged / 100))
          spdlog::warn("alight-mocap: {} message(s) or pose(s) refused (last value or stamp: {})",
                       refusals, stats.last_refusal.empty() ? "none" : stats.last_refusal);
        refusals_logged = refusals;
        if (stats.poses > poses_before && !got_pose) {
          got_pose = true;
          spdlog::info("alight-mocap: receiving {} sensor {}", address.object, sp.sensor);
        }
        if (state != State::kConnected) {
          // dropped by a receive error above
        } else if (client.failed()) {
          drop("not a usable VRPN stream: " + client.error());
        } else if (closed) {
          drop("server closed the connection");
        } else if (now - last_rx > sp.silence_timeout_s * 1e6) {
          drop("nothing received for " + std::to_string(sp.silence_timeout_s) + " s");
        }
        // The usual set-up mistake: the object's name differs from the room software's.
        if (state == State::kConnected && !warned_no_pose && stats.reports == reports_before &&
            now - attempt_started > 2'000'000 && !client.trackers_seen().empty()) {
          warned_no_pose = true;
          std::string seen;
          for (const auto& t : client.trackers_seen()) seen += (seen.empty() ? "" : ", ") + t;
          spdlog::warn("alight-mocap: {} sends no pose of {} sensor {}; it sends: {}", where,
                       address.object, sp.sensor, seen);
        }
      }
      node.spin_once(0);
    }
    if (fd >= 0) close(fd);
    return 0;
  });
}

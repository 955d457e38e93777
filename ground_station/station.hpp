#pragma once
// The ground station's glue: LCM subscriptions feeding StationState and the video FrameStores,
// and the web server (cpp-httplib) serving the page, the state document, video frames and
// command requests. The LCM thread never waits for a web client: it only takes short locks to
// update state or swap a frame pointer; the server (http_server.hpp) reads request heads in one
// gate thread with deadlines and limits, serves them from bounded worker pools with workers kept
// for commands, and keeps no per-client buffers (every client reads the same newest frame and
// the same cached state document). Every response forbids framing (X-Frame-Options, CSP
// frame-ancestors), and every command needs the session token in the X-Alight-Token header, on
// loopback too: a cross-site form cannot set that header, and a cross-site script cannot send
// it without a CORS preflight that this server never grants.

#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "common/node.hpp"
#include "common/operator_auth.hpp"
#include "ground_station/commands.hpp"
#include "ground_station/frame_store.hpp"
#include "ground_station/params.hpp"
#include "ground_station/state.hpp"

namespace alight::ground_station {

class HardenedServer;

struct StationOptions {
  std::string bind_address = "127.0.0.1";
  int port = -1;                   ///< -1: params.http_port; 0: any free port
  std::string web_dir;             ///< folder with index.html, app.js, style.css
  std::optional<OperatorKey> key;  ///< without a key the station is view-only
  std::string sender = "ground-station";
  std::string token;  ///< session token, required with every command (empty on loopback: one
                      ///< is drawn)
  bool require_token = false;  ///< on loopback, do not hand the token to the page through
                               ///< GET /api/session (e.g. behind an SSH tunnel or a proxy)
};

/// Counters for tests and the page.
struct StationCounters {
  uint64_t http_requests = 0;
  uint64_t commands_published = 0;
  uint64_t commands_refused = 0;          ///< access or parse errors
  uint64_t connections_over_limit = 0;    ///< refused: no worker free and the queue full, or too
                                          ///< many heads arriving at once
  uint64_t heads_timed_out = 0;           ///< request head not complete within head_deadline_s
  uint64_t heads_too_large = 0;           ///< over max_head_bytes or max_header_count
  uint64_t commands_without_session = 0;  ///< refused: the vehicle's session is not known
};

class Station {
 public:
  Station(const GroundStationParams& params, StationOptions options);
  ~Station();
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  /// Subscribes to the vehicle's channels and adds the timer that publishes queued commands.
  void attach(Node& node);
  /// Starts the web server threads; returns the bound port. Throws std::runtime_error.
  int start();
  void stop();

  StationCounters counters() const;
  const AccessPolicy& policy() const { return policy_; }
  /// The state document at steady time `now_utime`, at most `state_cache_s` old (for tests; the
  /// server uses it too).
  std::shared_ptr<const std::string> state_json(int64_t now_utime);

 private:
  void setup_routes();
  void publish_pending(Node& node, int64_t now_utime);
  std::string station_json(int64_t now_utime) const;

  GroundStationParams params_;
  StationOptions options_;
  AccessPolicy policy_;

  mutable std::mutex state_mutex_;
  StationState state_;
  std::shared_ptr<const std::string> state_cache_;
  int64_t state_cache_utime_ = INT64_MIN;
  std::atomic<int64_t> lcm_loop_utime_{0};  // last LCM timer tick (page shows it as health)

  FrameStore camera_;
  FrameStore diag_;

  std::mutex command_mutex_;
  std::optional<CommandBuilder> builder_;
  std::deque<operator_cmd_t> pending_commands_;  // bounded: kMaxPendingCommands

  std::unique_ptr<HardenedServer> server_;
  std::thread server_thread_;
  std::atomic<uint64_t> http_requests_{0}, commands_published_{0}, commands_refused_{0};
  std::atomic<uint64_t> commands_without_session_{0};
};

/// Random session token (128 bits, hex) from OpenSSL's RAND_bytes.
std::string make_session_token();

}  // namespace alight::ground_station

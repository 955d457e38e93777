#pragma once
// The thin-node side of every process: owns the LCM handle, the command line, the wall clock
// and the signals; libraries never see any of them (docs/ARCHITECTURE.md "Libraries and nodes").
//
// Debian's LCM 1.3.1 needs three things done for it here:
//  - a large UDP receive buffer (its default loses most of a burst of 300 KB images): the URL
//    gets recv_buf_size unless it names one;
//  - per-subscription queues hold 30 messages and silently drop the newest beyond that: every
//    subscription gets a deep LCM queue, which each spin empties into the node's own Inbox
//    (common/inbox.hpp: one arrival order across channels, a capacity per subscription, every
//    message refused for a full queue counted in `dropped`), and on_latest() drains all pending
//    messages before calling back with the newest one, counting the ones it skipped;
//  - a message that fails to decode is only printed by its typed handler, and lcm-gen's
//    decoders throw on some malformed lengths: ours decode through decode_message()
//    (common/decode.hpp), which never throws, and count and report decode errors per channel.
//
// Every input is untrusted: besides decode errors, a node counts the messages its conversions
// refuse (reject_value) and the stamps its StampGuard refuses (accept_stamp), and publishes all
// counters on NODE_STATUS once a second. Channels are named in the code by common/channels.hpp
// and renamed per process by --remap FROM=TO (NodeArgs, Node(const NodeArgs&, ...)). Timers run on
// the steady clock, so a wall-clock step neither freezes nor bursts them.
//
// Who published (common/bus_auth.hpp): every message a node publishes carries an origin trailer
// (this node's random source id and a counter), signed when the node has a bus key (--bus-key,
// else $ALIGHT_BUS_KEY_FILE, which alight-launch sets from the launch file's bus_key). Every
// message a node receives is judged on arrival, before it takes a place in a queue: with a key,
// unsigned, wrongly signed and replayed messages are refused; with or without one, a second
// publisher on a channel that has one (every channel but NODE_STATUS and OPERATOR_CMD) is refused
// while the first is alive. Both are counted per channel and reported on NODE_STATUS; contested()
// tells flight logic that a channel has a second publisher now. The stamp guard judges each
// publisher's stamps on their own, so one that jumps ahead cannot make the others' look old.

#include <alight/node_status_t.hpp>
#include <atomic>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/bus_auth.hpp"
#include "common/channels.hpp"
#include "common/decode.hpp"
#include "common/inbox.hpp"
#include "common/stamp_guard.hpp"

namespace CLI {
class App;
}

namespace alight {

/// Default LCM URL: multicast with ttl=0 (nothing leaves the machine unless asked).
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
/// Receive buffer requested when the URL names none [bytes].
inline constexpr int kDefaultRecvBufBytes = 8 * 1024 * 1024;

/// Command-line options every node shares.
struct NodeArgs {
  std::string config;   ///< --config FILE (component parameters)
  std::string lcm_url;  ///< --lcm-url URL, else $LCM_DEFAULT_URL, else kDefaultLcmUrl
  std::string log_level = "info";
  std::vector<std::string> remap_args;  ///< --remap FROM=TO, repeatable
  ChannelRemap remap;                   ///< remap_args parsed by finalize()
  std::string bus_key_file;             ///< --bus-key FILE, else $ALIGHT_BUS_KEY_FILE, else none
  std::optional<bus::BusKey> bus_key;   ///< read by finalize()

  /// Adds --config, --lcm-url, --log-level and --remap to an app that has options of its own.
  void add_to(CLI::App& app, bool config_required);
  /// Fills lcm_url from the environment when not given, applies the log level and parses the
  /// remaps (throws RemapError, which run_node_main turns into exit code 2) and reads the bus
  /// key (a bad key file is a ParamError naming it: exit code 2).
  void finalize();
};

/// URL with recv_buf_size added when absent (udpm only).
std::string with_receive_buffer(const std::string& url, int bytes = kDefaultRecvBufBytes);
/// Current wall-clock time [us since Unix epoch]. For nodes only; flight logic gets time passed in.
int64_t wall_utime();
/// Monotonic time [us since an arbitrary start]: for timers and timeouts, immune to clock steps.
int64_t steady_utime();

/// Per-channel counters, for logs and tests.
struct ChannelStats {
  uint64_t received = 0;          ///< messages decoded
  uint64_t decode_errors = 0;     ///< messages that failed to decode (malformed or wrong type)
  uint64_t rejected_values = 0;   ///< decoded, then refused by a conversion (non-finite, range)
  uint64_t rejected_stamps = 0;   ///< decoded, then refused by the stamp guard
  uint64_t skipped = 0;           ///< on_latest(): older messages replaced by a newer one
  uint64_t dropped = 0;           ///< on(): refused unread, the subscription's queue was full
  uint64_t rejected_auth = 0;     ///< refused on arrival: unsigned, wrong key, bad tag, replayed
  uint64_t second_publisher = 0;  ///< refused on arrival: a second publisher on the channel
  uint64_t owner_changes = 0;     ///< a silent publisher replaced by another (a restart)
};

/// Messages an on() subscription may hold waiting for its handler unless told otherwise.
inline constexpr size_t kDefaultQueueCapacity = 2048;

/// When the node read the message being handled off LCM.
struct Receipt {
  int64_t wall_utime = 0;    ///< [us since Unix epoch]
  int64_t steady_utime = 0;  ///< steady_utime() [us]
};

class Node {
 public:
  /// Connects to LCM; throws std::runtime_error naming the URL when that fails. `bus_key`: sign
  /// what it publishes and refuse what is not signed with it.
  explicit Node(const std::string& lcm_url, std::string name = "alight",
                std::optional<bus::BusKey> bus_key = std::nullopt);
  /// Connects to args.lcm_url and renames channels by args.remap.
  Node(const NodeArgs& args, std::string name);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  /// Calls `fn` for every message on `channel`, in arrival order across all on() channels. At
  /// most `capacity` messages of this channel wait for it; more arriving meanwhile are dropped
  /// unread and counted (ChannelStats::dropped), so a handler slower than its input holds
  /// bounded memory instead of an ever longer backlog.
  template <class Msg>
  void on(const std::string& name, std::function<void(const Msg&)> fn,
          size_t capacity = kDefaultQueueCapacity) {
    const std::string channel = remap_(name);
    subscribe_raw(
        channel, false,
        [this, channel, fn](const void* data, uint32_t size) {
          Msg msg;
          if (decode(channel, msg, data, size)) fn(msg);
        },
        capacity, channels::single_publisher(name));
  }
  /// Calls `fn` with only the newest message on `channel` each time the node catches up, so a
  /// slow consumer works on the newest frame instead of a backlog.
  template <class Msg>
  void on_latest(const std::string& name, std::function<void(const Msg&)> fn) {
    const std::string channel = remap_(name);
    subscribe_raw(
        channel, true,
        [this, channel, fn](const void* data, uint32_t size) {
          Msg msg;
          if (decode(channel, msg, data, size)) fn(msg);
        },
        kDefaultQueueCapacity, channels::single_publisher(name));
  }
  template <class Msg>
  int publish(const std::string& channel, const Msg& msg) {
    const int n = msg.getEncodedSize();
    std::vector<uint8_t> bytes(static_cast<size_t>(n));
    if (msg.encode(bytes.data(), 0, n) != n) return -1;
    return publish_raw(remap_(channel), std::move(bytes));
  }
  /// Publishes `bytes` (an encoded message) on `lcm_channel` (already remapped) with this node's
  /// origin trailer.
  int publish_raw(const std::string& lcm_channel, std::vector<uint8_t> bytes);
  /// Calls `fn(wall_utime)` every `period_s` of steady time (the argument is the wall clock, for
  /// stamping messages; never use it to measure intervals).
  void every(double period_s, std::function<void(int64_t)> fn);

  /// Counts a decoded message on `channel` that a conversion refused, and logs `why` for the
  /// first and then every 100th. Returns false, for `return node.reject_value(...)`.
  bool reject_value(const std::string& channel, const std::string& why);
  /// Judges a decoded message's stamp (StampGuard, with this node's clocks). A refused stamp is
  /// counted and logged like reject_value; true when the message may be used.
  bool accept_stamp(const std::string& channel, int64_t utime);
  /// Sets the counters of an input that is not an LCM channel (alight-mocap's TCP stream), so
  /// NODE_STATUS reports it beside the channels.
  void set_input_stats(const std::string& input, const ChannelStats& stats) {
    stats_[input] = stats;
  }
  /// True while `channel` has a second publisher: one was refused within the last `window_s`.
  bool contested(const std::string& channel, double window_s = 2.0) const;
  /// How long `channel`'s current contest by a second publisher has lasted [s] (0: none; one
  /// forged message: 0; a second publisher that keeps sending: growing).
  double contest_span_s(const std::string& channel) const;
  /// The newest counter (bus time) this node has accepted from any publisher [us], 0 before.
  int64_t bus_time_us() const { return gatekeeper_.bus_time_us(); }
  /// This node's publisher id (in every trailer it sends) and whether it signs.
  uint64_t source_id() const { return sealer_.source(); }
  bool signing() const { return sealer_.signing(); }
  /// Newest stamp accepted on any channel (0 before the first).
  int64_t newest_stamp() const { return stamps_.newest_utime(); }
  void set_stamp_params(const StampGuardParams& p) { stamps_ = StampGuard(p); }
  /// Publishes this node's counters on NODE_STATUS every `period_s` (every node does, at 1 s,
  /// unless it calls this with 0 before run()).
  void set_status_period(double period_s) { status_period_s_ = period_s; }
  /// The NODE_STATUS message as it would be published now.
  node_status_t status_message(int64_t wall_utime) const;

  /// Handles messages and timers until SIGINT / SIGTERM or stop(). Returns 0.
  int run();
  /// Waits up to `timeout_ms` for messages (not at all when some already wait), hands every
  /// message waiting in the inbox to its on() handler in arrival order (what arrives meanwhile
  /// is read into the inbox and waits for the next spin), calls back the latest ones, and runs
  /// due timers. Returns the number of messages read off LCM.
  int spin_once(int timeout_ms);
  void stop() { stopping_ = true; }
  bool stopping() const;

  const ChannelStats& stats(const std::string& channel) const;
  /// When the message being handled was read off LCM (valid inside an on() / on_latest()
  /// handler; for timing, never for what a node computes).
  const Receipt& receipt() const { return receipt_; }
  lcm::LCM& lcm() { return *lcm_; }
  /// The name on LCM of a channel named in the code (channels.hpp): its --remap target or itself.
  /// Every method above that takes a channel applies it.
  std::string channel_name(const std::string& channel) const { return remap_(channel); }
  const std::string& name() const { return name_; }

  /// Installs the SIGINT / SIGTERM handlers that make run() return (called by the constructor).
  static void install_signal_handlers();
  static bool signalled();

 private:
  struct Subscription;
  void subscribe_raw(const std::string& channel, bool latest,
                     std::function<void(const void*, uint32_t)> dispatch,
                     size_t capacity = kDefaultQueueCapacity, bool single_publisher = true);
  // A message read off LCM, waiting in the inbox for its handler.
  struct Inbound {
    Subscription* sub = nullptr;
    std::vector<uint8_t> bytes;
    Receipt receipt;
    uint64_t source = 0;  // the trailer's publisher id (0: none)
  };
  // Judges a message on arrival (bus_auth); counts and logs a refusal. True: keep it.
  bool admit(Subscription& sub, const void* data, uint32_t size, int64_t steady_us,
             uint64_t* source);
  int read_pending();  // empties LCM's queues without waiting; returns the messages read
  void enqueue(Subscription& sub, const void* data, uint32_t size);
  template <class Msg>
  bool decode(const std::string& channel, Msg& msg, const void* data, uint32_t size) {
    const bus::Received r = bus::split(data, size);
    if (!decode_message(msg, r.payload.data(), r.payload.size())) {
      report_decode_error(channel, size);
      return false;
    }
    ++stats_[channel].received;
    return true;
  }
  void report_decode_error(const std::string& channel, uint32_t size);
  void run_timers(int64_t steady_now);

  std::string name_;
  ChannelRemap remap_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Subscription>> subs_;
  Inbox<Inbound> inbox_;
  Receipt receipt_;
  std::map<std::string, ChannelStats> stats_;
  struct Timer {
    int64_t period_us;
    int64_t next_utime;
    std::function<void(int64_t)> fn;
  };
  std::vector<Timer> timers_;  // next_utime on the steady clock
  std::atomic<bool> stopping_{false};
  StampGuard stamps_;
  bus::Sealer sealer_;
  bus::Gatekeeper gatekeeper_;
  uint64_t current_source_ = 0;  // publisher of the message being handled
  double status_period_s_ = 1.0;
  bool status_timer_added_ = false;
  int64_t start_steady_us_ = 0;
  int64_t wall_minus_steady_us_ = 0;  // the clocks' offset at the last spin
  int32_t wall_clock_steps_ = 0;
};

/// Runs a node's body, turning exceptions into a message on stderr and an exit code: 2 for bad
/// configuration (ParamError), 1 for anything else. First it makes the heap keep freed memory
/// (retain_freed_memory, common/heap.hpp), so per-frame buffers do not page-fault every frame.
int run_node_main(const char* node_name, const std::function<int()>& body);

}  // namespace alight

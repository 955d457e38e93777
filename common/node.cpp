#include "common/node.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>

#include "common/heap.hpp"
#include "common/operator_auth.hpp"
#include "common/params.hpp"

namespace alight {

namespace {
std::atomic<bool> g_signalled{false};
extern "C" void on_signal(int) { g_signalled = true; }

// Every refusal is counted; the log says so for the first and then every 100th.
bool log_this(uint64_t n) { return n == 1 || n % 100 == 0; }

int rmem_max_bytes() {
  std::ifstream f("/proc/sys/net/core/rmem_max");
  int v = -1;
  f >> v;
  return v;
}
}  // namespace

void NodeArgs::add_to(CLI::App& app, bool config_required) {
  auto* c = app.add_option("--config", config, "Parameter file (YAML)");
  if (config_required) c->required()->check(CLI::ExistingFile);
  app.add_option("--lcm-url", lcm_url,
                 "LCM URL (default: $LCM_DEFAULT_URL, else " + std::string(kDefaultLcmUrl) + ")");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  app.add_option("--remap", remap_args,
                 "FROM=TO: use channel TO where this process would use FROM (repeatable; FROM "
                 "one of the channels in common/channels.hpp)")
      ->allow_extra_args(false);
  app.add_option("--bus-key", bus_key_file,
                 "Bus key file (scripts/make-key): sign what this node publishes and refuse what "
                 "is not signed with it (default: $ALIGHT_BUS_KEY_FILE, else an unsigned bus)");
}

void NodeArgs::finalize() {
  if (lcm_url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    lcm_url = (env && *env) ? env : kDefaultLcmUrl;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));
  remap = parse_remaps(remap_args);
  for (const auto& [from, to] : remap.map()) spdlog::info("channel {} remapped to {}", from, to);
  if (bus_key_file.empty()) {
    const char* env = std::getenv("ALIGHT_BUS_KEY_FILE");
    if (env && *env) bus_key_file = env;
  }
  if (!bus_key_file.empty()) {
    std::vector<std::string> warnings;
    try {
      bus_key = bus::load_bus_key(bus_key_file, &warnings);
    } catch (const KeyFileError& e) {
      throw ParamError(bus_key_file, "--bus-key", bus_key_file, e.what());
    }
    for (const auto& w : warnings) spdlog::warn("{}", w);
  }
}

std::string with_receive_buffer(const std::string& url, int bytes) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") +
         "recv_buf_size=" + std::to_string(bytes);
}

int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int64_t steady_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct Node::Subscription {
  Node* node = nullptr;
  std::string channel;
  bool single_publisher = true;  // the channel has one publisher (channels::single_publisher)
  bool latest = false;
  size_t source = 0;  // in the node's inbox (not latest mode)
  std::function<void(const void*, uint32_t)> dispatch;
  std::vector<uint8_t> pending;  // newest undispatched message (latest mode)
  Receipt pending_receipt;
  uint64_t pending_source = 0;
  bool has_pending = false;
  lcm::Subscription* handle = nullptr;

  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (!latest) {
      node->enqueue(*this, rbuf->data, rbuf->data_size);
      return;
    }
    const Receipt receipt{wall_utime(), steady_utime()};
    uint64_t source = 0;
    if (!node->admit(*this, rbuf->data, rbuf->data_size, receipt.steady_utime, &source)) return;
    if (has_pending) ++node->stats_[channel].skipped;
    const auto* bytes = static_cast<const uint8_t*>(rbuf->data);
    pending.assign(bytes, bytes + rbuf->data_size);
    pending_receipt = receipt;
    pending_source = source;
    has_pending = true;
  }
};

bool Node::admit(Subscription& sub, const void* data, uint32_t size, int64_t steady_us,
                 uint64_t* source) {
  const bus::Received r = bus::split(data, size);
  const bus::Verdict v = gatekeeper_.check(sub.channel, r, steady_us, sub.single_publisher);
  ChannelStats& st = stats_[sub.channel];
  const bus::ChannelAuthStats& a = gatekeeper_.stats(sub.channel);
  st.rejected_auth = a.rejected_auth;
  st.second_publisher = a.second_publisher;
  if (a.owner_changes != st.owner_changes) {
    st.owner_changes = a.owner_changes;
    spdlog::warn("{}: {} has a new publisher ({:016x}): the last one fell silent", name_,
                 sub.channel, a.owner);
  }
  *source = r.trailer ? r.trailer->source : 0;
  if (bus::accepted(v)) return true;
  const uint64_t n = v == bus::Verdict::kSecondPublisher ? a.second_publisher : a.rejected_auth;
  if (log_this(n))
    spdlog::error("{}: {} message(s) on {} refused (last: from {:016x}, {})", name_, n, sub.channel,
                  *source, bus::verdict_name(v));
  return false;
}

void Node::enqueue(Subscription& sub, const void* data, uint32_t size) {
  Inbound in;
  in.sub = &sub;
  in.receipt = Receipt{wall_utime(), steady_utime()};
  if (!admit(sub, data, size, in.receipt.steady_utime, &in.source)) return;
  const auto* bytes = static_cast<const uint8_t*>(data);
  in.bytes.assign(bytes, bytes + size);
  if (!inbox_.push(sub.source, std::move(in))) {
    const uint64_t n = ++stats_[sub.channel].dropped;
    if (log_this(n))
      spdlog::warn("{}: {} message(s) on {} dropped: {} already wait for the handler", name_, n,
                   sub.channel, inbox_.capacity(sub.source));
  }
}

Node::Node(const std::string& lcm_url, std::string name, std::optional<bus::BusKey> bus_key)
    : name_(std::move(name)),
      sealer_(bus::draw_source_id(), bus_key),
      gatekeeper_(bus_key),
      start_steady_us_(steady_utime()) {
  install_signal_handlers();
  const std::string url = with_receive_buffer(lcm_url);
  lcm_ = std::make_unique<lcm::LCM>(url);
  if (!lcm_->good())
    throw std::runtime_error("cannot open LCM at '" + url +
                             "' (is a multicast route set up? run scripts/setup)");
  const int rmem = rmem_max_bytes();
  if (url.rfind("udpm://", 0) == 0 && rmem > 0 && rmem < kDefaultRecvBufBytes)
    spdlog::warn(
        "{}: net.core.rmem_max is {} bytes (< {}); large messages may be lost. "
        "Run scripts/setup as root to raise it.",
        name_, rmem, kDefaultRecvBufBytes);
}

Node::Node(const NodeArgs& args, std::string name)
    : Node(args.lcm_url, std::move(name), args.bus_key) {
  remap_ = args.remap;
  spdlog::info("{}: publisher {:016x} on a{} bus", name_, sealer_.source(),
               sealer_.signing() ? " signed" : "n unsigned");
}

int Node::publish_raw(const std::string& lcm_channel, std::vector<uint8_t> bytes) {
  // The bus time: never behind what this node has heard, so a node whose clock lags (no
  // real-time clock before NTP) still stamps counters its peers take as fresh.
  sealer_.seal(bytes, lcm_channel, std::max(wall_utime(), gatekeeper_.bus_time_us()));
  return lcm_->publish(lcm_channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

double Node::contest_span_s(const std::string& channel) const {
  return static_cast<double>(gatekeeper_.contest_span_us(remap_(channel), steady_utime())) * 1e-6;
}

bool Node::contested(const std::string& channel, double window_s) const {
  return gatekeeper_.contested(remap_(channel), steady_utime(),
                               static_cast<int64_t>(window_s * 1e6));
}

Node::~Node() {
  for (auto& s : subs_)
    if (s->handle) lcm_->unsubscribe(s->handle);
}

void Node::install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool Node::signalled() { return g_signalled; }
bool Node::stopping() const { return stopping_ || g_signalled; }

void Node::subscribe_raw(const std::string& channel, bool latest,
                         std::function<void(const void*, uint32_t)> dispatch, size_t capacity,
                         bool single_publisher) {
  // Programmer invariant: capacities come from validated parameters or constants.
  assert(capacity >= 1);
  auto sub = std::make_unique<Subscription>();
  sub->node = this;
  sub->channel = channel;
  sub->single_publisher = single_publisher;
  sub->latest = latest;
  if (!latest) sub->source = inbox_.add_source(capacity);
  sub->dispatch = std::move(dispatch);
  sub->handle = lcm_->subscribe(channel, &Subscription::on_message, sub.get());
  // LCM's queue only holds what arrives while one handler runs (each spin moves it into the
  // inbox between handlers); its overflow is silent, so it is deep enough for several seconds
  // of the fastest input behind one slow handler (2 s of 200 Hz IMU, 30 s of 60 Hz frames).
  sub->handle->setQueueCapacity(latest ? 256 : 2048);
  stats_[channel];
  subs_.push_back(std::move(sub));
}

void Node::report_decode_error(const std::string& channel, uint32_t size) {
  const uint64_t n = ++stats_[channel].decode_errors;
  if (log_this(n))
    spdlog::error(
        "{}: {} message(s) on channel {} failed to decode (last: {} bytes; wrong type "
        "or malformed)",
        name_, n, channel, size);
}

bool Node::reject_value(const std::string& name, const std::string& why) {
  const std::string channel = remap_(name);
  const uint64_t n = ++stats_[channel].rejected_values;
  if (log_this(n))
    spdlog::warn("{}: {} message(s) on {} refused (last: {})", name_, n, channel, why);
  return false;
}

bool Node::accept_stamp(const std::string& name, int64_t utime) {
  const std::string channel = remap_(name);
  // Each publisher's stamps on their own: one that jumps ahead makes no other's look old.
  const std::string source =
      current_source_ == 0 ? channel : fmt::format("{}#{:016x}", channel, current_source_);
  const StampVerdict v = stamps_.check(source, utime, steady_utime(), wall_utime());
  if (v == StampVerdict::kAdopted)
    spdlog::warn(
        "{}: the wall clock ({}) is far behind {}'s stamps ({}): the inputs' stamps are the time "
        "base from now on (no real-time clock, or NTP not yet synchronised?)",
        name_, wall_utime(), channel, utime);
  if (v == StampVerdict::kRestarted)
    spdlog::warn("{}: stamps on {} went back to {} and stayed there: taken as a restart", name_,
                 channel, utime);
  if (stamp_ok(v)) return true;
  const uint64_t n = ++stats_[channel].rejected_stamps;
  if (log_this(n))
    spdlog::warn("{}: {} message(s) on {} refused for their stamp (last: utime {}, {})", name_, n,
                 channel, utime, stamp_verdict_name(v));
  return false;
}

node_status_t Node::status_message(int64_t wall) const {
  node_status_t m{};
  m.utime = wall;
  m.node = name_;
  m.pid = static_cast<int32_t>(::getpid());
  m.uptime_s = (steady_utime() - start_steady_us_) * 1e-6;
  for (const auto& [channel, st] : stats_) {
    channel_stats_t c{};
    c.channel = channel;
    c.received = static_cast<int64_t>(st.received);
    c.decode_errors = static_cast<int64_t>(st.decode_errors);
    c.rejected_values = static_cast<int64_t>(st.rejected_values);
    c.rejected_stamps = static_cast<int64_t>(st.rejected_stamps);
    c.skipped = static_cast<int64_t>(st.skipped);
    c.dropped = static_cast<int64_t>(st.dropped);
    c.rejected_auth = static_cast<int64_t>(st.rejected_auth);
    c.second_publisher = static_cast<int64_t>(st.second_publisher);
    c.owner_changes = static_cast<int64_t>(st.owner_changes);
    m.channels.push_back(c);
  }
  m.n = static_cast<int32_t>(m.channels.size());
  m.source = static_cast<int64_t>(sealer_.source());
  m.signed_bus = sealer_.signing();
  m.clock_from_inputs = stamps_.inputs_time_base();
  m.wall_clock_steps = wall_clock_steps_;
  return m;
}

const ChannelStats& Node::stats(const std::string& channel) const {
  static const ChannelStats kEmpty;
  auto it = stats_.find(remap_(channel));
  return it == stats_.end() ? kEmpty : it->second;
}

void Node::every(double period_s, std::function<void(int64_t)> fn) {
  // Programmer invariant: periods come from validated parameters or constants.
  assert(period_s > 0 && period_s < 1e6);
  const auto period_us = std::max<int64_t>(1, static_cast<int64_t>(period_s * 1e6));
  timers_.push_back({period_us, steady_utime() + period_us, std::move(fn)});
}

void Node::run_timers(int64_t now) {
  for (auto& t : timers_) {
    if (now < t.next_utime) continue;
    t.fn(wall_utime());
    t.next_utime += t.period_us;
    if (t.next_utime <= now) t.next_utime = now + t.period_us;  // fell behind: skip, don't burst
  }
}

int Node::spin_once(int timeout_ms) {
  if (!status_timer_added_) {
    status_timer_added_ = true;
    if (status_period_s_ > 0)
      every(status_period_s_,
            [this](int64_t wall) { publish(channels::kNodeStatus, status_message(wall)); });
    // On a signed bus a node learns the bus time from what it hears, and stamps its counters no
    // lower (a new publisher far behind it is taken for a recording). One that subscribes to
    // nothing (a camera) would go on from its own wall clock, which after a boot without a
    // real-time clock is decades behind: it hears every node's NODE_STATUS instead.
    const std::string status = remap_(channels::kNodeStatus);
    const bool hears_status = std::any_of(subs_.begin(), subs_.end(),
                                          [&](const auto& s) { return s->channel == status; });
    if (gatekeeper_.signing() && !hears_status)
      subscribe_raw(
          status, true, [](const void*, uint32_t) {}, kDefaultQueueCapacity, false);
  }
  if (!timers_.empty()) {
    int64_t next = timers_.front().next_utime;
    for (const auto& t : timers_) next = std::min(next, t.next_utime);
    // Rounded up: waking early would spin until the timer is due.
    const int64_t wait_ms = std::max<int64_t>(0, (next - steady_utime() + 999) / 1000);
    timeout_ms = static_cast<int>(std::min<int64_t>(timeout_ms, wait_ms));
  }
  // Messages read during the last spin's handlers are waiting already: no reason to wait.
  if (inbox_.size() > 0) timeout_ms = 0;
  int handled = 0;
  const int r = lcm_->handleTimeout(timeout_ms);
  // A signal (ours, or SIGCHLD) interrupting the wait is not an LCM failure.
  if (r < 0 && errno != EINTR) throw std::runtime_error(name_ + ": LCM handle failed");
  if (r > 0) handled = 1 + read_pending();
  // The messages waiting now, in arrival order. What arrives meanwhile is read into the inbox
  // after each handler (so LCM's silent queue stays short) and handled in the next spin, so
  // latest-only subscriptions and timers run even when input never stops.
  for (size_t n = inbox_.size(); n > 0; --n) {
    auto next = inbox_.pop();
    receipt_ = next->second.receipt;
    current_source_ = next->second.source;
    const std::vector<uint8_t> msg = std::move(next->second.bytes);
    next->second.sub->dispatch(msg.data(), static_cast<uint32_t>(msg.size()));
    handled += read_pending();
  }
  for (auto& s : subs_) {
    if (!s->has_pending) continue;
    s->has_pending = false;
    std::vector<uint8_t> msg;
    msg.swap(s->pending);
    receipt_ = s->pending_receipt;
    current_source_ = s->pending_source;
    s->dispatch(msg.data(), static_cast<uint32_t>(msg.size()));
  }
  // A wall clock that steps (NTP's first sync on a computer without a real-time clock, a hand-set
  // clock) is said and counted: stamps and signed commands are judged on it.
  const int64_t offset = wall_utime() - steady_utime();
  if (wall_minus_steady_us_ != 0 && std::abs(offset - wall_minus_steady_us_) > 500'000) {
    ++wall_clock_steps_;
    spdlog::warn("{}: the wall clock stepped by {:.3f} s", name_,
                 (offset - wall_minus_steady_us_) * 1e-6);
  }
  wall_minus_steady_us_ = offset;
  run_timers(steady_utime());
  return handled;
}

int Node::read_pending() {
  int n = 0;
  int r;
  while ((r = lcm_->handleTimeout(0)) > 0) ++n;
  if (r < 0 && errno != EINTR) throw std::runtime_error(name_ + ": LCM handle failed");
  return n;
}

int Node::run() {
  while (!stopping()) spin_once(100);
  spdlog::info("{}: shutting down", name_);
  return 0;
}

int run_node_main(const char* node_name, const std::function<int()>& body) {
  if (!retain_freed_memory())
    spdlog::warn("{}: glibc refused the heap settings: frame buffers page-fault in every frame",
                 node_name);
  try {
    return body();
  } catch (const ParamError& e) {
    spdlog::error("{}: configuration error: {}", node_name, e.what());
    return 2;
  } catch (const RemapError& e) {
    spdlog::error("{}: {}", node_name, e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("{}: {}", node_name, e.what());
    return 1;
  }
}

}  // namespace alight

// alight-link: chosen LCM channels between the vehicle's bus and a peer's bus (the operator's
// ground station on another computer) over one TCP connection, every frame authenticated
// (docs/link.md: the onboard bus never leaves the vehicle computer). Glue only: the
// protocol, what is sent when and which connections are kept are link/'s; this file owns the
// sockets, the clocks, LCM and the command line.
//
//   vehicle: alight-link --listen 0.0.0.0:7670 --key link.key --send AUTONOMY_STATUS,...
//                        --receive OPERATOR_CMD --max-rate CAMERA=2
//   ground:  alight-link --connect vehicle.local:7670 --key link.key --send OPERATOR_CMD
//                        --receive AUTONOMY_STATUS,...
//
// Messages read from the local bus pass its checks (Node: signature, second publisher, decoding)
// before they are sent; messages from the peer are published through this process's Node, so on
// the local bus they carry its origin trailer and bus signature like any other publisher's.
// NODE_STATUS reports the link as five inputs beside its channels (docs/link.md has the table):
//   link:rx       received: peer messages published; rejected_values: refused (not a --receive
//                 channel, not its channel's type); skipped: beyond --max-rate; rejected_auth:
//                 connections ended unauthenticated (another key, bad tag, reflected, counter,
//                 handshake timeout); decode_errors: connections ended for malformed bytes;
//                 dropped: pending handshakes pushed out by newer ones
//   link:tx       received: messages sent; skipped: replaced by a newer one or a full queue
//                 before their turn; dropped: no session, too large, or waiting when a session
//                 ended; rejected_values: not their channel's type
//   link:session  received: sessions authenticated; owner_changes: sessions ended;
//                 second_publisher: sessions replaced by a newer authenticated one; dropped:
//                 connection attempts that failed (connecting side)
//   link:bytes_sent, link:bytes_received   received: bytes over TCP (hellos and frames)

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/rand.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/node.hpp"
#include "common/operator_auth.hpp"
#include "common/params.hpp"
#include "link/cli.hpp"
#include "link/connections.hpp"
#include "link/options.hpp"
#include "link/payload.hpp"
#include "link/protocol.hpp"
#include "link/routing.hpp"

namespace {

using namespace alight;
using namespace alight::link;

// An idle link still says it is there, well within any --timeout the peer may use.
constexpr int64_t kKeepaliveUs = 250'000;
// The connecting side's retries: quick after a drop, at most every 5 s against a vehicle that is
// off or refuses us.
constexpr int64_t kRetryInitialUs = 200'000;
constexpr int64_t kRetryMaxUs = 5'000'000;
constexpr size_t kReadChunkBytes = 64 * 1024;
// Bytes read from one connection per loop: a fast peer cannot starve the bus side.
constexpr size_t kMaxReadPerTurn = 1u << 20;
// Unsent bytes the kernel may hold before the socket stops taking frames: the backlog a slow
// link can build behind the newest message (TCP_NOTSENT_LOWAT).
constexpr int kNotSentLowatBytes = 128 * 1024;
// kEvery channels (NODE_STATUS: a message per node per second; OPERATOR_CMD): what may wait.
constexpr size_t kEveryQueue = 64;

bool log_this(uint64_t n) { return n == 1 || n % 100 == 0; }

Nonce draw_nonce() {
  Nonce n{};
  if (RAND_bytes(n.data(), static_cast<int>(n.size())) != 1)
    throw std::runtime_error("RAND_bytes failed: no nonce for the link's handshake");
  return n;
}

std::string peer_name(const sockaddr_storage& a) {
  char host[INET6_ADDRSTRLEN] = "?";
  int port = 0;
  if (a.ss_family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&a);
    inet_ntop(AF_INET, &in->sin_addr, host, sizeof host);
    port = ntohs(in->sin_port);
    return std::string(host) + ":" + std::to_string(port);
  }
  if (a.ss_family == AF_INET6) {
    const auto* in = reinterpret_cast<const sockaddr_in6*>(&a);
    inet_ntop(AF_INET6, &in->sin6_addr, host, sizeof host);
    port = ntohs(in->sin6_port);
  }
  return "[" + std::string(host) + "]:" + std::to_string(port);
}

void tune_socket(int fd) {
  const int one = 1;
  // Status messages are small and must not wait for Nagle's algorithm.
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  const int lowat = kNotSentLowatBytes;
  setsockopt(fd, IPPROTO_TCP, TCP_NOTSENT_LOWAT, &lowat, sizeof lowat);
}

struct Connection {
  uint64_t id = 0;
  int fd = -1;
  std::string peer;
  Session session;
  bool connecting = false;  // connecting side: connect() under way
  bool was_open = false;
  std::deque<std::vector<uint8_t>> out;  // frames in the order sealed
  size_t out_offset = 0;                 // bytes of out.front() already sent
  int64_t started_us = 0;
  int64_t last_rx_us = 0;
  int64_t last_tx_us = 0;

  Connection(uint64_t id_, int fd_, std::string peer_, Session s, int64_t now)
      : id(id_),
        fd(fd_),
        peer(std::move(peer_)),
        session(std::move(s)),
        started_us(now),
        last_rx_us(now),
        last_tx_us(now) {}
};

struct Counters {
  uint64_t rx_published = 0, rx_not_listed = 0, rx_invalid = 0, rx_over_rate = 0;
  uint64_t auth_failures = 0, malformed = 0, evicted = 0, handshake_timeouts = 0;
  uint64_t tx_no_session = 0, tx_too_large = 0, tx_invalid = 0;
  uint64_t sessions = 0, sessions_ended = 0, replaced = 0, connect_failures = 0;
  uint64_t bytes_sent = 0, bytes_received = 0;
};

class Link {
 public:
  Link(const Options& o, bus::BusKey key, Node& node)
      : o_(o),
        key_(std::move(key)),
        node_(node),
        timeout_us_(static_cast<int64_t>(o.timeout_s * 1e6)),
        admission_(kMaxPendingHandshakes, timeout_us_),
        backoff_(kRetryInitialUs, kRetryMaxUs) {
    for (const auto& ch : o_.receive) filter_.allow(ch, rate(ch));
    for (const auto& ch : o_.send) {
      // Every NODE_STATUS (one per node) and every operator command counts; elsewhere only the
      // newest message does.
      const bool every = !channels::single_publisher(ch);
      outbox_.add_channel(ch, every ? SendMode::kEvery : SendMode::kNewest, kEveryQueue, rate(ch));
      const auto handler = [this, ch](const RawMessage& m) { on_local(ch, m); };
      if (every)
        node_.on<RawMessage>(ch, handler, kEveryQueue);
      else
        node_.on_latest<RawMessage>(ch, handler);
    }
  }

  ~Link() {
    for (auto& [id, c] : conns_) ::close(c->fd);
    if (listen_fd_ >= 0) ::close(listen_fd_);
  }

  int run() {
    if (o_.role == Role::kVehicle) open_listener();
    const int lcm_fd = node_.lcm().getFileno();
    std::vector<pollfd> fds;
    std::vector<uint64_t> ids;
    while (!node_.stopping()) {
      int64_t now = steady_utime();
      if (o_.role == Role::kGround && conns_.empty() && now >= next_attempt_us_) connect_peer(now);

      fds.clear();
      ids.clear();
      fds.push_back({lcm_fd, POLLIN, 0});
      if (listen_fd_ >= 0) fds.push_back({listen_fd_, POLLIN, 0});
      for (const auto& [id, c] : conns_) {
        short events = c->connecting ? POLLOUT : POLLIN;
        if (!c->out.empty()) events |= POLLOUT;
        fds.push_back({c->fd, events, 0});
        ids.push_back(id);
      }
      ::poll(fds.data(), fds.size(), wait_ms(now));
      now = steady_utime();

      node_.spin_once(0);  // local messages into the outbox, NODE_STATUS
      if (listen_fd_ >= 0 && (fds[1].revents & POLLIN)) accept_all(now);
      const size_t first = listen_fd_ >= 0 ? 2 : 1;
      for (size_t i = 0; i < ids.size(); ++i) {
        const auto it = conns_.find(ids[i]);
        if (it == conns_.end()) continue;  // closed meanwhile (replaced)
        service(*it->second, fds[first + i].revents, now);
      }
      fill_session(now);
      expire(now);
      report();
    }
    spdlog::info("alight-link: shutting down");
    return 0;
  }

 private:
  double rate(const std::string& ch) const {
    const auto it = o_.max_rate_hz.find(ch);
    return it == o_.max_rate_hz.end() ? 0.0 : it->second;
  }

  Connection* session() {
    if (!session_id_) return nullptr;
    const auto it = conns_.find(*session_id_);
    return it == conns_.end() ? nullptr : it->second.get();
  }

  // A message of a --send channel from the local bus (already judged by the Node).
  void on_local(const std::string& ch, const RawMessage& m) {
    if (!session()) {
      ++n_.tx_no_session;
      return;
    }
    if (!valid_payload(ch, m.bytes)) {
      ++n_.tx_invalid;
      node_.reject_value(ch, "not one well-formed " + channels::message_type(ch) + ": not sent");
      return;
    }
    if (data_frame_length(ch, m.bytes.size()) > o_.max_frame_bytes) {
      if (log_this(++n_.tx_too_large))
        spdlog::warn(
            "alight-link: {} message(s) too large to send (last: {} bytes on {}; "
            "--max-frame-bytes {})",
            n_.tx_too_large, m.bytes.size(), ch, o_.max_frame_bytes);
      return;
    }
    outbox_.offer(ch, m.bytes);
  }

  int wait_ms(int64_t now) const {
    int64_t until = now + 100'000;
    const auto earlier = [&](int64_t t) { until = std::min(until, t); };
    if (auto t = admission_.next_expiry_us()) earlier(*t);
    for (const auto& [id, c] : conns_) {
      if (c->session.open()) {
        // A keepalive waits behind a frame the socket has not taken yet (POLLOUT wakes us).
        if (c->out.empty()) earlier(c->last_tx_us + kKeepaliveUs);
        earlier(c->last_rx_us + timeout_us_);
      } else {
        earlier(c->started_us + timeout_us_);
      }
    }
    if (session_id_)
      if (auto t = outbox_.next_due_us(now)) earlier(*t);
    if (o_.role == Role::kGround && conns_.empty()) earlier(next_attempt_us_);
    // Rounded up: waking early would spin until the deadline.
    return static_cast<int>(std::max<int64_t>(0, (until - now + 999) / 1000));
  }

  void open_listener() {
    const std::string where = o_.endpoint.text();
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE;
    addrinfo* found = nullptr;
    const int rc = getaddrinfo(o_.endpoint.host.c_str(), std::to_string(o_.endpoint.port).c_str(),
                               &hints, &found);
    if (rc != 0)
      throw ParamError("", "--listen", where, std::string("cannot resolve: ") + gai_strerror(rc));
    std::string error = "no address";
    for (addrinfo* ai = found; ai && listen_fd_ < 0; ai = ai->ai_next) {
      const int fd =
          ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
      if (fd < 0) continue;
      const int one = 1;
      // A restarted link takes its port back at once, not after TIME_WAIT.
      setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
      if (::bind(fd, ai->ai_addr, ai->ai_addrlen) == 0 && ::listen(fd, 16) == 0) {
        listen_fd_ = fd;
      } else {
        error = std::strerror(errno);
        ::close(fd);
      }
    }
    freeaddrinfo(found);
    if (listen_fd_ < 0) throw ParamError("", "--listen", where, "cannot listen: " + error);
    spdlog::info("alight-link: vehicle side, listening on {}", where);
  }

  void accept_all(int64_t now) {
    for (;;) {
      sockaddr_storage addr{};
      socklen_t len = sizeof addr;
      const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len,
                               SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) {
        // EMFILE and the like: the next poll tries again; nothing to count per connection.
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
          spdlog::warn("alight-link: accept: {}", std::strerror(errno));
        return;
      }
      tune_socket(fd);
      const uint64_t id = next_id_++;
      auto c = std::make_unique<Connection>(
          id, fd, peer_name(addr), Session(key_, o_.role, draw_nonce(), o_.max_frame_bytes), now);
      spdlog::debug("alight-link: connection from {}", c->peer);
      const auto hello = c->session.hello();
      c->out.emplace_back(hello.begin(), hello.end());
      conns_[id] = std::move(c);
      if (const auto evicted = admission_.add(id, now)) {
        if (log_this(++n_.evicted))
          spdlog::warn(
              "alight-link: {} connection(s) dropped before their handshake ended: {} waited "
              "at once",
              n_.evicted, kMaxPendingHandshakes);
        drop(*evicted);
      }
      flush(*conns_.at(id), now);
    }
  }

  void connect_peer(int64_t now) {
    const std::string where = o_.endpoint.text();
    // getaddrinfo waits for a name server when HOST is a name; the launch files give an address.
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    const int rc = getaddrinfo(o_.endpoint.host.c_str(), std::to_string(o_.endpoint.port).c_str(),
                               &hints, &found);
    if (rc != 0) return connect_failed(now, std::string("cannot resolve: ") + gai_strerror(rc));
    int fd = -1;
    std::string error = "no address";
    for (addrinfo* ai = found; ai && fd < 0; ai = ai->ai_next) {
      fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
      if (fd < 0) continue;
      tune_socket(fd);
      if (::connect(fd, ai->ai_addr, ai->ai_addrlen) != 0 && errno != EINPROGRESS) {
        error = std::strerror(errno);
        ::close(fd);
        fd = -1;
      }
    }
    freeaddrinfo(found);
    if (fd < 0) return connect_failed(now, error);
    const uint64_t id = next_id_++;
    auto c = std::make_unique<Connection>(
        id, fd, where, Session(key_, o_.role, draw_nonce(), o_.max_frame_bytes), now);
    c->connecting = true;
    conns_[id] = std::move(c);
  }

  void connect_failed(int64_t now, const std::string& why) {
    const int64_t delay = backoff_.failed();
    next_attempt_us_ = now + delay;
    if (log_this(++n_.connect_failures) || n_.connect_failures <= 3)
      spdlog::warn("alight-link: cannot reach {}: {}; retrying in {:.1f} s ({} failures)",
                   o_.endpoint.text(), why, delay * 1e-6, n_.connect_failures);
  }

  void service(Connection& c, short revents, int64_t now) {
    if (c.connecting) {
      if (!(revents & (POLLOUT | POLLERR | POLLHUP))) return;
      int err = 0;
      socklen_t len = sizeof err;
      getsockopt(c.fd, SOL_SOCKET, SO_ERROR, &err, &len);
      if (err != 0) return close(c.id, std::string("connect: ") + std::strerror(err));
      c.connecting = false;
      c.started_us = c.last_rx_us = c.last_tx_us = now;
      spdlog::debug("alight-link: connected to {}, authenticating", c.peer);
      const auto hello = c.session.hello();
      c.out.emplace_back(hello.begin(), hello.end());
      flush(c, now);
      return;
    }
    if (revents & (POLLIN | POLLERR | POLLHUP))
      if (!receive(c, now)) return;
    if (!c.out.empty()) flush(c, now);
  }

  // Reads what the connection has (bounded per turn) and handles it. False: it was closed.
  bool receive(Connection& c, int64_t now) {
    std::vector<Message> messages;
    size_t taken = 0;
    while (taken < kMaxReadPerTurn) {
      const ssize_t n = ::recv(c.fd, buffer_.data(), buffer_.size(), 0);
      if (n == 0) {
        close(c.id, "the peer closed the connection");
        return false;
      }
      if (n < 0) {
        if (errno == EINTR) continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK) break;
        close(c.id, std::string("recv: ") + std::strerror(errno));
        return false;
      }
      taken += static_cast<size_t>(n);
      n_.bytes_received += static_cast<size_t>(n);
      c.last_rx_us = now;
      const bool was_open = c.session.open();
      const bool ok = c.session.feed({buffer_.data(), static_cast<size_t>(n)}, messages);
      // The frames before a failure were authentic: they are published.
      for (auto& m : messages) publish(std::move(m), now);
      messages.clear();
      if (!ok) {
        refuse(c);
        return false;
      }
      auto control = c.session.take_control();
      if (!control.empty()) c.out.push_back(std::move(control));
      if (!was_open && c.session.open()) authenticated(c);
      if (static_cast<size_t>(n) < buffer_.size()) break;
    }
    return true;
  }

  // A session failed: count and log why, end the connection.
  void refuse(Connection& c) {
    const Failure f = c.session.failure();
    const uint64_t n = is_auth_failure(f) ? ++n_.auth_failures : ++n_.malformed;
    const std::string what = std::string(is_auth_failure(f) ? "unauthenticated" : "malformed");
    // A genuine peer's failure is news; a stranger's, only now and then.
    if (c.was_open || log_this(n))
      spdlog::warn("alight-link: {} connection(s) refused as {} (last: {}: {}: {})", n, what,
                   c.peer, failure_name(f), c.session.error());
    close(c.id, "", /*logged=*/true);
  }

  // The peer's READY verified.
  void authenticated(Connection& c) {
    c.was_open = true;
    ++n_.sessions;
    if (o_.role == Role::kVehicle) {
      if (const auto previous = admission_.authenticated(c.id)) {
        ++n_.replaced;
        const auto it = conns_.find(*previous);
        spdlog::warn("alight-link: a new session from {} replaces the one from {}", c.peer,
                     it != conns_.end() ? it->second->peer : "?");
        close(*previous, "replaced by a newer authenticated session");
      }
    } else {
      backoff_.succeeded();
    }
    session_id_ = c.id;
    outbox_.clear();
    spdlog::info("alight-link: session open with {} ({} side): sending {}, receiving {}", c.peer,
                 role_name(o_.role == Role::kVehicle ? Role::kGround : Role::kVehicle),
                 list(o_.send), list(o_.receive));
  }

  static std::string list(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
    return s.empty() ? "nothing" : s;
  }

  // An authenticated peer's message: published when it is one of --receive, of its channel's
  // type and within its rate.
  void publish(Message&& m, int64_t now) {
    if (!filter_.allowed(m.channel)) {
      if (log_this(++n_.rx_not_listed))
        spdlog::warn(
            "alight-link: {} message(s) from the peer refused (last on {}: not a "
            "--receive channel)",
            n_.rx_not_listed, m.channel);
      return;
    }
    if (!valid_payload(m.channel, m.payload)) {
      if (log_this(++n_.rx_invalid))
        spdlog::warn(
            "alight-link: {} message(s) from the peer refused (last on {}: not one "
            "well-formed {})",
            n_.rx_invalid, m.channel, channels::message_type(m.channel));
      return;
    }
    if (filter_.check(m.channel, now) != Admit::kAccepted) {
      ++n_.rx_over_rate;
      return;
    }
    node_.publish_raw(node_.channel_name(m.channel), std::move(m.payload));
    ++n_.rx_published;
  }

  // Hands queued frames to the kernel; closes the connection on an error.
  void flush(Connection& c, int64_t now) {
    while (!c.out.empty()) {
      const auto& f = c.out.front();
      const ssize_t n = ::send(c.fd, f.data() + c.out_offset, f.size() - c.out_offset,
                               MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0) {
        if (errno == EINTR) continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK) return;
        return close(c.id, std::string("send: ") + std::strerror(errno));
      }
      n_.bytes_sent += static_cast<size_t>(n);
      c.out_offset += static_cast<size_t>(n);
      if (c.out_offset < f.size()) return;
      c.out.pop_front();
      c.out_offset = 0;
      c.last_tx_us = now;
    }
  }

  // The session's socket takes a new frame only when it has taken everything before: what waits
  // stays in the outbox, where a newer message replaces it.
  void fill_session(int64_t now) {
    Connection* c = session();
    if (!c) return;
    while (c->out.empty()) {
      auto item = outbox_.next(now);
      if (!item) break;
      c->out.push_back(c->session.seal_data(item->channel, item->payload));
      const uint64_t id = c->id;
      flush(*c, now);
      if (!conns_.count(id)) return;
    }
    if (c->out.empty() && now - c->last_tx_us >= kKeepaliveUs) {
      c->out.push_back(c->session.seal_keepalive());
      flush(*c, now);
    }
  }

  void expire(int64_t now) {
    for (const uint64_t id : admission_.expired(now)) {
      if (log_this(++n_.handshake_timeouts))
        spdlog::warn(
            "alight-link: {} connection(s) ended unauthenticated after {:.1f} s (last: "
            "{})",
            n_.handshake_timeouts, o_.timeout_s, conns_.at(id)->peer);
      close(id, "", /*logged=*/true);
    }
    std::vector<std::pair<uint64_t, std::string>> ends;
    for (const auto& [id, c] : conns_) {
      if (c->session.open() && now - c->last_rx_us > timeout_us_)
        ends.emplace_back(id, "nothing heard for " + std::to_string(o_.timeout_s) + " s");
      else if (o_.role == Role::kGround && !c->session.open() && now - c->started_us > timeout_us_)
        ends.emplace_back(id, c->connecting ? "connect timed out" : "handshake timed out");
    }
    for (const auto& [id, why] : ends) close(id, why);
  }

  // Ends a connection. `why` empty with `logged`: the caller has said why.
  void close(uint64_t id, const std::string& why, bool logged = false) {
    const auto it = conns_.find(id);
    if (it == conns_.end()) return;
    Connection& c = *it->second;
    const int64_t now = steady_utime();
    if (c.was_open) {
      ++n_.sessions_ended;
      const auto& s = c.session.stats();
      if (!logged)
        spdlog::warn(
            "alight-link: session with {} ended: {} ({:.0f} s, {} messages sent, {} "
            "received)",
            c.peer, why, (now - c.started_us) * 1e-6, s.data_sent, s.data_received);
    }
    if (session_id_ == id) {
      session_id_.reset();
      outbox_.clear();
    }
    if (o_.role == Role::kGround) {
      // Every end is followed by another attempt; one that never authenticated backs off.
      const int64_t delay = backoff_.failed();
      next_attempt_us_ = now + delay;
      if (!c.was_open && (++n_.connect_failures <= 3 || log_this(n_.connect_failures)) && !logged)
        spdlog::warn("alight-link: {}: {}; retrying in {:.1f} s ({} failures)", c.peer, why,
                     delay * 1e-6, n_.connect_failures);
    }
    ::close(c.fd);
    admission_.remove(id);
    conns_.erase(it);
  }

  void drop(uint64_t id) { close(id, "", /*logged=*/true); }

  void report() {
    ChannelStats rx;
    rx.received = n_.rx_published;
    rx.rejected_values = n_.rx_not_listed + n_.rx_invalid;
    rx.skipped = n_.rx_over_rate;
    rx.rejected_auth = n_.auth_failures + n_.handshake_timeouts;
    rx.decode_errors = n_.malformed;
    rx.dropped = n_.evicted;
    node_.set_input_stats("link:rx", rx);
    const OutboxStats o = outbox_.total();
    ChannelStats tx;
    tx.received = o.sent;
    tx.skipped = o.superseded + o.overflowed;
    tx.dropped = n_.tx_no_session + n_.tx_too_large + o.discarded;
    tx.rejected_values = n_.tx_invalid;
    node_.set_input_stats("link:tx", tx);
    ChannelStats s;
    s.received = n_.sessions;
    s.owner_changes = n_.sessions_ended;
    s.second_publisher = n_.replaced;
    s.dropped = n_.connect_failures;
    node_.set_input_stats("link:session", s);
    ChannelStats bytes;
    bytes.received = n_.bytes_sent;
    node_.set_input_stats("link:bytes_sent", bytes);
    bytes.received = n_.bytes_received;
    node_.set_input_stats("link:bytes_received", bytes);
  }

  Options o_;
  bus::BusKey key_;
  Node& node_;
  int64_t timeout_us_;
  Admission admission_;
  Backoff backoff_;
  Outbox outbox_;
  ReceiveFilter filter_;
  Counters n_;
  int listen_fd_ = -1;
  std::map<uint64_t, std::unique_ptr<Connection>> conns_;
  std::optional<uint64_t> session_id_;
  uint64_t next_id_ = 1;
  int64_t next_attempt_us_ = 0;
  std::vector<uint8_t> buffer_ = std::vector<uint8_t>(kReadChunkBytes);
};

}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-link", [&]() -> int {
    CLI::App app{
        "alight-link: chosen LCM channels between this bus and a peer's over one authenticated "
        "TCP connection (docs/link.md)"};
    NodeArgs args;
    args.add_to(app, false);
    RawOptions raw;
    std::string key_file;
    add_options(app, raw, key_file);
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();
    const Options options = parse_options(raw);
    bus::BusKey key;
    std::vector<std::string> warnings;
    try {
      key = bus::load_bus_key(key_file, &warnings);
    } catch (const KeyFileError& e) {
      throw ParamError("", "--key", key_file, e.what());
    }
    for (const auto& w : warnings) spdlog::warn("alight-link: {}", w);
    // Named by role: both links' NODE_STATUS end up on the operator's bus, where the ground
    // station keeps a row per node name.
    Node node(args, options.role == Role::kVehicle ? "alight-link-vehicle" : "alight-link-ground");
    Link link(options, std::move(key), node);
    return link.run();
  });
}

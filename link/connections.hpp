#pragma once
// Which connections alight-link keeps (docs/link.md). Pure: connections are ids the node hands
// out, times come from its steady clock.
//
// The listening side (the vehicle) serves one authenticated session at a time, and anyone on the
// network can connect. So connections that have not authenticated yet wait apart, each for at
// most the handshake timeout, and at most a few of them: a new one beyond that pushes the oldest
// out. A genuine handshake takes one round trip, so a stranger would have to open connections
// faster than that, for as long as he wants to block the link, to keep it out; holding a few
// silent ones open blocks nothing. An authenticated connection proved that it holds the key: it
// replaces the session in place (the ground station that lost its Wi-Fi and reconnects gets in
// at once, without waiting for the old session's silence timeout).

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace alight::link {

/// Connections waiting to authenticate at the same time, beyond which the oldest is dropped.
inline constexpr size_t kMaxPendingHandshakes = 8;

class Admission {
 public:
  Admission(size_t max_pending, int64_t handshake_timeout_us);

  /// A new connection at `now_us`. Returns the pending connection to drop to make room for it
  /// (the oldest), if any.
  std::optional<uint64_t> add(uint64_t id, int64_t now_us);
  /// Connection `id` authenticated: it is the session now. Returns the session it replaces.
  std::optional<uint64_t> authenticated(uint64_t id);
  /// Forgets a connection (closed, failed).
  void remove(uint64_t id);
  /// Pending connections whose handshake has taken longer than the timeout at `now_us`.
  std::vector<uint64_t> expired(int64_t now_us) const;
  /// When the oldest pending handshake expires (nullopt: none pending).
  std::optional<int64_t> next_expiry_us() const;

  std::optional<uint64_t> session() const { return session_; }
  size_t pending() const { return pending_.size(); }
  bool is_pending(uint64_t id) const { return pending_.count(id) > 0; }

 private:
  size_t max_pending_;
  int64_t timeout_us_;
  std::map<uint64_t, int64_t> pending_;  // id -> when it connected
  std::optional<uint64_t> session_;
};

/// The connecting side's delay between attempts: doubling from `initial_us` up to `max_us`, back
/// to the initial delay after a session that authenticated (a vehicle that went away and came
/// back is reached quickly; one that refuses us is not hammered).
class Backoff {
 public:
  Backoff(int64_t initial_us, int64_t max_us);
  /// An attempt failed or a session ended: the delay before the next attempt [us].
  int64_t failed();
  /// A session authenticated: the next failure waits the initial delay.
  void succeeded() { delay_us_ = initial_us_; }

 private:
  int64_t initial_us_;
  int64_t max_us_;
  int64_t delay_us_;
};

}  // namespace alight::link

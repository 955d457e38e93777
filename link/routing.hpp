#pragma once
// What alight-link sends, when, and what it takes from the peer (docs/link.md). Pure: the node
// passes the steady clock in.
//
// The outbox keeps, per channel, what waits for the TCP connection. The node takes a message from
// it only when the socket has taken everything before (and the kernel holds little unsent:
// TCP_NOTSENT_LOWAT), so a link slower than the bus never builds a backlog: a channel in kNewest
// mode keeps one message, replaced by each newer one, and the peer sees the newest camera frame,
// not one from seconds ago. Channels with many publishers whose every message counts (NODE_STATUS:
// one per node; OPERATOR_CMD) keep a short queue instead. Channels take turns, so images never
// hold back the status messages behind them. A rate limit per channel (images over Wi-Fi) holds
// its newest message until its turn comes.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace alight::link {

/// At most `max_rate_hz` messages per second on average; 0: no limit. A message sent late
/// (nothing to send at its time) moves the schedule rather than allowing a burst afterwards.
class RateLimit {
 public:
  explicit RateLimit(double max_rate_hz = 0);
  bool allows(int64_t now_us) const { return period_us_ == 0 || now_us >= next_us_; }
  /// Notes a message sent (or accepted) at `now_us`.
  void sent(int64_t now_us);
  /// When the next message is allowed [steady us].
  int64_t next_allowed_us() const { return next_us_; }
  bool limited() const { return period_us_ > 0; }

 private:
  int64_t period_us_ = 0;
  int64_t next_us_ = 0;
  bool started_ = false;
};

enum class SendMode {
  kNewest,  ///< one message waits; a newer one replaces it (superseded)
  kEvery,   ///< up to `capacity` wait in order; beyond it the oldest goes (overflowed)
};

struct OutboxStats {
  uint64_t offered = 0;
  uint64_t sent = 0;
  uint64_t superseded = 0;  ///< kNewest: replaced by a newer message before its turn
  uint64_t overflowed = 0;  ///< kEvery: dropped, the queue was full
  uint64_t discarded = 0;   ///< waiting when the session ended (clear())
};

class Outbox {
 public:
  /// Programmer invariant: each channel once, capacity >= 1, a validated rate.
  void add_channel(const std::string& channel, SendMode mode, size_t capacity = 1,
                   double max_rate_hz = 0);
  bool has_channel(const std::string& channel) const { return index_.count(channel) > 0; }
  /// A message to send on `channel` (one added before).
  void offer(const std::string& channel, std::vector<uint8_t> payload);

  struct Item {
    std::string channel;
    std::vector<uint8_t> payload;
  };
  /// The next message to send at `now_us`: the channels take turns, each when its rate allows.
  std::optional<Item> next(int64_t now_us);
  /// When a waiting message held back by its rate will be allowed (nullopt: none waits held
  /// back; a message that may go now is not "held back").
  std::optional<int64_t> next_due_us(int64_t now_us) const;
  /// Drops what waits (the session ended: nothing stale goes into the next one), counted.
  void clear();
  size_t waiting() const;

  const OutboxStats& stats(const std::string& channel) const;
  OutboxStats total() const;

 private:
  struct Channel {
    std::string name;
    SendMode mode = SendMode::kNewest;
    size_t capacity = 1;
    RateLimit rate;
    std::deque<std::vector<uint8_t>> waiting;
    OutboxStats stats;
  };
  std::vector<Channel> channels_;
  std::map<std::string, size_t> index_;
  size_t turn_ = 0;  // the channel to look at first
};

enum class Admit {
  kAccepted,
  kNotListed,  ///< not one of --receive
  kOverRate,   ///< beyond its --max-rate
};
const char* admit_name(Admit a);

/// Which channels the peer may publish on this bus, and how often.
class ReceiveFilter {
 public:
  /// Programmer invariant: a validated rate (0: no limit).
  void allow(const std::string& channel, double max_rate_hz = 0);
  bool allowed(const std::string& channel) const { return rates_.count(channel) > 0; }
  /// Whether a message on `channel` at `now_us` may be published; an accepted one uses up its
  /// rate's turn.
  Admit check(const std::string& channel, int64_t now_us);

 private:
  std::map<std::string, RateLimit> rates_;
};

}  // namespace alight::link

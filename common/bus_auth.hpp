#pragma once
// Who published a message on the LCM bus, and whether it may be believed. LCM authenticates
// nothing: anything that reaches a node's UDP port (multicast on a joined interface, or unicast to
// the port, which LCM 1.3.1's socket bound to INADDR_ANY also takes) is delivered. Every alight
// publisher therefore appends an origin trailer to the lcm-gen encoding of each message, and
// every alight subscriber judges it before decoding (docs/security.md).
//
// The trailer, in the spirit of MAVLink 2 message signing (a per-link secret, a timestamp that
// only moves forward, a truncated tag): 38 bytes after the encoded message, big-endian:
//   offset 0   uint64  source   random per publisher start (one per process's Node)
//   offset 8   uint64  counter  the publisher's bus time [us]: max(wall clock, newest counter it
//                               has accepted, its last counter + 1), so strictly increasing
//   offset 16  uint8   key_id   0: unsigned; else the id of the bus key that made the tag
//   offset 17  uint8   flags    0 (reserved)
//   offset 18  16 B    tag      HMAC-SHA256(key, "ALB1" channel 0x00 payload bytes 0..17 of the
//                               trailer) truncated to 16 bytes; zeros when unsigned
//   offset 34  4 B     magic    "ALB1"
// lcm-gen decoders of every language read a message's fields and ignore what follows, so
// lcm-spy, lcm-logger, lcm-logplayer and Python's decode() read trailed messages as they are.
//
// A receiver with a bus key refuses a message without a valid tag by that key, a counter that
// does not increase for its (channel, source), and a new source whose counter is more than
// kMaxStaleUs behind the bus time (a recording replayed later). With or without a key, a channel
// that one publisher owns (single_publisher) refuses messages from any other source while the
// owner is alive, and counts them: a second publisher is detected even when it signs nothing. An
// owner silent for longer than it ever pauses is taken to have restarted: its successor owns the
// channel. Pure: the caller passes the steady clock in.

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/bus_trailer.hpp"

namespace alight::bus {

inline constexpr size_t kTagBytes = 16;
/// A new source's counter may lag the bus time by this much (MAVLink 2 signing: one minute).
inline constexpr int64_t kMaxStaleUs = 60'000'000;
/// Refusals of a second publisher no further apart than this belong to one contest.
inline constexpr int64_t kContestGapUs = 2'000'000;
/// Sources remembered per channel (an attacker drawing new source ids must not grow memory).
inline constexpr size_t kMaxSourcesPerChannel = 8;

/// A shared secret and its id (1-255; 0 means unsigned on the wire).
struct BusKey {
  uint8_t id = 1;
  std::vector<uint8_t> bytes;  ///< at least 32 bytes
};

/// Reads a key file made by scripts/make-key (hex or raw, >= 32 bytes); throws KeyFileError
/// naming the file. The key id is the first byte of SHA-256 of the key, never 0, so a receiver
/// tells "signed with another key" from "signed with a bad tag". `warnings`: a file others can
/// read.
BusKey load_bus_key(const std::string& path, std::vector<std::string>* warnings = nullptr);
/// A key from bytes (id derived as above).
BusKey make_bus_key(std::vector<uint8_t> bytes);

struct Trailer {
  uint64_t source = 0;
  uint64_t counter = 0;
  uint8_t key_id = 0;
  uint8_t flags = 0;
  std::array<uint8_t, kTagBytes> tag{};
};

/// A received buffer: the lcm-gen payload and the trailer, if the buffer ends in one.
struct Received {
  std::span<const uint8_t> payload;
  std::optional<Trailer> trailer;
};
Received split(const void* data, size_t size);

/// The tag of `payload` on `channel` with the trailer's source, counter, key_id and flags.
std::array<uint8_t, kTagBytes> compute_tag(const BusKey& key, const std::string& channel,
                                           std::span<const uint8_t> payload, const Trailer& t);

/// Appends the origin trailer to each message a publisher sends.
class Sealer {
 public:
  /// `source`: this publisher's id (draw_source_id()); `key`: sign with it, or unsigned.
  Sealer(uint64_t source, std::optional<BusKey> key);
  /// Appends the trailer to `bytes` (an encoded message) for `channel`; `bus_time_us` is the
  /// publisher's clock (the counter never goes below it, and never repeats).
  void seal(std::vector<uint8_t>& bytes, const std::string& channel, int64_t bus_time_us);
  uint64_t source() const { return source_; }
  bool signing() const { return key_.has_value(); }
  uint64_t last_counter() const { return counter_; }

 private:
  uint64_t source_;
  std::optional<BusKey> key_;
  uint64_t counter_ = 0;
};

/// 64 random bits from the operating system, never 0 (0 stands for "no trailer").
uint64_t draw_source_id();

enum class Verdict {
  kAccepted,         ///< from the channel's owner (or a channel any source may publish on)
  kNewOwner,         ///< accepted: a first publisher, or the successor of a silent owner
  kUnsigned,         ///< refused: no tag, and this receiver has a key
  kWrongKey,         ///< refused: signed with a key this receiver does not have
  kBadTag,           ///< refused: the tag does not match (forged or altered)
  kReplayed,         ///< refused: counter not above the source's last on this channel
  kStale,            ///< refused: a new source far behind the bus time (a recording replayed)
  kSecondPublisher,  ///< refused: another source while the channel's owner is alive
};
const char* verdict_name(Verdict v);
inline bool accepted(Verdict v) { return v == Verdict::kAccepted || v == Verdict::kNewOwner; }

/// Per-channel figures a node reports (NODE_STATUS).
struct ChannelAuthStats {
  uint64_t rejected_auth = 0;                   ///< unsigned, wrong key, bad tag, replayed, stale
  uint64_t second_publisher = 0;                ///< messages refused from a second source
  uint64_t owner_changes = 0;                   ///< a silent owner replaced by another source
  int64_t last_second_publisher_steady_us = 0;  ///< 0: never
  /// First refusal of the current contest (refusals no further apart than kContestGapUs).
  int64_t contest_since_steady_us = 0;
  uint64_t owner = 0;  ///< the owner's source id (0: untrailed messages, or none yet)
};

class Gatekeeper {
 public:
  explicit Gatekeeper(std::optional<BusKey> key = std::nullopt) : key_(std::move(key)) {}

  /// Judges a received message on `channel` at `steady_us`. `single_publisher`: the channel has
  /// one owner (every flight channel); false for channels many nodes publish on (NODE_STATUS).
  Verdict check(const std::string& channel, const Received& msg, int64_t steady_us,
                bool single_publisher = true);

  /// The newest counter accepted on any channel (the bus time this node has heard), 0 before.
  int64_t bus_time_us() const { return bus_time_us_; }
  const ChannelAuthStats& stats(const std::string& channel) const;
  /// True while a second publisher was refused on `channel` within `window_us` before now.
  bool contested(const std::string& channel, int64_t steady_us, int64_t window_us) const;
  /// How long the current contest of `channel` has lasted (first to latest refusal, refusals
  /// no further apart than kContestGapUs) [us]; 0 when none is under way. One forged message
  /// is a contest of 0 s; a second publisher that keeps sending makes it grow.
  int64_t contest_span_us(const std::string& channel, int64_t steady_us) const;
  bool signing() const { return key_.has_value(); }
  /// Publishers remembered on `channel` (at most kMaxSourcesPerChannel).
  size_t known_sources(const std::string& channel) const;

 private:
  struct Source {
    uint64_t last_counter = 0;
    int64_t last_steady_us = 0;
    double interval_us = 0;  // smoothed spacing of its messages
    uint64_t n = 0;
  };
  struct Channel {
    std::map<uint64_t, Source> sources;
    std::optional<uint64_t> owner;
    ChannelAuthStats stats;
  };
  Verdict authenticate(const std::string& channel, const Received& msg) const;
  // How long the owner may be silent before another source may take the channel over.
  static int64_t silent_after_us(const Source& s);
  static void remember(Channel& c, uint64_t id, const Received& msg, int64_t steady_us);

  std::optional<BusKey> key_;
  std::map<std::string, Channel> channels_;
  int64_t bus_time_us_ = 0;
};

}  // namespace alight::bus

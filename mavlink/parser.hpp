#pragma once
// Streaming MAVLink parser: bytes in arbitrary chunks (a serial port's reads, UDP datagrams),
// frames out. Bytes that do not start a frame are dropped until the next start marker; a candidate
// frame of a known message is delivered only when its checksum (with the message's CRC_EXTRA)
// matches, and otherwise only its start marker is dropped, so a real frame inside a false start is
// still found. A candidate whose length claims more bytes than have come is given up as soon as a
// complete frame is found after its start marker, so a corrupted length byte delays nothing that
// has arrived. Every byte ends up counted: in a delivered frame, in a refused whole frame, or
// dropped.
//
// What is delivered:
//  - MAVLink 2 frames of the messages in messages.hpp, checksum correct, no incompatibility flag
//    but signing; a payload longer than alight's definition (extensions added after it) is
//    delivered and its extra bytes ignored, as the protocol demands of older receivers (counted;
//    ParserOptions::refuse_longer_than_known refuses it instead);
//  - MAVLink 1 frames of those messages at least as long as the message's base length (MAVLink 1
//    does not truncate; extension fields after the base are read) (ParserOptions::accept_v1);
//  - with a signing key: correctly signed frames from streams whose timestamp increases, and
//    unsigned frames only if ParserOptions::accept_unsigned (signing.hpp); without a key, signed
//    frames unverified (counted).
// Frames of unknown messages cannot be checked (no CRC_EXTRA): such a frame is skipped whole when
// another frame starts right after it and no frame of a known message starts inside it; otherwise
// its start marker is taken for noise.
//
// Pure: no I/O, no clock (observe_time() passes the receiver's clock in for signing).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "mavlink/frame.hpp"
#include "mavlink/signing.hpp"

namespace alight::mavlink {

struct ParserOptions {
  std::optional<SigningKey> key;          ///< verify signatures with this key
  bool accept_unsigned = false;           ///< with a key: deliver unsigned frames too
  bool accept_v1 = true;                  ///< deliver MAVLink 1 frames of known messages
  bool refuse_longer_than_known = false;  ///< refuse payloads longer than alight's definition
};

struct ParserStats {
  uint64_t bytes_in = 0;
  uint64_t bytes_delivered = 0;     ///< in delivered frames
  uint64_t bytes_skipped = 0;       ///< in whole frames refused or skipped
  uint64_t bytes_dropped = 0;       ///< noise and false starts dropped while resynchronising
  uint64_t frames_ok = 0;           ///< delivered
  uint64_t frames_v1 = 0;           ///< of which MAVLink 1
  uint64_t crc_errors = 0;          ///< candidate frames of known messages with a wrong checksum
  uint64_t unknown_ids = 0;         ///< whole frames of messages alight does not know, skipped
  uint64_t v1_skipped = 0;          ///< MAVLink 1 frames skipped (accept_v1 off)
  uint64_t bad_length = 0;          ///< MAVLink 1 frames shorter than the message's base length
  uint64_t longer_than_known = 0;   ///< payloads longer than alight's definition
  uint64_t incompat_flags = 0;      ///< candidate frames with incompatibility flags alight lacks
  uint64_t signature_failures = 0;  ///< signed frames whose signature is not the key's
  uint64_t replays = 0;             ///< correctly signed, but not newer than their stream
                                    ///< (or a new stream more than a minute behind)
  uint64_t unsigned_refused = 0;    ///< unsigned frames refused because a key is configured
  uint64_t signed_unverified = 0;   ///< signed frames delivered without a key to check them
};

class Parser {
 public:
  explicit Parser(ParserOptions options = {});

  /// Appends received bytes; call next() until it returns false after each push.
  void push(std::span<const uint8_t> bytes);
  /// The next complete frame, or false when more bytes are needed.
  bool next(Frame& out);

  /// The receiver's wall clock, for signing: a new stream more than a minute behind it is
  /// refused. Never lowers the receiver's timestamp.
  void observe_time(int64_t now_unix_utime);
  /// Forgets buffered bytes (after a reconnect); they are counted as dropped.
  void clear();

  const ParserStats& stats() const { return stats_; }
  size_t buffered() const { return buf_.size() - head_; }
  const SignedStreams& streams() const { return streams_; }

 private:
  enum class Step { kNeedMore, kDelivered, kContinue };
  enum class Probe { kNo, kYes, kNeedMore };
  /// Whether a complete frame of a known message with a correct checksum starts at p.
  Probe probe_known_frame(const uint8_t* p, size_t avail) const;
  Step parse_v2(const uint8_t* p, size_t avail, Frame& out);
  Step parse_v1(const uint8_t* p, size_t avail, Frame& out);
  Step undecided(const uint8_t* p, size_t avail);
  Step skip_uncheckable(const uint8_t* p, size_t avail, size_t total, uint64_t& counter);
  /// False (and the frame counted and skipped) when the signing policy refuses it.
  bool signing_allows(const uint8_t* p, size_t total, bool is_signed, Frame& out);
  void drop(size_t n);
  void skip(size_t n);

  ParserOptions options_;
  ParserStats stats_;
  SignedStreams streams_;
  std::vector<uint8_t> buf_;
  size_t head_ = 0;  // first unparsed byte in buf_
  // undecided(): where to resume probing start markers for the candidate that began after
  // scan_consumed_ bytes (those before scan_from_ were judged for good).
  uint64_t scan_consumed_ = UINT64_MAX;
  size_t scan_from_ = 1;
};

}  // namespace alight::mavlink

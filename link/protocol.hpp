#pragma once
// The alight-link wire protocol (docs/link.md): LCM messages of chosen channels carried between
// the vehicle's bus and a peer's bus over one TCP connection, every frame authenticated. Pure: no
// sockets, no clock, no LCM; the node draws the nonce, moves the bytes and keeps the time.
//
// Both sides open with a hello (24 bytes, integers big-endian as everywhere below):
//   offset 0   4 B     magic "ALK1" (the protocol and its version)
//   offset 4   uint8   role: 1 vehicle (listens), 2 ground (connects)
//   offset 5   uint8   key id: first byte of SHA-256 of the link key, never 0 (bus_auth's key id;
//                      tells "the peer has another key" apart from a forged frame)
//   offset 6   2 B     zero (reserved)
//   offset 8   16 B    nonce: fresh random bytes for this connection
// session key = HMAC-SHA256(link key, "alight-link session" | vehicle nonce | ground nonce).
// Both nonces are new for every connection, so nothing recorded from an earlier one verifies in
// a later one, whichever side the recording is played to.
//
// Then frames:
//   offset 0   uint32  length of the rest of the frame
//   offset 4   uint8   type: 1 READY, 2 DATA, 3 KEEPALIVE
//   offset 5   uint8   direction: the sender's role, so a frame reflected back to its sender
//                      (same session key both ways) is refused
//   offset 6   uint64  counter: 0 for READY, then exactly +1 per frame
//   offset 14  uint8   channel length C: 1..63 for DATA (LCM's limit), 0 otherwise
//   offset 15  C B     channel: its name in the code (common/channels.hpp, before --remap)
//   15 + C             payload: the lcm-gen encoding without the bus's origin trailer (DATA only)
//   last 16 B          tag: HMAC-SHA256(session key, every byte of the frame before it), truncated
// The first frame each side sends is READY; its tag proves that the sender holds the link key
// (key confirmation), and nothing else is taken before it, so a peer without the key is never
// sent a message and never has one published. TCP delivers every byte once and in order: a
// counter other than the previous + 1 is a frame replayed, dropped or reordered by someone on the
// path, not a network accident. Every failure (a bad hello, a length beyond the bound, a bad tag,
// a counter, a malformed frame) ends the connection: there is no resynchronising on a byte
// stream someone has written into, and the genuine peer reconnects within a second.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/bus_auth.hpp"

namespace alight::link {

enum class Role : uint8_t { kVehicle = 1, kGround = 2 };
const char* role_name(Role r);

inline constexpr size_t kNonceBytes = 16;
inline constexpr size_t kHelloBytes = 24;
inline constexpr size_t kTagBytes = 16;
inline constexpr size_t kSessionKeyBytes = 32;
inline constexpr std::array<uint8_t, 4> kHelloMagic = {'A', 'L', 'K', '1'};
/// LCM_MAX_CHANNEL_NAME_LENGTH in lcm/lcm.h.
inline constexpr size_t kMaxChannelBytes = 63;
/// Bytes of a frame after its length field besides channel and payload: type, direction,
/// counter, channel length, tag.
inline constexpr size_t kFrameOverhead = 1 + 1 + 8 + 1 + kTagBytes;
/// READY and KEEPALIVE frames: the overhead alone.
inline constexpr size_t kControlFrameLength = kFrameOverhead;
/// Largest frame length a receiver takes unless told otherwise: a 1920x1080 RGB image_t (6.2 MB)
/// fits, and an authenticated peer can make it hold no more than this.
inline constexpr size_t kDefaultMaxFrameBytes = 8u << 20;
/// Bounds of --max-frame-bytes: a NODE_STATUS of every node must fit; a frame is held whole
/// before its tag is checked.
inline constexpr size_t kMinMaxFrameBytes = 4096;
inline constexpr size_t kMaxMaxFrameBytes = 256u << 20;

using Nonce = std::array<uint8_t, kNonceBytes>;
using SessionKey = std::array<uint8_t, kSessionKeyBytes>;

enum class FrameType : uint8_t { kReady = 1, kData = 2, kKeepalive = 3 };

/// Why a connection was ended. The first group is refused as unauthenticated, the second as
/// malformed (NODE_STATUS counts them apart: docs/link.md).
enum class Failure {
  kNone,
  kOtherKey,    ///< the peer's hello names another key id
  kBadTag,      ///< a frame's tag does not match (forged, altered, another session, wrong key)
  kReflected,   ///< a valid frame sent in our own direction: our frame played back to us
  kBadCounter,  ///< not the previous counter + 1: replayed, dropped or reordered
  kBadHello,    ///< not an alight-link hello (magic, reserved bytes, role)
  kSameRole,    ///< both sides claim the same role (two vehicles, or two ground links)
  kSameNonce,   ///< the peer echoed our nonce
  kOversized,   ///< a length beyond the bound (or beyond a READY's before READY)
  kMalformed,   ///< a length, type, channel or payload that no valid frame has
  kOutOfOrder,  ///< something other than READY first, or a second READY
};
const char* failure_name(Failure f);
/// True for the failures that mean "this peer does not hold our key or forged a frame".
bool is_auth_failure(Failure f);

struct Hello {
  Role role = Role::kVehicle;
  uint8_t key_id = 0;
  Nonce nonce{};
};
std::array<uint8_t, kHelloBytes> encode_hello(const Hello& h);
/// The hello in `bytes` (exactly kHelloBytes), or nullopt and *why (kBadHello).
std::optional<Hello> parse_hello(std::span<const uint8_t> bytes, Failure* why);

SessionKey derive_session_key(const bus::BusKey& link_key, const Nonce& vehicle,
                              const Nonce& ground);

/// A whole frame, length field first. Programmer invariant: `channel` is empty except for DATA,
/// at most kMaxChannelBytes.
std::vector<uint8_t> seal_frame(const SessionKey& key, FrameType type, Role direction,
                                uint64_t counter, const std::string& channel,
                                std::span<const uint8_t> payload);
/// The frame length (the value of its length field) of a DATA frame.
inline size_t data_frame_length(const std::string& channel, size_t payload_bytes) {
  return kFrameOverhead + channel.size() + payload_bytes;
}

/// True when `name` can travel as a channel: 1..63 characters that an LCM subscription's regular
/// expression matches literally (letters, digits, '_', '-', '/'), as parse_remaps demands.
bool valid_channel_name(std::span<const uint8_t> name);

/// One LCM message received from the peer.
struct Message {
  std::string channel;
  std::vector<uint8_t> payload;
};

struct SessionStats {
  uint64_t frames_sent = 0;  ///< every frame, control ones included
  uint64_t bytes_sent = 0;   ///< frames (the hello aside)
  uint64_t data_sent = 0;
  uint64_t frames_received = 0;  ///< frames that passed every check
  uint64_t bytes_received = 0;   ///< every byte fed, including those of a refused frame
  uint64_t data_received = 0;
};

/// One connection's protocol, either side. The node sends hello(), then whatever take_control()
/// holds, then frames sealed here, in the order it got them; it feeds every byte it reads.
class Session {
 public:
  /// `nonce`: fresh random bytes (RAND_bytes), one per connection. `max_frame_bytes`: the
  /// largest frame length taken from the peer (and the largest this side may seal).
  Session(bus::BusKey link_key, Role role, const Nonce& nonce,
          size_t max_frame_bytes = kDefaultMaxFrameBytes);

  /// The first bytes to send on the connection.
  std::array<uint8_t, kHelloBytes> hello() const;
  /// Takes received bytes. DATA frames that passed every check are appended to `out` (an
  /// authenticated peer's messages; still untrusted as values). Returns false once the session
  /// has failed (now or before): failure() and error() say why; end the connection. Holds at most
  /// one incomplete hello or frame (bounded by max_frame_bytes; a READY's size before READY).
  bool feed(std::span<const uint8_t> bytes, std::vector<Message>& out);
  /// Bytes the session needs sent now (its READY, once the peer's hello came), then empty.
  std::vector<uint8_t> take_control();

  /// The peer's READY verified: it holds the key. Only now may DATA be sealed and received.
  bool open() const { return state_ == State::kOpen; }
  bool failed() const { return failure_ != Failure::kNone; }
  Failure failure() const { return failure_; }
  const std::string& error() const { return error_; }
  Role role() const { return role_; }

  /// Whether a DATA frame of this channel and payload size fits max_frame_bytes.
  bool fits(const std::string& channel, size_t payload_bytes) const {
    return data_frame_length(channel, payload_bytes) <= max_frame_bytes_;
  }
  /// A DATA frame. Programmer invariant: open(), take_control() called since the hello, a valid
  /// channel name, fits().
  std::vector<uint8_t> seal_data(const std::string& channel, std::span<const uint8_t> payload);
  /// A KEEPALIVE frame, so the peer knows this side is there when it has nothing to say.
  /// Programmer invariant: open().
  std::vector<uint8_t> seal_keepalive();

  const SessionStats& stats() const { return stats_; }

 private:
  enum class State { kHello, kReady, kOpen };
  bool fail(Failure f, std::string why);
  // Handles the complete unit in unit_ (hello or frame); false on failure.
  bool handle_hello();
  bool handle_frame(std::vector<Message>& out);
  std::vector<uint8_t> seal(FrameType type, const std::string& channel,
                            std::span<const uint8_t> payload);
  size_t frame_bound() const;

  bus::BusKey key_;
  Role role_;
  Nonce nonce_;
  size_t max_frame_bytes_;
  State state_ = State::kHello;
  Failure failure_ = Failure::kNone;
  std::string error_;
  SessionKey session_key_{};
  std::vector<uint8_t> control_;  // READY, until taken
  bool control_taken_ = false;
  uint64_t next_send_counter_ = 0;
  uint64_t next_receive_counter_ = 0;
  // The unit being read: the hello, or a frame (its length field, then the rest).
  std::vector<uint8_t> unit_;
  size_t unit_need_ = kHelloBytes;
  bool have_length_ = false;
  SessionStats stats_;
};

}  // namespace alight::link

#pragma once
// MAVLink 2 frames (mavlink.io/en/guide/serialization.html, "MAVLink 2 Packet Format"):
//
//   0xFD len incompat_flags compat_flags seq sysid compid msgid(3, LE) payload(len) crc(2, LE)
//   [link_id timestamp(6, LE) signature(6)]   when incompat_flags has 0x01 (signing.hpp)
//
// The checksum is CRC-16/MCRF4XX over every byte after 0xFD up to the end of the payload, then
// the message's CRC_EXTRA. A MAVLink 1 frame (0xFE len seq sysid compid msgid(1) payload crc) has
// the same checksum and no flags, extensions or truncation; the parser reads those too.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "mavlink/messages.hpp"
#include "mavlink/signing.hpp"

namespace alight::mavlink {

inline constexpr uint8_t kStxV2 = 0xFD;
inline constexpr uint8_t kStxV1 = 0xFE;
inline constexpr size_t kHeaderLengthV2 = 10;
inline constexpr size_t kHeaderLengthV1 = 6;
inline constexpr size_t kChecksumLength = 2;
inline constexpr size_t kMaxPayloadLength = 255;
inline constexpr size_t kMaxFrameLength =
    kHeaderLengthV2 + kMaxPayloadLength + kChecksumLength + kSignatureLength;  // 280

struct Signature {
  uint8_t link_id = 0;
  uint64_t timestamp = 0;  ///< 10 us units since 2015-01-01 UTC
  std::array<uint8_t, 6> value{};
};

/// One received frame.
struct Frame {
  uint8_t version = 2;  ///< 2 (0xFD) or 1 (0xFE)
  uint8_t incompat_flags = 0;
  uint8_t compat_flags = 0;
  uint8_t seq = 0;
  uint8_t sysid = 0;
  uint8_t compid = 0;
  uint32_t msgid = 0;
  uint8_t payload_length = 0;  ///< as received (MAVLink 2 senders drop trailing zeros)
  std::array<uint8_t, kMaxPayloadLength> payload{};  ///< zero past payload_length
  uint16_t checksum = 0;
  std::optional<Signature> signature;  ///< signed frames
  bool signature_verified = false;     ///< a key was configured and the signature matched it
};

/// The typed message in a frame; nullopt when the frame holds another message.
template <class M>
std::optional<M> decode(const Frame& f) {
  if (f.msgid != M::kId) return std::nullopt;
  return decode_payload<M>(f.payload.data());
}

/// Decodes a frame of a known message and calls f(message) with the typed message; false (and
/// f not called) when alight does not know the frame's message.
template <class F>
bool dispatch(const Frame& f, F&& fn) {
  bool known = false;
  for_each_message_type([&](auto tag) {
    using M = decltype(tag);
    if (!known && f.msgid == M::kId) {
      known = true;
      fn(decode_payload<M>(f.payload.data()));
    }
  });
  return known;
}

/// One encoded frame, ready to write.
struct FrameBytes {
  std::array<uint8_t, kMaxFrameLength> data;
  size_t size = 0;
  std::span<const uint8_t> bytes() const { return {data.data(), size}; }
};

/// Header fields a sender chooses.
struct FrameHeader {
  uint8_t seq = 0;
  uint8_t sysid = 0;
  uint8_t compid = 0;
  uint8_t compat_flags = 0;
};

/// Signs with `key` as link `link_id` at `timestamp` (10 us since 2015).
struct SignWith {
  const SigningKey* key;
  uint8_t link_id;
  uint64_t timestamp;
};

/// A MAVLink 2 frame around `payload_length` bytes of payload, exactly as given (truncation is
/// encode_payload's job), signed when `sign` is given. Returns the frame's length.
size_t write_frame(const FrameHeader& header, uint32_t msgid, uint8_t crc_extra,
                   const uint8_t* payload, uint8_t payload_length,
                   const std::optional<SignWith>& sign, uint8_t* out /* kMaxFrameLength */);

/// A MAVLink 1 frame (tests and peers that still speak it): msgid < 256, the full base payload.
size_t write_frame_v1(const FrameHeader& header, uint8_t msgid, uint8_t crc_extra,
                      const uint8_t* payload, uint8_t payload_length, uint8_t* out);

struct SigningConfig {
  SigningKey key{};
  uint8_t link_id = 0;
};

/// Encodes messages from one system / component: sequence numbers, and signing timestamps that
/// increase by at least one per frame whatever the clock does.
class Sender {
 public:
  Sender(uint8_t sysid, uint8_t compid, std::optional<SigningConfig> signing = std::nullopt)
      : sysid_(sysid), compid_(compid), signing_(signing) {}

  /// One frame of `m`; `now_unix_utime` (the sender's wall clock) stamps signed frames.
  template <class M>
  FrameBytes pack(const M& m, int64_t now_unix_utime) {
    std::array<uint8_t, M::kMaxLength> payload;
    const uint8_t n = encode_payload(m, payload.data());
    return pack_payload(M::kId, M::kCrcExtra, payload.data(), n, now_unix_utime);
  }
  FrameBytes pack_payload(uint32_t msgid, uint8_t crc_extra, const uint8_t* payload,
                          uint8_t payload_length, int64_t now_unix_utime);

  uint8_t next_seq() const { return seq_; }
  bool signing() const { return signing_.has_value(); }
  /// The last signing timestamp used (0 before the first signed frame).
  uint64_t signing_timestamp() const { return last_timestamp_; }
  /// Never sign below this (e.g. a timestamp kept across restarts, or a peer's newer one).
  void raise_signing_timestamp(uint64_t timestamp) {
    if (timestamp > last_timestamp_) last_timestamp_ = timestamp;
  }

 private:
  uint8_t sysid_, compid_;
  uint8_t seq_ = 0;
  std::optional<SigningConfig> signing_;
  uint64_t last_timestamp_ = 0;
};

}  // namespace alight::mavlink

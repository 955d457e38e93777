#pragma once
// MAVLink 2 message signing (mavlink.io/en/guide/message_signing.html). A signed frame has
// incompatibility flag 0x01 and 13 more bytes after the checksum: link id (1 byte), timestamp
// (6 bytes, little-endian, 10 us units since 2015-01-01 00:00 UTC) and the first 6 bytes of
// SHA-256(secret key (32 bytes) + header + payload + checksum + link id + timestamp).
//
// Receiving: a stream is (sysid, compid, link id); its timestamps must increase. A frame whose
// timestamp is not newer than its stream's last accepted one is a replay and is refused (the
// spec only demands "not smaller"; equal stamps never come from a conforming sender, which adds
// at least 1 per frame). A stream's first frame is refused when it is more than one minute
// behind the receiver's timestamp (the newest accepted, or the one its clock gives).
//
// Pure: SHA-256 from OpenSSL's libcrypto; every time is passed in.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <unordered_map>

namespace alight::mavlink {

using SigningKey = std::array<uint8_t, 32>;

inline constexpr size_t kSignatureLength = 13;    ///< link id + timestamp + signature bytes
inline constexpr uint8_t kIncompatSigned = 0x01;  ///< MAVLINK_IFLAG_SIGNED
/// 2015-01-01 00:00:00 UTC in microseconds since the Unix epoch.
inline constexpr int64_t kSigningEpochUnixUtime = 1'420'070'400'000'000;
/// One minute in signing-timestamp units (10 us): how far a new stream may lag.
inline constexpr uint64_t kNewStreamMaxLag = 6'000'000;
inline constexpr uint64_t kMaxSigningTimestamp = (uint64_t{1} << 48) - 1;

/// Signing timestamp (10 us since 2015) of a Unix time in microseconds; 0 before 2015.
uint64_t signing_timestamp_from_unix_utime(int64_t unix_utime);

/// The key as Mission Planner and QGroundControl derive it from a passphrase: SHA-256(passphrase).
SigningKey signing_key_from_passphrase(std::string_view passphrase);
/// A key from 64 hex digits (surrounding white space ignored); nullopt otherwise.
std::optional<SigningKey> signing_key_from_hex(std::string_view hex);

/// The 6 signature bytes of a frame: `frame` holds header, payload, checksum, link id and
/// timestamp (everything up to the signature bytes).
std::array<uint8_t, 6> compute_signature(const SigningKey& key, const uint8_t* frame, size_t n);

/// True when `value` (6 bytes) is the signature of the `n` bytes at `frame` (constant time).
bool signature_matches(const SigningKey& key, const uint8_t* frame, size_t n, const uint8_t* value);

/// Timestamps of the streams a receiver has accepted signed frames from.
class SignedStreams {
 public:
  enum class Verdict { kAccepted, kReplay, kTooOld };

  /// Judges (and, when accepted, records) a correctly signed frame's timestamp.
  Verdict accept(uint8_t sysid, uint8_t compid, uint8_t link_id, uint64_t timestamp);
  /// Raises the receiver's timestamp (never lowers it), e.g. from its clock.
  void observe(uint64_t timestamp) {
    if (timestamp > local_timestamp_) local_timestamp_ = timestamp;
  }
  uint64_t local_timestamp() const { return local_timestamp_; }
  size_t stream_count() const { return last_.size(); }

 private:
  std::unordered_map<uint32_t, uint64_t> last_;  // (sysid << 16 | compid << 8 | link) -> stamp
  uint64_t local_timestamp_ = 0;
};

}  // namespace alight::mavlink

#pragma once
// Authentication of operator commands (channel OPERATOR_CMD): LCM itself has none, so anything on
// the network could otherwise command the vehicle. Shared by the ground station (sign) and
// autonomy (verify); pure except load_key_file(), which reads the key file.
//
// Tag: HMAC-SHA256 (RFC 2104 / FIPS 198-1 with SHA-256, test vectors RFC 4231) computed with
// OpenSSL over canonical_bytes(cmd), keyed with a secret shared by the ground station and the
// vehicle (a key file of >= 32 bytes).
//
// Canonical byte string: exactly the LCM wire encoding of the fields utime .. nudge_W of
// operator_cmd_t, in declaration order, big-endian, without the 8-byte type fingerprint:
//   offset 0   int64  utime           8 bytes, big-endian two's complement
//   offset 8   int64  seq             8 bytes, big-endian two's complement
//   offset 16  int32  Ls = len(sender) + 1, big-endian
//   offset 20  sender bytes (Ls - 1), then one 0x00
//   20 + Ls    int32  Lv = len(vehicle_id) + 1, big-endian
//   24 + Ls    vehicle_id bytes (Lv - 1), then one 0x00
//   24+Ls+Lv   int64  session         8 bytes, big-endian two's complement
//   32+Ls+Lv   int8   command
//   33+Ls+Lv   int8   mission
//   34+Ls+Lv   3 x IEEE-754 binary64 nudge_W[0..2], big-endian each (24 bytes)
//   total      58 + Ls + Lv bytes
// `auth` and `hmac` are not covered (auth must be AUTH_HMAC_SHA256 for a command to be
// accepted at all). Because it equals LCM's own encoding, a verifier in any language can take
// the bytes straight from the received message.
//
// Binding: the tag covers the vehicle's id, so vehicles sharing a key no longer obey
// each other's commands, and the session nonce that the verifier draws from the operating
// system's random source at every start of autonomy and announces in AUTONOMY_STATUS, so a
// command recorded before a restart of autonomy is refused after it (the new verifier has no
// sequence history, but it has a new session). Within a session, replay protection is the
// sequence number: seq must be strictly greater than the last accepted seq of the same sender;
// and utime must be within a window of the verifier's clock. The ground station starts its seq
// at the wall time in microseconds so it increases across ground-station restarts too.

#include <alight/operator_cmd_t.hpp>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/command_reject.hpp"

namespace alight {

/// Shared secret. At least kMinKeyBytes long.
struct OperatorKey {
  std::vector<uint8_t> bytes;
};
inline constexpr size_t kMinKeyBytes = 32;
using HmacTag = std::array<uint8_t, 32>;

/// Bad key file: missing, unreadable, too short, malformed. The message names the file.
class KeyFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LoadedKey {
  OperatorKey key;
  std::vector<std::string> warnings;  ///< e.g. "readable by other users"; the node logs them
};

/// Key from a file's contents: hex (>= 64 hex digits, optional surrounding whitespace) when the
/// contents are hex digits only, else the raw bytes (>= 32). `origin` names the source in errors.
OperatorKey parse_key(const std::string& contents, const std::string& origin);
/// Reads and parses a key file; warns when the file is readable or writable by group or others.
LoadedKey load_key_file(const std::string& path);

/// `bytes` random bytes from the operating system (OpenSSL RAND_bytes) as lowercase hex: a key
/// file's contents (scripts/make-key writes the same form).
std::string random_key_hex(size_t bytes = 32);

/// HMAC-SHA256 of `data` with `key` (any length; RFC 4231 uses 4 to 131 bytes).
HmacTag hmac_sha256(const uint8_t* key, size_t key_len, const uint8_t* data, size_t data_len);
HmacTag hmac_sha256(const std::vector<uint8_t>& key, const std::vector<uint8_t>& data);

/// The bytes the tag covers (layout above).
std::vector<uint8_t> canonical_bytes(const operator_cmd_t& cmd);
/// Sets auth = AUTH_HMAC_SHA256 and hmac = tag over canonical_bytes(cmd).
void sign(operator_cmd_t& cmd, const OperatorKey& key);
/// True when auth = AUTH_HMAC_SHA256 and the tag matches (constant-time comparison).
bool signature_valid(const operator_cmd_t& cmd, const OperatorKey& key);

/// Outcome of CommandVerifier::check.
struct CommandVerdict {
  using Reason = CommandReject;
  static constexpr int kReasonCount = kCommandRejectCount;
  Reason reason = Reason::kNone;
  bool accepted() const { return reason == Reason::kNone; }
};

/// A fresh session nonce for a CommandVerifier: 63 random bits from OpenSSL's RAND_bytes (seeded
/// by the operating system, never by the vehicle's configured seed), never 0. Not pure: the
/// node draws it once at start and passes it to the verifier.
int64_t draw_session_nonce();

/// Accepts an operator command only when it is signed with the shared key, names this vehicle
/// and this session, is fresh and new. Used by autonomy on every OPERATOR_CMD; the node passes
/// its current time in. Pure.
class CommandVerifier {
 public:
  /// `vehicle_id`: the id commands must name. `session`: this run's nonce (draw_session_nonce;
  /// not 0). `max_age_us`: largest |now - cmd.utime| accepted (covers clock offset between the
  /// ground station and the vehicle plus link delay).
  CommandVerifier(OperatorKey key, std::string vehicle_id, int64_t session,
                  int64_t max_age_us = 2'000'000);

  /// Checks in order unsigned, bad signature, wrong vehicle, wrong session, stale, replayed;
  /// remembers seq only when accepted, so a rejected message cannot block later genuine ones.
  CommandVerdict check(const operator_cmd_t& cmd, int64_t now_utime);

  const std::string& vehicle_id() const { return vehicle_id_; }
  int64_t session() const { return session_; }
  uint64_t n_rejected() const { return n_rejected_; }
  uint64_t n_rejected(CommandVerdict::Reason reason) const {
    return by_reason_[static_cast<size_t>(reason)];
  }
  /// seq and reason of the last rejected command (-1 and kNone when none was rejected).
  int64_t last_rejected_seq() const { return last_rejected_seq_; }
  CommandVerdict::Reason last_reject_reason() const { return last_reject_reason_; }
  /// Last accepted seq of `sender`, or INT64_MIN when none was accepted.
  int64_t last_seq(const std::string& sender) const;

 private:
  OperatorKey key_;
  std::string vehicle_id_;
  int64_t session_;
  int64_t max_age_us_;
  std::map<std::string, int64_t> last_seq_;  // per sender; only signed senders get an entry
  uint64_t n_rejected_ = 0;
  std::array<uint64_t, CommandVerdict::kReasonCount> by_reason_{};
  int64_t last_rejected_seq_ = -1;
  CommandVerdict::Reason last_reject_reason_ = CommandVerdict::Reason::kNone;
};

/// Why a kill authority (the operator's signed CMD_KILL carried in POSITION_SETPOINT and
/// ATTITUDE_CMD, position_setpoint_t.kill_authority) was or was not accepted.
enum class KillCheck {
  kAuthorised,
  kNoKey,         ///< this process has no operator key: no KILL can be authorised
  kNotKill,       ///< empty, or another command
  kUnsigned,      ///< auth is not AUTH_HMAC_SHA256
  kBadSignature,  ///< the tag does not match the operator key
  kWrongVehicle,  ///< signed for another vehicle
  kStale,         ///< further than max_age from the checker's time
};
const char* kill_check_name(KillCheck c);

/// Checks, in every process that can stop the motors (outer loop, simulator, alight-mavlink),
/// that a disarm in the air comes from the operator: the CMD_KILL must be signed with the
/// operator key and name this vehicle, and be fresh when first seen. The carrier repeats the
/// same command with every message after the KILL: once authorised, that command (sender, seq,
/// tag) stays authorised however old. No session check: only autonomy knows its session. Pure.
class KillVerifier {
 public:
  KillVerifier(std::optional<OperatorKey> key, std::string vehicle_id, int64_t max_age_us);
  KillCheck check(const operator_cmd_t& cmd, int64_t now_utime);
  bool has_key() const { return key_.has_value(); }

 private:
  std::optional<OperatorKey> key_;
  std::string vehicle_id_;
  int64_t max_age_us_;
  std::optional<operator_cmd_t> authorised_;
};

}  // namespace alight

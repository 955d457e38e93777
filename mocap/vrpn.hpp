#pragma once
// The VRPN wire protocol as a tracker client needs it: the protocol VICON Tracker, OptiTrack
// Motive and Qualisys QTM serve poses with. Written from VRPN's protocol
// description (Format_Of_Protocol.txt) and the facts of its reference implementation
// (vrpn_Connection.C, vrpn_Tracker.C in github.com/vrpn/vrpn), where the two differ:
//
// - Each peer first sends a 24-byte cookie: "vrpn: ver. MM.mm", two spaces, the remote log mode
//   it requests as an ASCII digit '0'..'3', then NULs. Peers whose cookies agree up to the last
//   '.' (the major version) talk; a different minor version is only noted.
// - Then messages. A header of five big-endian 32-bit words, padded to 24 bytes: length,
//   timestamp seconds, timestamp microseconds, sender id, type id (the padding word carries a
//   sequence number that no receiver reads). The length is 24 + the payload's length; the
//   description says the padded length, but the implementation writes the unpadded one and every
//   receiver rounds it up itself. The payload follows, zero-padded to a multiple of 8 bytes.
// - Ids are the sender's own. Negative types are system messages: -1 describes a sender and -2 a
//   type (header sender field = the id described; payload = big-endian int32 length of the name
//   including its NUL, then the name and the NUL); -3 offers a UDP port, -4 asks for remote
//   logging, -5 marks a disconnect in logs. A message of a type id >= 0 means nothing until that
//   type and its sender have been described.
// - "vrpn_Tracker Pos_Quat": int32 sensor, 4 bytes of padding, float64 position[3], float64
//   quaternion[4] in x, y, z, w order (64 bytes). "vrpn_Tracker Velocity" and
//   "vrpn_Tracker Acceleration": sensor, padding, float64 v[3], float64 q[4], float64 dt (72
//   bytes). Numbers are big-endian IEEE 754.
// - Transport here is TCP only: the client connects to the server's port (3883 by default) and
//   never offers a UDP port, so the server sends everything over that one connection (VRPN's
//   "tcp://" client form, which servers accept on their listening port). The older UDP "lob"
//   request, where the server connects back to the client, is not implemented.
//
// Pure: no sockets, no clock. Every length, id and name from the peer is checked before use; a
// refused message is counted and skipped, and only a broken frame (a length that cannot be a
// message) makes the stream unusable, since TCP gives no way to find the next message after it.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace alight::mocap::vrpn {

inline constexpr int kDefaultPort = 3883;
/// The version this client announces; servers of any 07.xx accept it.
inline constexpr const char* kMagic = "vrpn: ver. 07.35";
inline constexpr size_t kMagicLength = 16;
inline constexpr size_t kCookieBytes = 24;
inline constexpr size_t kHeaderBytes = 24;
inline constexpr size_t kAlign = 8;
/// Longest payload accepted [bytes]. VRPN's own TCP buffers hold 64000 bytes, so no server sends
/// more in one message; tracker messages are 64 and 72 bytes.
inline constexpr size_t kMaxPayloadBytes = 65536;
/// Longest sender or type name including its NUL (VRPN's vrpn_CNAME).
inline constexpr size_t kMaxNameBytes = 100;
/// Ids a peer may describe: 0 .. kMaxIds - 1 (VRPN allows 2000 senders and 2000 types).
inline constexpr int32_t kMaxIds = 4096;

inline constexpr int32_t kSenderDescription = -1;
inline constexpr int32_t kTypeDescription = -2;
inline constexpr int32_t kUdpDescription = -3;
inline constexpr int32_t kLogDescription = -4;
inline constexpr int32_t kDisconnectMessage = -5;

inline constexpr const char* kPosQuatType = "vrpn_Tracker Pos_Quat";
inline constexpr const char* kVelocityType = "vrpn_Tracker Velocity";
inline constexpr const char* kAccelerationType = "vrpn_Tracker Acceleration";
inline constexpr size_t kPosQuatBytes = 64;
inline constexpr size_t kVelocityBytes = 72;

/// `n` rounded up to a multiple of kAlign.
constexpr size_t padded(size_t n) { return (n + kAlign - 1) / kAlign * kAlign; }

// --- Cookie -------------------------------------------------------------------------------------

/// Our cookie: kMagic, two spaces, the log mode digit, NULs.
std::array<uint8_t, kCookieBytes> make_cookie(int remote_log_mode = 0);

enum class CookieVerdict {
  kOk,            ///< same version
  kMinorDiffers,  ///< same major version, other minor: talk (VRPN only notes it)
  kBadMagic,      ///< not a VRPN peer, or another major version
  kBadLogMode,    ///< log mode not '0'..'3'
};
struct CookieCheck {
  CookieVerdict verdict = CookieVerdict::kBadMagic;
  std::string version;  ///< the peer's "MM.mm" (printable characters only)
  int log_mode = 0;     ///< the remote logging the peer asks of us (we never log)
  bool usable() const {
    return verdict == CookieVerdict::kOk || verdict == CookieVerdict::kMinorDiffers;
  }
};
/// Judges the peer's 24 cookie bytes.
CookieCheck check_cookie(const uint8_t* cookie);

// --- Encoding (the client's greeting; tests) -----------------------------------------------------

/// Appends one framed message: header, payload, zero padding to kAlign.
void append_message(std::vector<uint8_t>& out, int32_t type, int32_t sender, uint32_t sec,
                    uint32_t usec, const uint8_t* payload, size_t size, uint32_t sequence = 0);
/// Payload of a sender or type description: int32 length with NUL, name, NUL.
std::vector<uint8_t> name_payload(const std::string& name);

void put_u32(std::vector<uint8_t>& out, uint32_t v);
void put_f64(std::vector<uint8_t>& out, double v);
uint32_t get_u32(const uint8_t* p);
double get_f64(const uint8_t* p);

// --- Decoding ---------------------------------------------------------------------------------

/// One tracker message, as the server sent it (room frame, room units).
struct TrackerReport {
  enum class Kind { kPose, kVelocity, kAcceleration };
  Kind kind = Kind::kPose;
  std::string tracker;  ///< the sender's name, e.g. "Pelican"
  int32_t sensor = 0;
  int64_t stamp_us = 0;       ///< header timestamp [us since the server's epoch]
  std::array<double, 3> v{};  ///< position / velocity / acceleration [room units (/s, /s^2)]
  std::array<double, 4> q_xyzw{0, 0, 0, 1};  ///< orientation / its rate quaternion, x y z w
  double dt_s = 0;                           ///< Velocity / Acceleration: the interval q spans [s]
};

/// What the stream held. Every refusal has its counter; nothing is dropped silently.
struct DecoderStats {
  uint64_t bytes = 0;     ///< bytes fed, cookie included
  uint64_t messages = 0;  ///< complete frames read
  uint64_t sender_descriptions = 0;
  uint64_t type_descriptions = 0;
  uint64_t poses = 0;           ///< Pos_Quat reports decoded
  uint64_t velocities = 0;      ///< Velocity reports decoded
  uint64_t accelerations = 0;   ///< Acceleration reports decoded
  uint64_t other_messages = 0;  ///< described types a tracker client has no use for
  uint64_t system_ignored = 0;  ///< UDP and log descriptions, disconnect, unknown system types
  // Refused; the frame was intact, so the stream goes on.
  uint64_t bad_descriptions = 0;  ///< id out of range, name length inconsistent or too long
  uint64_t undescribed = 0;       ///< type or sender id never described
  uint64_t bad_payloads = 0;      ///< tracker message of the wrong size
  uint64_t bad_stamps = 0;        ///< microseconds outside [0, 1e6)
  // Fatal: the stream cannot be read past this.
  uint64_t framing_errors = 0;  ///< a length that cannot be a message
  uint64_t cookie_errors = 0;   ///< not a VRPN peer, or another major version

  /// Messages refused, framing intact.
  uint64_t refused() const { return bad_descriptions + undescribed + bad_payloads + bad_stamps; }
};

/// Reads a server's byte stream, arriving in chunks of any size, into tracker reports.
class StreamDecoder {
 public:
  /// Feeds the next bytes of the stream. Appends the tracker reports they completed to `out`.
  /// Returns false once the stream is unusable (bad cookie, broken frame); later calls do nothing.
  bool feed(const uint8_t* data, size_t size, std::vector<TrackerReport>& out);

  bool failed() const { return failed_; }
  /// Why the stream is unusable ("" while it is not).
  const std::string& error() const { return error_; }
  bool cookie_received() const { return cookie_received_; }
  const CookieCheck& cookie() const { return cookie_; }
  /// Bytes of a message (or cookie) begun but not complete: what a closed connection truncated.
  size_t pending_bytes() const { return buffer_.size() - start_; }
  const DecoderStats& stats() const { return stats_; }
  /// Name the peer gave a type or sender id ("" when undescribed).
  std::string type_name(int32_t id) const;
  std::string sender_name(int32_t id) const;

 private:
  enum class TypeKind { kPose, kVelocity, kAcceleration, kOther };
  struct Type {
    std::string name;
    TypeKind kind = TypeKind::kOther;
  };
  bool fail(std::string why);
  /// Handles one complete frame at `p` (header + padded payload).
  void handle(const uint8_t* p, size_t payload_size, std::vector<TrackerReport>& out);
  void describe(int32_t type, int32_t id, const uint8_t* payload, size_t size);
  void tracker(const Type& type, const std::string& sender, uint32_t sec, uint32_t usec,
               const uint8_t* payload, size_t size, std::vector<TrackerReport>& out);

  std::vector<uint8_t> buffer_;
  size_t start_ = 0;  // first unread byte of buffer_
  bool cookie_received_ = false;
  bool failed_ = false;
  std::string error_;
  CookieCheck cookie_;
  std::unordered_map<int32_t, std::string> senders_;
  std::unordered_map<int32_t, Type> types_;
  DecoderStats stats_;
};

}  // namespace alight::mocap::vrpn

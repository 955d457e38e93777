#pragma once
// Operator commands from the web page to OPERATOR_CMD (paper 4.1: the operator commands take-off
// and "go"; alight adds abort, land here, kill and position nudges), and who may send them.
// Pure: the node passes in the time, the key and the request's headers.

#include <alight/autonomy_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>

#include "common/operator_auth.hpp"

namespace alight::ground_station {

/// One command as the page asks for it.
struct CommandRequest {
  int8_t command = operator_cmd_t::CMD_NONE;
  int8_t mission = 0;                      ///< target_t.MISSION_* (CMD_GO only)
  std::array<double, 3> nudge_W{0, 0, 0};  ///< CMD_NUDGE only [m]
};

/// "takeoff", "go", "abort", "land_here", "kill", "nudge" <-> CMD_*.
std::optional<int8_t> command_from_name(const std::string& name);
const char* command_name(int8_t command);

/// Parses the form fields of POST /api/command: command=NAME, for go mission=landing|ingress,
/// for nudge dx, dy, dz [m] each within +-nudge_max_m. Kill needs confirm=kill, so a stray
/// keypress or a replayed form without it cannot kill the motors.
struct ParsedCommand {
  std::optional<CommandRequest> request;
  std::string error;  ///< why not, when request is empty
};
ParsedCommand parse_command_request(const std::map<std::string, std::string>& fields,
                                    double nudge_max_m);

/// Builds signed operator_cmd_t messages of one sender for one vehicle, with strictly
/// increasing seq.
class CommandBuilder {
 public:
  CommandBuilder(std::string sender, OperatorKey key, std::string vehicle_id);
  /// Signs for `session`, the nonce the vehicle's verifier announced in AUTONOMY_STATUS (a
  /// command signed for another session is refused there). seq = max(previous + 1, now_utime):
  /// increasing within a run and across restarts of the ground station.
  operator_cmd_t build(const CommandRequest& request, int64_t session, int64_t now_utime);
  const std::string& sender() const { return sender_; }
  const std::string& vehicle_id() const { return vehicle_id_; }

 private:
  std::string sender_;
  OperatorKey key_;
  std::string vehicle_id_;
  int64_t last_seq_ = 0;
};

/// What became of a command the station sent ("sent" alone said nothing about whether
/// the vehicle heard it).
enum class AckState {
  kSent,             ///< on LCM, no answer yet, deadline not passed
  kAcknowledged,     ///< AUTONOMY_STATUS echoed it as accepted (last_cmd_seq)
  kRejected,         ///< AUTONOMY_STATUS named it as rejected (last_rejected_seq), with a reason
  kNotAcknowledged,  ///< no answer within the deadline: the operator must not assume it acted
};
const char* ack_state_name(AckState s);
/// Text of autonomy_status_t.REJECT_*.
const char* reject_reason_name(int8_t reason);

struct TrackedCommand {
  std::string name;
  int64_t seq = 0;
  int64_t session = 0;
  int64_t sent_utime = 0;            ///< station clock [us]
  AckState state = AckState::kSent;  ///< as of the last status; see CommandTracker::state_at
  int64_t answered_utime = 0;        ///< when acknowledged or rejected (station clock) [us]
  std::string reject_reason;
  int32_t rejected_at_send = -1;  ///< vehicle's cmds_rejected when sent (-1: unknown)
};

/// The station's command state machine: SENT -> ACKNOWLEDGED | REJECTED, or NOT ACKNOWLEDGED
/// once `ack_timeout_s` passed without an answer (a late answer still moves it on). Pure: the
/// station passes the time and every AUTONOMY_STATUS in.
///
/// Autonomy echoes only the last accepted seq, so a command followed quickly by another may never
/// be echoed itself. Sequence numbers of one sender are strictly increasing and the verifier
/// accepts only increasing ones, so when a later command of ours is echoed and the vehicle's
/// rejection count has not moved since ours was sent, ours was accepted too; otherwise it stays
/// unanswered (and alarms), never guessed.
class CommandTracker {
 public:
  explicit CommandTracker(double ack_timeout_s, size_t kept = 20);
  void sent(const std::string& name, int64_t seq, int64_t session, int64_t now_utime);
  void on_status(const autonomy_status_t& status, int64_t now_utime);
  /// State at `now_utime` (kSent turns into kNotAcknowledged after the deadline).
  AckState state_at(const TrackedCommand& c, int64_t now_utime) const;
  const std::deque<TrackedCommand>& commands() const { return commands_; }
  /// The newest command, when it is NOT ACKNOWLEDGED at `now_utime` (the page's alarm).
  const TrackedCommand* alarm(int64_t now_utime) const;

 private:
  int64_t ack_timeout_us_;
  size_t kept_;
  std::deque<TrackedCommand> commands_;
  int32_t vehicle_rejected_ = -1;  // cmds_rejected of the newest status
  int64_t vehicle_session_ = 0;
};

/// Who may command: the web server's policy, fixed at start.
struct AccessPolicy {
  bool require_token = true;  ///< every command request needs the token in X-Alight-Token
  std::string token;          ///< session token printed at start
  bool loopback_only = true;  ///< bound to a loopback address: Host must name it
};
/// Policy for a bind address: the token is always required (on loopback it was not,
/// and any web page could post commands); on a loopback address the Host must name it too.
AccessPolicy policy_for_bind(const std::string& bind_address, std::string token);
bool is_loopback_address(const std::string& address);

enum class Access { kAllowed, kMissingToken, kBadToken, kCrossOrigin, kBadHost };
const char* access_name(Access a);
/// Decides whether a command request may pass. `headers` are the request's (lower-case names
/// not required). Besides the token rule this refuses cross-site requests (an Origin that is
/// not the page's own host) so a web page in the operator's browser cannot command the vehicle,
/// and on loopback a Host other than a loopback name (DNS rebinding).
Access check_command_access(const AccessPolicy& policy,
                            const std::multimap<std::string, std::string>& headers);

/// Hex text of `bytes` (for the session token from a random source).
std::string to_hex(const uint8_t* bytes, size_t n);

}  // namespace alight::ground_station

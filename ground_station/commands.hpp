#pragma once
// Operator commands from the web page to OPERATOR_CMD (paper 4.1: the operator commands take-off
// and "go"; alight adds abort, land here, kill and position nudges), and who may send them.
// Pure: the node passes in the time, the key and the request's headers.

#include <alight/operator_cmd_t.hpp>
#include <array>
#include <cstdint>
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

/// Builds signed operator_cmd_t messages of one sender with strictly increasing seq.
class CommandBuilder {
 public:
  CommandBuilder(std::string sender, OperatorKey key);
  /// seq = max(previous + 1, now_utime): increasing within a run and across restarts of the
  /// ground station (the vehicle remembers the last seq per sender).
  operator_cmd_t build(const CommandRequest& request, int64_t now_utime);
  const std::string& sender() const { return sender_; }

 private:
  std::string sender_;
  OperatorKey key_;
  int64_t last_seq_ = 0;
};

/// Who may command: the web server's policy, fixed at start.
struct AccessPolicy {
  bool require_token = false;  ///< serving other hosts: every command request needs the token
  std::string token;           ///< session token printed at start
  bool loopback_only = true;   ///< bound to a loopback address: Host must name it
};
/// Policy for a bind address: a token is required unless it is a loopback address.
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

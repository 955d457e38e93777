#include "ground_station/commands.hpp"

#include <openssl/crypto.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>

namespace alight::ground_station {

namespace {

struct NamedCommand {
  const char* name;
  int8_t command;
};
constexpr NamedCommand kCommands[] = {
    {"takeoff", operator_cmd_t::CMD_TAKEOFF}, {"go", operator_cmd_t::CMD_GO},
    {"abort", operator_cmd_t::CMD_ABORT},     {"land_here", operator_cmd_t::CMD_LAND_HERE},
    {"kill", operator_cmd_t::CMD_KILL},       {"nudge", operator_cmd_t::CMD_NUDGE},
};

// Mission codes of target_t (MISSION_LANDING = 1, MISSION_INGRESS = 2).
constexpr int8_t kMissionLanding = 1;
constexpr int8_t kMissionIngress = 2;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

const std::string* header(const std::multimap<std::string, std::string>& headers,
                          const std::string& name_lower) {
  for (const auto& [k, v] : headers)
    if (lower(k) == name_lower) return &v;
  return nullptr;
}

// "host:port" of an Origin "scheme://host:port".
std::string origin_authority(const std::string& origin) {
  const auto p = origin.find("://");
  return lower(p == std::string::npos ? origin : origin.substr(p + 3));
}

// Host part of a Host header value ("127.0.0.1:8080", "[::1]:8080", "localhost").
std::string host_name(const std::string& host) {
  if (!host.empty() && host[0] == '[') {
    const auto close = host.find(']');
    return lower(host.substr(1, close == std::string::npos ? std::string::npos : close - 1));
  }
  return lower(host.substr(0, host.find(':')));
}

}  // namespace

std::optional<int8_t> command_from_name(const std::string& name) {
  for (const auto& c : kCommands)
    if (name == c.name) return c.command;
  return std::nullopt;
}

const char* command_name(int8_t command) {
  for (const auto& c : kCommands)
    if (command == c.command) return c.name;
  return "none";
}

ParsedCommand parse_command_request(const std::map<std::string, std::string>& fields,
                                    double nudge_max_m) {
  auto get = [&](const std::string& k) -> const std::string* {
    auto it = fields.find(k);
    return it == fields.end() ? nullptr : &it->second;
  };
  ParsedCommand out;
  const std::string* name = get("command");
  if (!name) return {std::nullopt, "missing field 'command'"};
  const auto command = command_from_name(*name);
  if (!command) return {std::nullopt, "unknown command '" + *name + "'"};
  CommandRequest req;
  req.command = *command;
  if (*command == operator_cmd_t::CMD_GO) {
    const std::string* m = get("mission");
    if (!m) return {std::nullopt, "go needs mission=landing or mission=ingress"};
    if (*m == "landing") {
      req.mission = kMissionLanding;
    } else if (*m == "ingress") {
      req.mission = kMissionIngress;
    } else {
      return {std::nullopt, "unknown mission '" + *m + "' (landing or ingress)"};
    }
  }
  if (*command == operator_cmd_t::CMD_KILL) {
    const std::string* confirm = get("confirm");
    if (!confirm || *confirm != "kill") return {std::nullopt, "kill needs confirm=kill"};
  }
  if (*command == operator_cmd_t::CMD_NUDGE) {
    const char* keys[3] = {"dx", "dy", "dz"};
    for (int i = 0; i < 3; ++i) {
      const std::string* v = get(keys[i]);
      if (!v) continue;
      char* end = nullptr;
      const double d = std::strtod(v->c_str(), &end);
      if (v->empty() || *end != '\0' || !std::isfinite(d) || std::abs(d) > nudge_max_m)
        return {std::nullopt, std::string("nudge ") + keys[i] + " = '" + *v +
                                  "': must be a number within +-" + std::to_string(nudge_max_m)};
      req.nudge_W[i] = d;
    }
  }
  out.request = req;
  return out;
}

CommandBuilder::CommandBuilder(std::string sender, OperatorKey key, std::string vehicle_id)
    : sender_(std::move(sender)), key_(std::move(key)), vehicle_id_(std::move(vehicle_id)) {
  if (key_.bytes.size() < kMinKeyBytes)
    throw KeyFileError("CommandBuilder: key shorter than " + std::to_string(kMinKeyBytes) +
                       " bytes");
}

operator_cmd_t CommandBuilder::build(const CommandRequest& request, int64_t session,
                                     int64_t now_utime) {
  operator_cmd_t cmd{};
  cmd.utime = now_utime;
  last_seq_ = std::max(last_seq_ + 1, now_utime);
  cmd.seq = last_seq_;
  cmd.sender = sender_;
  cmd.vehicle_id = vehicle_id_;
  cmd.session = session;
  cmd.command = request.command;
  cmd.mission = request.command == operator_cmd_t::CMD_GO ? request.mission : 0;
  for (int i = 0; i < 3; ++i)
    cmd.nudge_W[i] = request.command == operator_cmd_t::CMD_NUDGE ? request.nudge_W[i] : 0.0;
  sign(cmd, key_);
  return cmd;
}

const char* ack_state_name(AckState s) {
  switch (s) {
    case AckState::kSent:
      return "sent";
    case AckState::kAcknowledged:
      return "acknowledged";
    case AckState::kRejected:
      return "rejected";
    case AckState::kNotAcknowledged:
      return "not_acknowledged";
  }
  return "unknown";
}

const char* reject_reason_name(int8_t reason) {
  switch (reason) {
    case autonomy_status_t::REJECT_UNSIGNED:
      return "unsigned";
    case autonomy_status_t::REJECT_BAD_SIGNATURE:
      return "bad signature (key?)";
    case autonomy_status_t::REJECT_STALE:
      return "stale (clock offset?)";
    case autonomy_status_t::REJECT_REPLAYED:
      return "replayed";
    case autonomy_status_t::REJECT_WRONG_VEHICLE:
      return "wrong vehicle id";
    case autonomy_status_t::REJECT_WRONG_SESSION:
      return "wrong session (autonomy restarted?)";
  }
  return "rejected";
}

CommandTracker::CommandTracker(double ack_timeout_s, size_t kept)
    : ack_timeout_us_(static_cast<int64_t>(std::llround(ack_timeout_s * 1e6))), kept_(kept) {}

void CommandTracker::sent(const std::string& name, int64_t seq, int64_t session,
                          int64_t now_utime) {
  TrackedCommand c;
  c.name = name;
  c.seq = seq;
  c.session = session;
  c.sent_utime = now_utime;
  c.rejected_at_send = vehicle_session_ == session ? vehicle_rejected_ : -1;
  commands_.push_back(std::move(c));
  while (commands_.size() > kept_) commands_.pop_front();
}

void CommandTracker::on_status(const autonomy_status_t& st, int64_t now_utime) {
  vehicle_rejected_ = st.cmds_rejected;
  vehicle_session_ = st.cmd_session;
  // Is the echoed accepted seq one of ours (of this session)?
  bool echoed_is_ours = false;
  for (const auto& c : commands_)
    echoed_is_ours |= c.seq == st.last_cmd_seq && c.session == st.cmd_session;
  for (auto& c : commands_) {
    if (c.state == AckState::kAcknowledged || c.state == AckState::kRejected) continue;
    if (c.session != st.cmd_session) continue;  // answers of another run say nothing of it
    if (st.last_cmd_seq == c.seq) {
      c.state = AckState::kAcknowledged;
    } else if (st.last_rejected_seq == c.seq) {
      c.state = AckState::kRejected;
      c.reject_reason = reject_reason_name(st.last_reject_reason);
    } else if (echoed_is_ours && st.last_cmd_seq > c.seq && c.rejected_at_send >= 0 &&
               st.cmds_rejected == c.rejected_at_send) {
      c.state = AckState::kAcknowledged;  // a later one of ours was accepted, nothing rejected
    } else {
      continue;
    }
    c.answered_utime = now_utime;
  }
}

AckState CommandTracker::state_at(const TrackedCommand& c, int64_t now_utime) const {
  if (c.state == AckState::kSent && now_utime - c.sent_utime > ack_timeout_us_)
    return AckState::kNotAcknowledged;
  return c.state;
}

const TrackedCommand* CommandTracker::alarm(int64_t now_utime) const {
  if (commands_.empty()) return nullptr;
  const TrackedCommand& newest = commands_.back();
  return state_at(newest, now_utime) == AckState::kNotAcknowledged ? &newest : nullptr;
}

bool is_loopback_address(const std::string& address) {
  const std::string a = lower(address);
  if (a == "localhost" || a == "::1" || a == "[::1]") return true;
  // 127.0.0.0/8, dotted quad only.
  int parts[4];
  char tail;
  if (std::sscanf(a.c_str(), "%d.%d.%d.%d%c", &parts[0], &parts[1], &parts[2], &parts[3], &tail) !=
      4)
    return false;
  for (int p : parts)
    if (p < 0 || p > 255) return false;
  return parts[0] == 127;
}

AccessPolicy policy_for_bind(const std::string& bind_address, std::string token) {
  AccessPolicy p;
  p.loopback_only = is_loopback_address(bind_address);
  p.require_token = true;  // on loopback too: any page in the operator's browser can reach it
  p.token = std::move(token);
  return p;
}

const char* access_name(Access a) {
  switch (a) {
    case Access::kAllowed:
      return "allowed";
    case Access::kMissingToken:
      return "missing session token";
    case Access::kBadToken:
      return "wrong session token";
    case Access::kCrossOrigin:
      return "cross-origin request";
    case Access::kBadHost:
      return "Host is not a loopback name";
  }
  return "unknown";
}

Access check_command_access(const AccessPolicy& policy,
                            const std::multimap<std::string, std::string>& headers) {
  const std::string* host = header(headers, "host");
  if (policy.loopback_only && (!host || !is_loopback_address(host_name(*host))))
    return Access::kBadHost;
  const std::string* origin = header(headers, "origin");
  if (origin && (!host || origin_authority(*origin) != lower(*host))) return Access::kCrossOrigin;
  if (policy.require_token) {
    const std::string* token = header(headers, "x-alight-token");
    if (!token || token->empty()) return Access::kMissingToken;
    // Constant time, as for the HMAC tag: the token is the only secret of the web link.
    if (token->size() != policy.token.size() ||
        CRYPTO_memcmp(token->data(), policy.token.data(), token->size()) != 0)
      return Access::kBadToken;
  }
  return Access::kAllowed;
}

std::string to_hex(const uint8_t* bytes, size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < n; ++i) {
    s += digits[bytes[i] >> 4];
    s += digits[bytes[i] & 15];
  }
  return s;
}

}  // namespace alight::ground_station

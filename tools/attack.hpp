#pragma once
// The attacks of the attack campaign (scripts/attacks): what an outsider on the network sends to
// the vehicle's LCM bus, built from the newest messages it has overheard (on a bus that leaves
// the vehicle) or made up from nothing (on one that does not). Each attack is a schedule of
// messages; alight-attack sends them as plain LCM datagrams, by multicast or unicast, without the
// vehicle's key. Pure: the node passes the time and what it overheard.

#include <alight/attitude_cmd_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/target_t.hpp>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace alight::tools::attack {

enum class Kind {
  kKillSetpoint,     ///< one POSITION_SETPOINT{MOTORS_KILL} stamped 0.45 s ahead
  kSetpointStream,   ///< setpoints 20 m away, 50 Hz for 8 s: fly it out of the room
  kAttitudeDisarm,   ///< ATTITUDE_CMD{armed = false}, 10 Hz for 1 s
  kKillCommand,      ///< OPERATOR_CMD CMD_KILL unsigned, and one with a forged tag
  kPoseOffset,       ///< every pose re-sent 50 ms ahead, shifted 30 cm, 100 Hz for 15 s
  kPoseGrowing,      ///< ... with a shift growing at 0.5 m/s
  kPoseAhead,        ///< one pose stamped 0.45 s ahead (to capture the stamp guard)
  kPoseSpoofed,      ///< kPoseOffset under the live publisher's own id (its trailer copied)
  kVisionTarget,     ///< VISION_TARGET found 25 cm off the live one, 30 Hz for 15 s
  kFlood,            ///< copies and garbage on every flight channel, as fast as it can, 5 s
  kSecondPublisher,  ///< every overheard flight message re-published as is, 10 s
};

const char* name(Kind k);
std::optional<Kind> parse(const std::string& name);
std::vector<Kind> all();

/// What the attacker overheard last (nothing on a bus that stays on the vehicle).
struct Overheard {
  std::optional<pose_t> pose;
  std::optional<position_setpoint_t> setpoint;
  std::optional<attitude_cmd_t> attitude;
  std::optional<target_t> target;
  /// Raw bytes (with the publisher's origin trailer) of the newest message per flight channel.
  std::vector<std::pair<std::string, std::vector<uint8_t>>> raw;
};

struct Datagram {
  std::string channel;
  std::vector<uint8_t> payload;  ///< what LCM carries: an encoded message (and maybe a trailer)
};

/// The attack's period between rounds [s] and how long it lasts [s].
double period_s(Kind k);
double duration_s(Kind k);

/// The datagrams of one round, `t_s` into the attack, at the attacker's wall time `now_utime`.
/// Made-up values where nothing was overheard: a hover at 1.6 m over the origin, a platform at
/// (0.8, 0.4, 0.2).
std::vector<Datagram> round(Kind k, double t_s, int64_t now_utime, const Overheard& heard,
                            std::mt19937_64& rng);

/// LCM's small-message datagram (LCM 1.3.1 udpm: magic "LC02", sequence number, channel and a
/// NUL, payload), for a payload that fits one datagram.
std::vector<uint8_t> lcm_datagram(const std::string& channel, const std::vector<uint8_t>& payload,
                                  uint32_t seq);

}  // namespace alight::tools::attack

#pragma once
// LCM <-> bridge conversions of alight-mavlink (no network; tested in
// test/mavlink/bridge_msgs_test.cpp). The validating forms refuse what the bridge must never
// turn into a setpoint: non-finite values, unknown enumerations, absurd magnitudes.

#include <alight/attitude_cmd_t.hpp>
#include <alight/autopilot_status_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <optional>
#include <string>

#include "common/operator_auth.hpp"
#include "mavlink/bridge.hpp"

namespace alight::mavlink {

std::optional<AttitudeTarget> attitude_from_msg(const attitude_cmd_t& msg, std::string* why);
std::optional<PositionTarget> position_from_msg(const position_setpoint_t& msg, std::string* why);
/// Whether a setpoint's stamp may be used, judged against `reference_utime` (the newest stamp the
/// node accepted on any channel; 0: none yet): nullopt when it may, else why not. Not "never
/// backwards": the outer loop stamps ATTITUDE_CMD on its own extrapolated clock, which steps back
/// when a pose arrives after a timer tick (sim/sim_msgs.hpp has the same window for the same
/// reason). What it refuses is a replayed or stray command: stamped more than `max_age_s` before
/// the reference or `max_ahead_s` after it.
std::optional<std::string> setpoint_stamp_problem(int64_t utime, int64_t reference_utime,
                                                  double max_age_s, double max_ahead_s);
/// Whether a KILL (POSITION_SETPOINT motors KILL, ATTITUDE_CMD armed = false) carries the
/// operator's authority for a forced disarm: its kill_authority, the operator's signed
/// CMD_KILL, verified with the vehicle's operator key at `now_wall_us` (the command was stamped
/// by the ground station's clock). False, and *why, for an empty authority, no verifier (no
/// operator key configured) or one the verifier refuses: a plain motors-off then.
bool kill_authorised(KillVerifier* verifier, const operator_cmd_t& authority, int64_t now_wall_us,
                     std::string* why);
imu_t to_msg(const ImuOut& imu, int64_t seq);
/// `reopens`: how often the node reopened its device or socket.
autopilot_status_t to_msg(const AutopilotStatus& s, int64_t wall_utime, int64_t reopens);

}  // namespace alight::mavlink

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

#include "mavlink/bridge.hpp"

namespace alight::mavlink {

std::optional<AttitudeTarget> attitude_from_msg(const attitude_cmd_t& msg, std::string* why);
std::optional<PositionTarget> position_from_msg(const position_setpoint_t& msg, std::string* why);
imu_t to_msg(const ImuOut& imu, int64_t seq);
/// `reopens`: how often the node reopened its device or socket.
autopilot_status_t to_msg(const AutopilotStatus& s, int64_t wall_utime, int64_t reopens);

}  // namespace alight::mavlink

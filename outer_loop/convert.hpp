#pragma once
// LCM <-> domain conversions of the outer loop's messages (no network; tested in
// test/outer_loop/convert_test.cpp).

#include <alight/attitude_cmd_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <optional>
#include <string>

#include "outer_loop/setpoint.hpp"

namespace alight::outer_loop {

/// Unchecked conversion (trusted, e.g. a message this process made).
PositionSetpoint from_msg(const position_setpoint_t& msg);
/// Validating conversion for untrusted input: nullopt (and *why, when given) for a non-finite
/// position, velocity or yaw, or an unknown motors / mode value. The stamp is left to the node's
/// StampGuard.
std::optional<PositionSetpoint> setpoint_from_msg(const position_setpoint_t& msg, std::string* why);
position_setpoint_t to_msg(const PositionSetpoint& sp);

attitude_cmd_t to_msg(const AttitudeCommand& cmd);
/// Inverse of to_msg (the reason text is not carried by the message).
AttitudeCommand from_msg(const attitude_cmd_t& msg);

int8_t mode_to_msg(Mode mode);

}  // namespace alight::outer_loop

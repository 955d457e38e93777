#include "outer_loop/convert.hpp"

#include <cmath>

namespace alight::outer_loop {

PositionSetpoint from_msg(const position_setpoint_t& msg) {
  PositionSetpoint sp;
  sp.utime = msg.utime;
  sp.p_W = Vector3d(msg.p_W[0], msg.p_W[1], msg.p_W[2]);
  sp.v_W = Vector3d(msg.v_W[0], msg.v_W[1], msg.v_W[2]);
  sp.a_W = Vector3d(msg.a_W[0], msg.a_W[1], msg.a_W[2]);
  sp.yaw_rad = msg.yaw_rad;
  sp.yaw_rate_radps = msg.yaw_rate_radps;
  sp.motors_on = msg.motors == position_setpoint_t::MOTORS_ON;
  sp.kill = msg.motors == position_setpoint_t::MOTORS_KILL;
  sp.idle = msg.mode == position_setpoint_t::MODE_IDLE;
  sp.precise = msg.mode == position_setpoint_t::MODE_PRECISE;
  return sp;
}

std::optional<PositionSetpoint> setpoint_from_msg(const position_setpoint_t& msg,
                                                  std::string* why) {
  const auto refuse = [&](const std::string& text) -> std::optional<PositionSetpoint> {
    if (why) *why = text;
    return std::nullopt;
  };
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(msg.p_W[i])) return refuse("setpoint: non-finite position");
    if (!std::isfinite(msg.v_W[i])) return refuse("setpoint: non-finite velocity");
    if (!std::isfinite(msg.a_W[i])) return refuse("setpoint: non-finite acceleration");
  }
  if (!std::isfinite(msg.yaw_rad)) return refuse("setpoint: non-finite yaw");
  if (!std::isfinite(msg.yaw_rate_radps)) return refuse("setpoint: non-finite yaw rate");
  if (msg.motors != position_setpoint_t::MOTORS_OFF &&
      msg.motors != position_setpoint_t::MOTORS_ON &&
      msg.motors != position_setpoint_t::MOTORS_KILL)
    return refuse("setpoint: unknown motors value " + std::to_string(msg.motors));
  if (msg.mode != position_setpoint_t::MODE_POSITION &&
      msg.mode != position_setpoint_t::MODE_IDLE && msg.mode != position_setpoint_t::MODE_PRECISE)
    return refuse("setpoint: unknown mode value " + std::to_string(msg.mode));
  return from_msg(msg);
}

position_setpoint_t to_msg(const PositionSetpoint& sp) {
  position_setpoint_t msg{};
  msg.utime = sp.utime;
  for (int i = 0; i < 3; ++i) {
    msg.p_W[i] = sp.p_W[i];
    msg.v_W[i] = sp.v_W[i];
    msg.a_W[i] = sp.a_W[i];
  }
  msg.yaw_rad = sp.yaw_rad;
  msg.yaw_rate_radps = sp.yaw_rate_radps;
  msg.motors = sp.kill        ? position_setpoint_t::MOTORS_KILL
               : sp.motors_on ? position_setpoint_t::MOTORS_ON
                              : position_setpoint_t::MOTORS_OFF;
  msg.mode = sp.idle      ? position_setpoint_t::MODE_IDLE
             : sp.precise ? position_setpoint_t::MODE_PRECISE
                          : position_setpoint_t::MODE_POSITION;
  return msg;
}

int8_t mode_to_msg(Mode mode) {
  switch (mode) {
    case Mode::kNormal:
      return attitude_cmd_t::MODE_NORMAL;
    case Mode::kHoldLevel:
      return attitude_cmd_t::MODE_HOLD_LEVEL;
    case Mode::kFailsafeDescent:
      return attitude_cmd_t::MODE_FAILSAFE_DESCENT;
    case Mode::kHoldPosition:
      return attitude_cmd_t::MODE_HOLD_POSITION;
    case Mode::kSetpointLostDescent:
      return attitude_cmd_t::MODE_SETPOINT_LOST_DESCENT;
    case Mode::kDisarmed:
      return attitude_cmd_t::MODE_DISARMED;
    case Mode::kFailsafeLand:
      return attitude_cmd_t::MODE_FAILSAFE_LAND;
  }
  return attitude_cmd_t::MODE_DISARMED;
}

attitude_cmd_t to_msg(const AttitudeCommand& cmd) {
  attitude_cmd_t msg{};
  msg.utime = cmd.utime;
  msg.roll_rad = cmd.roll_rad;
  msg.pitch_rad = cmd.pitch_rad;
  msg.yaw_rate_radps = cmd.yaw_rate_radps;
  msg.thrust_N = cmd.armed ? cmd.thrust_N : 0.0;
  msg.armed = cmd.armed;
  msg.mode = mode_to_msg(cmd.mode);
  return msg;
}

AttitudeCommand from_msg(const attitude_cmd_t& msg) {
  AttitudeCommand c;
  c.utime = msg.utime;
  c.roll_rad = msg.roll_rad;
  c.pitch_rad = msg.pitch_rad;
  c.yaw_rate_radps = msg.yaw_rate_radps;
  c.thrust_N = msg.thrust_N;
  c.armed = msg.armed;
  switch (msg.mode) {
    case attitude_cmd_t::MODE_NORMAL:
      c.mode = Mode::kNormal;
      break;
    case attitude_cmd_t::MODE_HOLD_LEVEL:
      c.mode = Mode::kHoldLevel;
      break;
    case attitude_cmd_t::MODE_FAILSAFE_DESCENT:
      c.mode = Mode::kFailsafeDescent;
      break;
    case attitude_cmd_t::MODE_HOLD_POSITION:
      c.mode = Mode::kHoldPosition;
      break;
    case attitude_cmd_t::MODE_SETPOINT_LOST_DESCENT:
      c.mode = Mode::kSetpointLostDescent;
      break;
    case attitude_cmd_t::MODE_FAILSAFE_LAND:
      c.mode = Mode::kFailsafeLand;
      break;
    default:
      c.mode = Mode::kDisarmed;
      break;
  }
  return c;
}

}  // namespace alight::outer_loop

#include "mavlink/bridge_msgs.hpp"

#include <cmath>

namespace alight::mavlink {

namespace {
/// Beyond these a command is corrupt, not aggressive: 180 deg of tilt, 20 rad/s of yaw, 10 kN.
constexpr double kMaxAngleRad = M_PI, kMaxYawRateRadps = 20, kMaxThrustN = 1e4;
constexpr double kMaxPositionM = 1e4, kMaxVelocityMps = 100;
/// A feed-forward acceleration beyond 5 g is no multicopter's.
constexpr double kMaxAccelMps2 = 50;

bool finite_within(const double* v, int n, double limit) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i]) || std::abs(v[i]) > limit) return false;
  return true;
}
}  // namespace

std::optional<AttitudeTarget> attitude_from_msg(const attitude_cmd_t& msg, std::string* why) {
  const auto fail = [&](const char* w) -> std::optional<AttitudeTarget> {
    if (why) *why = w;
    return std::nullopt;
  };
  const double angles[] = {msg.roll_rad, msg.pitch_rad};
  if (!finite_within(angles, 2, kMaxAngleRad)) return fail("roll or pitch not finite or beyond pi");
  if (!finite_within(&msg.yaw_rate_radps, 1, kMaxYawRateRadps))
    return fail("yaw rate not finite or beyond 20 rad/s");
  if (!std::isfinite(msg.thrust_N) || msg.thrust_N < 0 || msg.thrust_N > kMaxThrustN)
    return fail("thrust not finite, negative or beyond 10 kN");
  AttitudeTarget t;
  t.utime = msg.utime;
  t.roll_rad = msg.roll_rad;
  t.pitch_rad = msg.pitch_rad;
  t.yaw_rate_radps = msg.yaw_rate_radps;
  t.thrust_N = msg.thrust_N;
  t.armed = msg.armed;
  return t;
}

std::optional<PositionTarget> position_from_msg(const position_setpoint_t& msg, std::string* why) {
  const auto fail = [&](const char* w) -> std::optional<PositionTarget> {
    if (why) *why = w;
    return std::nullopt;
  };
  if (!finite_within(msg.p_W, 3, kMaxPositionM)) return fail("position not finite or beyond 10 km");
  if (!finite_within(msg.v_W, 3, kMaxVelocityMps))
    return fail("velocity not finite or beyond 100 m/s");
  if (!finite_within(msg.a_W, 3, kMaxAccelMps2))
    return fail("acceleration not finite or beyond 50 m/s^2");
  if (!std::isfinite(msg.yaw_rad)) return fail("yaw not finite");
  if (!finite_within(&msg.yaw_rate_radps, 1, kMaxYawRateRadps))
    return fail("yaw rate not finite or beyond the limit");
  PositionTarget t;
  switch (msg.motors) {
    case position_setpoint_t::MOTORS_OFF:
      t.motors = Motors::kOff;
      break;
    case position_setpoint_t::MOTORS_ON:
      t.motors = Motors::kOn;
      break;
    case position_setpoint_t::MOTORS_KILL:
      t.motors = Motors::kKill;
      break;
    default:
      return fail("unknown motors value");
  }
  t.utime = msg.utime;
  t.p_W = Vector3d(msg.p_W[0], msg.p_W[1], msg.p_W[2]);
  t.v_W = Vector3d(msg.v_W[0], msg.v_W[1], msg.v_W[2]);
  t.a_W = Vector3d(msg.a_W[0], msg.a_W[1], msg.a_W[2]);
  t.yaw_rad = msg.yaw_rad;
  t.yaw_rate_radps = msg.yaw_rate_radps;
  return t;
}

std::optional<std::string> setpoint_stamp_problem(int64_t utime, int64_t reference_utime,
                                                  double max_age_s, double max_ahead_s) {
  if (utime <= 0) return "stamp not positive";
  if (reference_utime <= 0) return std::nullopt;
  // In double: hostile stamps near INT64_MIN / MAX must not overflow the difference.
  const double d_s = (static_cast<double>(utime) - static_cast<double>(reference_utime)) * 1e-6;
  if (d_s < -max_age_s) return "stamped " + std::to_string(-d_s) + " s before the newest input";
  if (d_s > max_ahead_s) return "stamped " + std::to_string(d_s) + " s after the newest input";
  return std::nullopt;
}

bool kill_authorised(KillVerifier* verifier, const operator_cmd_t& authority, int64_t now_wall_us,
                     std::string* why) {
  if (authority.command == operator_cmd_t::CMD_NONE &&
      authority.auth == operator_cmd_t::AUTH_NONE) {
    if (why) *why = "no kill authority attached";
    return false;
  }
  if (!verifier) {
    if (why) *why = "no operator key here (the vehicle file's autonomy.operator_key_file)";
    return false;
  }
  const KillCheck c = verifier->check(authority, now_wall_us);
  if (c == KillCheck::kAuthorised) return true;
  if (why) *why = kill_check_name(c);
  return false;
}

imu_t to_msg(const ImuOut& imu, int64_t seq) {
  imu_t m{};
  m.utime = imu.utime;
  m.seq = seq;
  for (int i = 0; i < 3; ++i) {
    m.accel_B[i] = imu.accel_B[i];
    m.gyro_B[i] = imu.gyro_B[i];
  }
  return m;
}

autopilot_status_t to_msg(const AutopilotStatus& s, int64_t wall_utime, int64_t reopens) {
  autopilot_status_t m{};
  m.utime = wall_utime;
  m.link_up = s.link_up;
  m.heartbeat_age_s = s.heartbeat_age_s;
  m.autopilot = s.flavour == Flavour::kPx4 ? autopilot_status_t::AUTOPILOT_PX4
                                           : autopilot_status_t::AUTOPILOT_ARDUPILOT;
  m.control = s.control == ControlMode::kAttitude ? autopilot_status_t::CONTROL_ATTITUDE
                                                  : autopilot_status_t::CONTROL_POSITION;
  m.sysid = s.sysid;
  m.custom_mode = s.custom_mode;
  m.base_mode = s.base_mode;
  m.system_status = s.system_status;
  m.mode = s.mode;
  m.armed = s.armed;
  m.offboard = s.offboard;
  m.engage = engage_state_name(s.engage);
  m.streaming = s.streaming;
  m.setpoint_age_s = s.setpoint_age_s;
  m.last_command = s.last_command;
  m.last_result = static_cast<int16_t>(s.last_result);
  m.last_statustext = s.last_statustext;
  m.battery_V = s.battery_V;
  m.firmware = s.firmware;
  m.accel_feedforward = s.accel_feedforward;
  m.frames_received = static_cast<int64_t>(s.parser.frames_ok);
  m.crc_errors = static_cast<int64_t>(s.parser.crc_errors);
  m.bytes_dropped = static_cast<int64_t>(s.parser.bytes_dropped);
  m.frames_sent = static_cast<int64_t>(s.stats.frames_sent);
  m.setpoints_sent = static_cast<int64_t>(s.stats.setpoints_sent);
  m.commands_sent = static_cast<int64_t>(s.stats.commands_sent);
  m.commands_failed = static_cast<int64_t>(s.stats.commands_failed);
  m.link_losses = static_cast<int64_t>(s.stats.link_losses);
  m.reopens = reopens;
  m.rejected = static_cast<int64_t>(s.stats.rejected_values + s.stats.rejected_stamps);
  return m;
}

}  // namespace alight::mavlink

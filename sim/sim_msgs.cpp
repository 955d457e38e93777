#include "sim/sim_msgs.hpp"

#include <cmath>

#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"

namespace alight::sim {

pose_t to_msg(const MocapSample& sample) {
  pose_t m = alight::to_msg(sample.pose, sample.seq);
  m.status = pose_t::STATUS_OK;
  return m;
}

imu_t to_msg(const ImuSample& s) {
  imu_t m{};
  m.utime = s.utime;
  m.seq = s.seq;
  for (int i = 0; i < 3; ++i) {
    m.accel_B[i] = s.accel_B[i];
    m.gyro_B[i] = s.gyro_B[i];
  }
  return m;
}

range_t to_msg(const RangeSample& s) {
  static_assert(static_cast<int8_t>(RangeStatus::kOk) == range_t::STATUS_OK);
  static_assert(static_cast<int8_t>(RangeStatus::kOutOfRange) == range_t::STATUS_OUT_OF_RANGE);
  static_assert(static_cast<int8_t>(RangeStatus::kTooNear) == range_t::STATUS_TOO_NEAR);
  static_assert(static_cast<int8_t>(RangeStatus::kNoEcho) == range_t::STATUS_NO_ECHO);
  range_t m{};
  m.utime = s.utime;
  m.seq = s.seq;
  m.status = static_cast<int8_t>(s.status);
  m.distance_m = s.status == RangeStatus::kOk ? s.distance_m : 0.0;
  m.min_range_m = s.min_range_m;
  m.max_range_m = s.max_range_m;
  for (int i = 0; i < 3; ++i) {
    m.t_B_R[i] = s.t_B_R[i];
    m.beam_B[i] = s.beam_B[i];
  }
  return m;
}

baro_t to_msg(const BaroSample& s) {
  baro_t m{};
  m.utime = s.utime;
  m.seq = s.seq;
  m.pressure_pa = s.pressure_pa;
  m.temperature_c = s.temperature_c;
  return m;
}

image_t to_msg(const CameraFrame& frame) {
  image_t m = image_to_msg(frame.pixels, frame.utime, frame.seq);
  set_exposure_metadata(m, frame.exposure_s);
  // A rolling shutter's line delay, where the vision can read it (Image::line_delay_s).
  if (frame.line_delay_s > 0)
    set_metadata_int(m, "line_delay_ns", std::llround(frame.line_delay_s * 1e9));
  return m;
}

sim_truth_t to_msg(const Truth& t) {
  sim_truth_t m{};
  m.utime = t.utime;
  m.scenario = t.scenario;
  for (int i = 0; i < 3; ++i) {
    m.pos[i] = t.state.p_W_B[i];
    m.vel[i] = t.state.v_W_B[i];
  }
  quat_to_wxyz(t.state.q_WB, m.orientation);
  m.has_platform = t.platform.has_value();
  if (t.platform) {
    for (int i = 0; i < 3; ++i) {
      m.platform_center_W[i] = t.platform->top_center_W[i];
      m.platform_size_m[i] = t.platform->size_m[i];
    }
    m.platform_yaw_rad = t.platform->yaw_rad;
  }
  m.has_opening = t.opening.has_value();
  if (t.opening) {
    for (int i = 0; i < 3; ++i) {
      m.opening_center_W[i] = t.opening->center_W[i];
      m.wall_normal_W[i] = t.opening->wall_normal_W[i];
    }
    m.opening_size_m[0] = t.opening->size_m.x();
    m.opening_size_m[1] = t.opening->size_m.y();
  }
  m.contact = static_cast<int8_t>(t.contact);
  m.armed = t.state.armed;
  m.landed = t.landed;
  m.tipped = t.tipped;
  m.collided = t.collided;
  m.n_collisions = t.n_collisions;
  m.out_of_area = t.out_of_area;
  return m;
}

std::optional<platform_truth_t> platform_msg(const Truth& t) {
  if (!t.platform || !t.platform->moving) return std::nullopt;
  const PlatformTruth& p = *t.platform;
  platform_truth_t m{};
  m.utime = t.utime;
  m.version = platform_truth_t::VERSION;
  for (int i = 0; i < 3; ++i) {
    m.top_center_W[i] = p.top_center_W[i];
    m.vel_W[i] = p.v_W[i];
    m.omega_W[i] = p.omega_W[i];
    m.size_m[i] = p.size_m[i];
  }
  quat_to_wxyz(Quaterniond(rotation_from_rpy(p.roll_rad, p.pitch_rad, p.yaw_rad)), m.orientation);
  m.roll_rad = p.roll_rad;
  m.pitch_rad = p.pitch_rad;
  m.yaw_rad = p.yaw_rad;
  return m;
}

AttitudeCommand from_msg(const attitude_cmd_t& msg) {
  AttitudeCommand c;
  c.utime = msg.utime;
  c.roll_rad = msg.roll_rad;
  c.pitch_rad = msg.pitch_rad;
  c.yaw_rate_radps = msg.yaw_rate_radps;
  c.thrust_N = msg.thrust_N;
  c.armed = msg.armed;
  return c;
}

std::optional<AttitudeCommand> command_from_msg(const attitude_cmd_t& msg, std::string* why) {
  if (!std::isfinite(msg.roll_rad) || !std::isfinite(msg.pitch_rad) ||
      !std::isfinite(msg.yaw_rate_radps) || !std::isfinite(msg.thrust_N)) {
    if (why) *why = "attitude command: non-finite roll, pitch, yaw rate or thrust";
    return std::nullopt;
  }
  return from_msg(msg);
}

std::optional<AttitudeCommand> command_from_msg(const attitude_cmd_t& msg, int64_t now_utime,
                                                double max_age_s, std::string* why) {
  // In double: a hostile stamp (INT64_MIN) must not overflow the difference.
  const double age_s = (static_cast<double>(now_utime) - static_cast<double>(msg.utime)) * 1e-6;
  if (!(age_s <= max_age_s && -age_s <= kMaxCommandAheadS)) {
    if (why)
      *why = "attitude command stamped " + std::to_string(age_s) + " s " +
             (age_s > 0 ? "before" : "after") + " the autopilot's clock (limit " +
             std::to_string(age_s > 0 ? max_age_s : kMaxCommandAheadS) +
             " s): a replay or a stray sender";
    return std::nullopt;
  }
  return command_from_msg(msg, why);
}

}  // namespace alight::sim

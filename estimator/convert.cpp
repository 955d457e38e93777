#include "estimator/convert.hpp"

#include "common/geometry.hpp"

namespace alight::estimator {
namespace {
Vector3d vec(const double v[3]) { return Vector3d(v[0], v[1], v[2]); }
void put(const Vector3d& v, double out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = v[i];
}
int8_t health_code(Health h) {
  switch (h) {
    case Health::kOk:
      return state_estimate_t::HEALTH_OK;
    case Health::kDegraded:
      return state_estimate_t::HEALTH_DEGRADED;
    case Health::kLost:
      break;
  }
  return state_estimate_t::HEALTH_LOST;
}
}  // namespace

ImuSample from_msg(const imu_t& msg) {
  ImuSample s;
  s.utime = msg.utime;
  s.accel_B = vec(msg.accel_B);
  s.gyro_B = vec(msg.gyro_B);
  return s;
}

RangeSample from_msg(const range_t& msg) {
  RangeSample s;
  s.utime = msg.utime;
  s.valid = msg.status == range_t::STATUS_OK;
  s.range_m = s.valid ? msg.distance_m : 0.0;
  return s;
}

BaroSample from_msg(const baro_t& msg) {
  BaroSample s;
  s.utime = msg.utime;
  s.pressure_pa = msg.pressure_pa;
  return s;
}

state_estimate_t to_msg(const State& s, const Vector3d& gyro_B, int64_t seq) {
  state_estimate_t m{};
  m.utime = s.utime;
  m.seq = seq;
  put(s.p_W_B, m.pos);
  put(s.v_W_B, m.vel);
  quat_to_wxyz(s.q_WB, m.orientation);
  put(gyro_B - s.gyro_bias_B, m.angular_velocity_B);
  put(s.accel_bias_B, m.accel_bias_B);
  put(s.gyro_bias_B, m.gyro_bias_B);
  m.terrain_height_m = s.terrain_height_m;
  m.baro_offset_m = s.baro_offset_m;
  for (int r = 0; r < 9; ++r)
    for (int c = 0; c < 9; ++c) m.cov_pva[9 * r + c] = s.cov(r, c);
  m.health = health_code(s.health);
  m.health_reasons = static_cast<int32_t>(s.health_reasons);
  for (int k = 0; k < 4; ++k) {
    m.n_fused[k] = s.counters.fused(static_cast<Sensor>(k));
    m.n_rejected[k] = s.counters.rejected(static_cast<Sensor>(k));
  }
  return m;
}

pose_t to_pose_msg(const State& s, const Vector3d& gyro_B, int64_t seq) {
  pose_t m{};
  m.utime = s.utime;
  m.seq = seq;
  put(s.p_W_B, m.pos);
  put(s.v_W_B, m.vel);
  quat_to_wxyz(s.q_WB, m.orientation);
  put(gyro_B - s.gyro_bias_B, m.angular_velocity_B);
  m.status = s.health == Health::kOk ? pose_t::STATUS_OK : pose_t::STATUS_COASTING;
  return m;
}

}  // namespace alight::estimator

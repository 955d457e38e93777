#include "common/msg_convert.hpp"

#include <cmath>

namespace alight {

PoseSample from_msg(const pose_t& m) {
  PoseSample s;
  s.utime = m.utime;
  s.p_W_B = Vector3d(m.pos[0], m.pos[1], m.pos[2]);
  s.v_W_B = Vector3d(m.vel[0], m.vel[1], m.vel[2]);
  s.q_WB = quat_from_wxyz(m.orientation);
  s.omega_B = Vector3d(m.angular_velocity_B[0], m.angular_velocity_B[1], m.angular_velocity_B[2]);
  return s;
}

pose_t to_msg(const PoseSample& s, int64_t seq) {
  pose_t m{};
  m.utime = s.utime;
  m.seq = seq;
  for (int i = 0; i < 3; ++i) {
    m.pos[i] = s.p_W_B[i];
    m.vel[i] = s.v_W_B[i];
    m.angular_velocity_B[i] = s.omega_B[i];
  }
  quat_to_wxyz(s.q_WB, m.orientation);
  m.status = pose_t::STATUS_OK;
  return m;
}

std::optional<PoseSample> pose_from_msg(const pose_t& m, std::string* why) {
  const auto refuse = [&](const std::string& text) -> std::optional<PoseSample> {
    if (why) *why = text;
    return std::nullopt;
  };
  const auto all_finite = [](const double* v, int n) {
    for (int i = 0; i < n; ++i)
      if (!std::isfinite(v[i])) return false;
    return true;
  };
  if (!all_finite(m.pos, 3)) return refuse("pose: non-finite position");
  if (!all_finite(m.vel, 3)) return refuse("pose: non-finite velocity");
  if (!all_finite(m.orientation, 4)) return refuse("pose: non-finite orientation");
  if (!all_finite(m.angular_velocity_B, 3)) return refuse("pose: non-finite angular velocity");
  const double q_norm =
      std::sqrt(m.orientation[0] * m.orientation[0] + m.orientation[1] * m.orientation[1] +
                m.orientation[2] * m.orientation[2] + m.orientation[3] * m.orientation[3]);
  // Not a rotation: a sender's bug or a corrupted message, never renormalised into one.
  if (!(std::abs(q_norm - 1.0) <= 0.01))
    return refuse("pose: orientation quaternion norm " + std::to_string(q_norm) + " is not 1");
  return from_msg(m);
}

}  // namespace alight

#include "mavlink/ned_frd.hpp"

#include <cmath>

namespace alight::mavlink {

namespace {

// NED <- ENU and FRD <- FLU are rotations by pi, each its own inverse.
const Quaterniond& q_NED_ENU() {
  static const Quaterniond q(0.0, M_SQRT1_2, M_SQRT1_2, 0.0);
  return q;
}
const Quaterniond& q_FLU_FRD() {
  static const Quaterniond q(0.0, 1.0, 0.0, 0.0);
  return q;
}

}  // namespace

Vector3d ned_from_enu(const Vector3d& v_ENU) { return {v_ENU.y(), v_ENU.x(), -v_ENU.z()}; }
Vector3d enu_from_ned(const Vector3d& v_NED) { return {v_NED.y(), v_NED.x(), -v_NED.z()}; }
Vector3d frd_from_flu(const Vector3d& v_FLU) { return {v_FLU.x(), -v_FLU.y(), -v_FLU.z()}; }
Vector3d flu_from_frd(const Vector3d& v_FRD) { return {v_FRD.x(), -v_FRD.y(), -v_FRD.z()}; }

Quaterniond q_ned_frd_from_enu_flu(const Quaterniond& q_ENU_FLU) {
  return (q_NED_ENU() * q_ENU_FLU * q_FLU_FRD()).normalized();
}

Quaterniond q_enu_flu_from_ned_frd(const Quaterniond& q_NED_FRD) {
  // q_ENU_NED = q_NED_ENU^-1 = q_NED_ENU (a half turn), likewise q_FRD_FLU.
  return (q_NED_ENU() * q_NED_FRD * q_FLU_FRD()).normalized();
}

double yaw_ned_from_enu(double yaw_ENU_rad) { return wrap_angle(M_PI_2 - yaw_ENU_rad); }
double yaw_enu_from_ned(double yaw_NED_rad) { return wrap_angle(M_PI_2 - yaw_NED_rad); }

std::array<float, 4> wxyz_float(const Quaterniond& q) {
  const double s = q.w() < 0 ? -1.0 : 1.0;
  return {static_cast<float>(s * q.w()), static_cast<float>(s * q.x()),
          static_cast<float>(s * q.y()), static_cast<float>(s * q.z())};
}

std::optional<Quaterniond> quat_from_wxyz_float(const std::array<float, 4>& wxyz,
                                                double norm_tolerance) {
  for (float c : wxyz)
    if (!std::isfinite(c)) return std::nullopt;
  const Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  const double n = q.norm();
  if (!(std::abs(n - 1.0) <= norm_tolerance)) return std::nullopt;
  return q.normalized();
}

}  // namespace alight::mavlink

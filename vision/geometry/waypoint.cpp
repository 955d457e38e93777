// Paper 3.1.3, eqs. 3-6; see waypoint.hpp.
#include "vision/geometry/waypoint.hpp"

#include <cmath>

namespace alight::vision {

MocapMotion mocap_motion(const PoseSample& pose_1, const PoseSample& pose_2,
                         const CameraMount& mount) {
  const Matrix3d R_V1 = pose_1.q_WB.toRotationMatrix();
  const Matrix3d R_V2 = pose_2.q_WB.toRotationMatrix();
  const Vector3d c_1 = pose_1.p_W_B + R_V1 * mount.t_B_C;  // c of eq. 3
  const Vector3d c_2 = pose_2.p_W_B + R_V2 * mount.t_B_C;  // c' of eq. 3
  const Matrix3d R_WC1 = R_V1 * mount.R_BC, R_WC2 = R_V2 * mount.R_BC;
  MocapMotion m;
  m.R_21 = R_WC2.transpose() * R_WC1;
  m.t_12 = R_WC1.transpose() * (c_2 - c_1);
  m.baseline_m = (c_2 - c_1).norm();  // |t_V - R_V1 t_c + R_V2 t_c|
  return m;
}

Result<Waypoint> compute_waypoint(const PlaneMotion& motion, const Vector3d& ray_2,
                                  const PoseSample& pose_1, const PoseSample& pose_2,
                                  const CameraMount& mount, const WaypointParams& params) {
  const MocapMotion mocap = mocap_motion(pose_1, pose_2, mount);
  const double s = mocap.baseline_m;  // eq. 3 with |t12| = 1
  if (!(s >= params.min_baseline_m)) return Result<Waypoint>::fail(Reason::kSmallBaseline);
  Waypoint w;
  w.scale_m = s;
  w.translation_angle_rad = direction_angle(motion.t_12, mocap.t_12);
  w.rotation_error_rad = rotation_angle(motion.R_21, mocap.R_21);
  constexpr double kDeg = M_PI / 180.0;
  if (w.translation_angle_rad > params.max_translation_angle_deg * kDeg ||
      w.rotation_error_rad > params.max_rotation_error_deg * kDeg)
    return Result<Waypoint>::fail(Reason::kMotionDisagrees);

  const Vector3d n_2 = motion.n_2();  // eq. 4 [1/baseline]
  const double denom = n_2.dot(ray_2);
  if (!(denom > 1e-9) || !std::isfinite(denom))
    return Result<Waypoint>::fail(Reason::kAimBehindCamera);
  w.p_C2 = s * ray_2 / denom;  // eq. 5
  const Matrix3d R_V2 = pose_2.q_WB.toRotationMatrix();
  w.p_W = pose_2.p_W_B + R_V2 * mount.t_B_C + R_V2 * mount.R_BC * w.p_C2;  // eq. 6 (current pose)
  w.n_W = -(R_V2 * mount.R_BC * n_2).normalized();
  w.distance_m = s / n_2.norm();
  return Result<Waypoint>::ok(w);
}

double pattern_angle(const Matrix3d& R_WC, const Vector3d& d_W) {
  const Vector3d d_C = R_WC.transpose() * d_W;
  return std::atan2(d_C.y(), d_C.x());
}

}  // namespace alight::vision

#pragma once
// alight's frames (docs/ARCHITECTURE.md "Frames", REP-103) and MAVLink's. alight's world W is
// z-up and is taken as ENU (x east, y north, z up); its body B is FLU (x forward, y left, z up).
// MAVLink's local frame is NED (x north, y east, z down) and its body frame FRD (x forward,
// y right, z down) (mavlink.io/en/messages/common.html, MAV_FRAME_LOCAL_NED, MAV_FRAME_BODY_FRD).
//
//   NED <- ENU: (x, y, z) -> (y, x, -z), a rotation by pi about (1, 1, 0)/sqrt(2)
//   FRD <- FLU: (x, y, z) -> (x, -y, -z), a rotation by pi about x
//
// An attitude q_WB (FLU body to ENU world) becomes q_NED_FRD = q_NED_ENU q_ENU_FLU q_FLU_FRD, the
// quaternion of ATTITUDE_QUATERNION, SET_ATTITUDE_TARGET, ATT_POS_MOCAP and ODOMETRY. A heading
// (yaw) measured from east counter-clockwise becomes one from north clockwise: pi/2 - yaw.

#include <array>
#include <optional>

#include "common/geometry.hpp"

namespace alight::mavlink {

/// Position, velocity or acceleration: ENU world -> NED local frame.
Vector3d ned_from_enu(const Vector3d& v_ENU);
/// NED local frame -> ENU world.
Vector3d enu_from_ned(const Vector3d& v_NED);
/// Vector or angular rate in the body: FLU -> FRD.
Vector3d frd_from_flu(const Vector3d& v_FLU);
/// FRD -> FLU.
Vector3d flu_from_frd(const Vector3d& v_FRD);

/// Attitude: FLU body in the ENU world -> FRD body in the NED frame.
Quaterniond q_ned_frd_from_enu_flu(const Quaterniond& q_ENU_FLU);
/// FRD body in the NED frame -> FLU body in the ENU world.
Quaterniond q_enu_flu_from_ned_frd(const Quaterniond& q_NED_FRD);

/// Heading [rad]: from east counter-clockwise (ENU) -> from north clockwise (NED), in (-pi, pi].
double yaw_ned_from_enu(double yaw_ENU_rad);
/// Heading [rad]: NED -> ENU, in (-pi, pi].
double yaw_enu_from_ned(double yaw_NED_rad);

/// MAVLink's float [w, x, y, z] of a quaternion, with w >= 0.
std::array<float, 4> wxyz_float(const Quaterniond& q);
/// A quaternion from MAVLink's float [w, x, y, z], normalised; nullopt when a component is not
/// finite or the norm is far from 1 (not an attitude: an unset field or a corrupt sender).
std::optional<Quaterniond> quat_from_wxyz_float(const std::array<float, 4>& wxyz,
                                                double norm_tolerance = 0.1);

}  // namespace alight::mavlink

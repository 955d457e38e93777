#pragma once
// From a motion-capture room's report to alight's world frame (docs/ARCHITECTURE.md "Frames").
//
// The server reports X_RM: the tracked object's frame M in the room's frame R, positions in the
// room's units. Rooms differ: VICON and QTM are z-up, Motive is y-up by default (x and z on the
// floor), positions in millimetres or metres. World W is z up, metres; body B is x forward,
// y left, z up. So
//
//   X_WB = X_WR * X_RM * X_MB,   R_WR = Rz(yaw) * A_up,   p_W_R from the configuration,
//
// where A_up levels the room: identity for a z-up room, and for a y-up room the rotation of
// +90 deg about x that takes the room's y (up) to z and its z to -y (world x = room x).
// X_MB places the vehicle's body in the tracked object: an object created level in a y-up room
// has its y up too, hence R_MB = Rx(-90 deg) for it.

#include "common/geometry.hpp"
#include "mocap/params.hpp"

namespace alight::mocap {

/// R_WR of a levelled room before its yaw: A_up above.
Matrix3d leveling_rotation(const std::string& up_axis);

class RoomFrame {
 public:
  RoomFrame(const RoomParams& room, const BodyParams& body);

  /// Body pose in world from the object's pose in the room (position in room units,
  /// quaternion x y z w, normalised here).
  Isometry3d X_WB(const Vector3d& p_R_M_units, const Quaterniond& q_RM) const;
  /// A vector in room units (a velocity) in world metres.
  Vector3d to_world(const Vector3d& v_R_units) const { return R_WR_ * (scale_ * v_R_units); }

  const Matrix3d& R_WR() const { return R_WR_; }
  const Vector3d& p_W_R() const { return p_W_R_; }
  const Isometry3d& X_MB() const { return X_MB_; }
  double metres_per_unit() const { return scale_; }

 private:
  Matrix3d R_WR_;
  Vector3d p_W_R_;
  double scale_;
  Isometry3d X_MB_;
};

}  // namespace alight::mocap

#include "mocap/room_frame.hpp"

#include <cassert>
#include <cmath>

namespace alight::mocap {

namespace {
constexpr double kDegToRad = M_PI / 180.0;
}

Matrix3d leveling_rotation(const std::string& up_axis) {
  if (up_axis == "z") return Matrix3d::Identity();
  // Validated parameters only name z or y.
  assert(up_axis == "y");
  Matrix3d A;    // columns: room x, y, z in the levelled frame
  A << 1, 0, 0,  //
      0, 0, -1,  //
      0, 1, 0;
  return A;
}

RoomFrame::RoomFrame(const RoomParams& room, const BodyParams& body)
    : R_WR_(Eigen::AngleAxisd(room.yaw_deg * kDegToRad, Vector3d::UnitZ()).toRotationMatrix() *
            leveling_rotation(room.up_axis)),
      p_W_R_(room.p_W_R_m),
      scale_(room.units == "mm" ? 1e-3 : 1.0),
      X_MB_(make_transform(
          rotation_from_rpy(body.rpy_M_B_deg[0] * kDegToRad, body.rpy_M_B_deg[1] * kDegToRad,
                            body.rpy_M_B_deg[2] * kDegToRad),
          body.t_M_B_m)) {}

Isometry3d RoomFrame::X_WB(const Vector3d& p_R_M_units, const Quaterniond& q_RM) const {
  const Isometry3d X_WR = make_transform(R_WR_, p_W_R_);
  const Isometry3d X_RM =
      make_transform(q_RM.normalized().toRotationMatrix(), scale_ * p_R_M_units);
  return X_WR * X_RM * X_MB_;
}

}  // namespace alight::mocap

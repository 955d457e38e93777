// Room-to-world known answers: a z-up VICON / QTM room and a y-up Motive room, in metres and
// millimetres, with a yaw, an origin and the body's offset in the tracked object.

#include "mocap/room_frame.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace alight::mocap {
namespace {

constexpr double kDeg = M_PI / 180.0;

Quaterniond about(const Vector3d& axis, double deg) {
  return Quaterniond(Eigen::AngleAxisd(deg * kDeg, axis.normalized()));
}

void expect_near(const Vector3d& a, const Vector3d& b, double tol = 1e-12) {
  EXPECT_LT((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

void expect_rotation_near(const Matrix3d& a, const Matrix3d& b, double tol = 1e-12) {
  EXPECT_LT((a - b).norm(), tol) << "\n" << a << "\nvs\n" << b;
}

TEST(RoomFrameTest, ZUpMetresIsTheIdentity) {
  const RoomFrame f(RoomParams{}, BodyParams{});
  const auto q = about(Vector3d(1, 2, 3), 40);
  const Isometry3d X = f.X_WB(Vector3d(1.5, -2, 0.8), q);
  expect_near(X.translation(), Vector3d(1.5, -2, 0.8));
  expect_rotation_near(X.linear(), q.toRotationMatrix());
}

TEST(RoomFrameTest, ZUpMillimetresWithYawAndOrigin) {
  RoomParams room;
  room.units = "mm";
  room.yaw_deg = 90;
  room.p_W_R_m = Vector3d(1, 2, 0);
  const RoomFrame f(room, BodyParams{});
  // Room (1000, 0, 500) mm = (1, 0, 0.5) m, turned 90 deg: (0, 1, 0.5), plus the origin.
  const Isometry3d X = f.X_WB(Vector3d(1000, 0, 500), Quaterniond::Identity());
  expect_near(X.translation(), Vector3d(1, 3, 0.5));
  // The object's x (along room x) points along world y: heading +90 deg.
  EXPECT_NEAR(yaw_of(X.linear()), 90 * kDeg, 1e-12);
  expect_near(f.to_world(Vector3d(1000, 0, 0)), Vector3d(0, 1, 0));
}

TEST(RoomFrameTest, YUpMillimetresLevelsTheRoom) {
  RoomParams room;
  room.units = "mm";
  room.up_axis = "y";
  BodyParams body;
  body.rpy_M_B_deg = Vector3d(-90, 0, 0);  // an object defined level in the y-up room
  const RoomFrame f(room, body);
  // Room x stays world x, room y (up) is world z, room z is world -y.
  const Isometry3d X = f.X_WB(Vector3d(100, 1500, -2000), Quaterniond::Identity());
  expect_near(X.translation(), Vector3d(0.1, 2.0, 1.5));
  expect_rotation_near(X.linear(), Matrix3d::Identity());
  // Turning 30 deg about the room's up is a 30 deg yaw in world, still level.
  const Isometry3d Xt = f.X_WB(Vector3d(0, 1000, 0), about(Vector3d::UnitY(), 30));
  expect_near(Xt.translation(), Vector3d(0, 0, 1));
  expect_rotation_near(Xt.linear(), rotation_from_rpy(0, 0, 30 * kDeg));
  // Nose up (a turn about the object's z, its right side): the body x axis gains +z.
  const Isometry3d Xp = f.X_WB(Vector3d::Zero(), about(Vector3d::UnitZ(), 20));
  EXPECT_NEAR(Xp.linear()(2, 0), std::sin(20 * kDeg), 1e-12);
  expect_near(f.to_world(Vector3d(0, 0, 1000)), Vector3d(0, -1, 0));
}

TEST(RoomFrameTest, YUpWithYawAndOrigin) {
  RoomParams room;
  room.up_axis = "y";
  room.yaw_deg = -90;
  room.p_W_R_m = Vector3d(0, 0, 0.05);
  BodyParams body;
  body.rpy_M_B_deg = Vector3d(-90, 0, 0);
  const RoomFrame f(room, body);
  // Levelled (2, 0, 1), turned -90 deg about z: (0, -2, 1), plus the origin.
  const Isometry3d X = f.X_WB(Vector3d(2, 1, 0), Quaterniond::Identity());
  expect_near(X.translation(), Vector3d(0, -2, 1.05));
  EXPECT_NEAR(yaw_of(X.linear()), -90 * kDeg, 1e-12);
}

TEST(RoomFrameTest, BodyOffsetInTheObjectFrame) {
  BodyParams body;
  body.t_M_B_m = Vector3d(0.2, 0, -0.05);  // body origin 20 cm ahead of and 5 cm below M's
  body.rpy_M_B_deg = Vector3d(0, 0, 180);  // the object was defined facing backwards
  const RoomFrame f(RoomParams{}, body);
  const Isometry3d X = f.X_WB(Vector3d(1, 1, 1), about(Vector3d::UnitZ(), 90));
  expect_near(X.translation(), Vector3d(1, 1.2, 0.95));
  EXPECT_NEAR(yaw_of(X.linear()), -90 * kDeg, 1e-12);
}

TEST(RoomFrameTest, RoomRotationIsARotationForEveryOption) {
  for (const char* up : {"z", "y"})
    for (double yaw : {-360.0, -135.0, 0.0, 17.0, 360.0}) {
      RoomParams room;
      room.up_axis = up;
      room.yaw_deg = yaw;
      const RoomFrame f(room, BodyParams{});
      EXPECT_TRUE(is_rotation(f.R_WR(), 1e-12)) << up << " " << yaw;
      // Up in the room is up in world.
      const Vector3d up_R = std::string(up) == "z" ? Vector3d::UnitZ() : Vector3d::UnitY();
      expect_near(f.R_WR() * up_R, Vector3d::UnitZ());
    }
}

}  // namespace
}  // namespace alight::mocap

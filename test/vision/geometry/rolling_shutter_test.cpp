// Rolling-shutter geometry (vision/geometry/rolling_shutter.hpp): a feature recorded on its row's
// time, brought to row 0's camera, lands where row 0's camera sees the point; with a global
// shutter every ray is the lens's own, to the bit.
#include "vision/geometry/rolling_shutter.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace alight::vision {
namespace {

CameraMount downward_mount() {
  CameraMount m;
  m.R_BC = R_BC_downward();
  m.t_B_C = Vector3d(0.05, 0.0, -0.08);  // a lever arm, so the body's turn moves the camera
  return m;
}

// A body 1.5 m above the floor z = 0, moving and turning at constant rates.
PoseSample moving_pose() {
  PoseSample p;
  p.p_W_B = Vector3d(0.2, -0.1, 1.5);
  p.q_WB = Quaterniond(rotation_from_rpy(0.05, -0.03, 0.4));
  p.v_W_B = Vector3d(0.5, -0.3, 0.1);
  p.omega_B = Vector3d(0.6, -0.4, 0.3);
  return p;
}

Isometry3d camera_at(const PoseSample& p0, const CameraMount& mount, double t_s) {
  PoseSample p = p0;
  p.p_W_B = p0.p_W_B + p0.v_W_B * t_s;
  const double a = (p0.omega_B * t_s).norm();
  const Matrix3d dR = a > 0 ? Eigen::AngleAxisd(a, p0.omega_B.normalized()).toRotationMatrix()
                            : Matrix3d::Identity();
  p.q_WB = Quaterniond(p0.q_WB.toRotationMatrix() * dR);
  return camera_in_world(p.X_WB(), mount.X_BC());
}

// Where a rolling-shutter camera records world point P: the pixel whose row's camera sees P
// there (fixed point on the row).
Vector2d recorded_pixel(const CameraModel& cam, const PoseSample& p0, const CameraMount& mount,
                        double line_delay_s, const Vector3d& P_W) {
  Vector2d u = *cam.project(camera_at(p0, mount, 0).inverse() * P_W);
  for (int i = 0; i < 20; ++i)
    u = *cam.project(camera_at(p0, mount, u.y() * line_delay_s).inverse() * P_W);
  return u;
}

TEST(RollingShutterTest, GlobalShutterLeavesEveryRayTheLenssOwn) {
  CameraModel cam;
  cam.D = {-0.2, 0.05, 0.001, -0.001, 0.0};
  const Readout global =
      readout_motion(moving_pose(), downward_mount(), 0.0, ScenePlane{Vector3d::UnitZ(), 0.0});
  EXPECT_FALSE(global.rolling());
  for (const Vector2d& u : {Vector2d(10.3, 20.7), Vector2d(320, 240), Vector2d(600.5, 470.25)}) {
    const Vector3d r = ray_at_epoch(cam, u, global);
    EXPECT_EQ(r, cam.ray(u));
    EXPECT_EQ(*pixel_of_epoch_ray(cam, r, global), *cam.project(r));
  }
  // A delay that is not a delay is a global shutter too.
  EXPECT_FALSE(readout_motion(moving_pose(), downward_mount(), -1e-5, std::nullopt).rolling());
  EXPECT_FALSE(
      readout_motion(moving_pose(), downward_mount(), std::nan(""), std::nullopt).rolling());
}

TEST(RollingShutterTest, FloorPointsComeBackToRowZerosCamera) {
  const CameraModel cam;
  const CameraMount mount = downward_mount();
  const PoseSample p0 = moving_pose();
  const double line_delay_s = 40e-6;  // 19 ms of readout
  const Readout m = readout_motion(p0, mount, line_delay_s, ScenePlane{Vector3d::UnitZ(), 0.0});
  ASSERT_TRUE(m.rolling());
  const Isometry3d X_C0W = camera_at(p0, mount, 0).inverse();
  double worst_raw_px = 0, worst_corrected_px = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      // The floor point row 0's camera sees at a grid pixel.
      const Vector2d grid(40 + 140 * i, 30 + 105 * j);
      const Vector3d d_W = X_C0W.inverse().linear() * cam.ray(grid);
      const Vector3d c_W = X_C0W.inverse().translation();
      const Vector3d P_W = c_W + d_W * (-c_W.z() / d_W.z());
      const Vector2d u = recorded_pixel(cam, p0, mount, line_delay_s, P_W);
      const Vector2d at_epoch = (cam.K() * ray_at_epoch(cam, u, m)).hnormalized();
      worst_raw_px = std::max(worst_raw_px, (u - grid).norm());
      worst_corrected_px = std::max(worst_corrected_px, (at_epoch - grid).norm());
      // ... and back to the raw pixel it was recorded at.
      const auto back = pixel_of_epoch_ray(cam, X_C0W * P_W, m);
      ASSERT_TRUE(back);
      EXPECT_LT((*back - u).norm(), 0.02) << grid.transpose();
    }
  // Several pixels of rolling-shutter shift, corrected to a small fraction of a pixel (the lever
  // arm's turn makes the camera's velocity vary a little over the readout).
  EXPECT_GT(worst_raw_px, 3.0);
  EXPECT_LT(worst_corrected_px, 0.05);
}

TEST(RollingShutterTest, WithoutAPlaneTheRotationIsStillCorrected) {
  const CameraModel cam;
  const CameraMount mount = downward_mount();
  PoseSample p0 = moving_pose();
  p0.v_W_B.setZero();
  p0.omega_B = Vector3d(0.0, 0.0, 0.8);
  CameraMount centred = mount;
  centred.t_B_C.setZero();  // a pure turn: no translation, so depths do not matter
  const double line_delay_s = 30e-6;
  const Readout m = readout_motion(p0, centred, line_delay_s, std::nullopt);
  const Isometry3d X_C0W = camera_at(p0, centred, 0).inverse();
  for (const double depth : {0.5, 3.0, 50.0}) {
    const Vector2d grid(500, 400);
    const Vector3d P_W = X_C0W.inverse() * (cam.ray(grid) * depth);
    const Vector2d u = recorded_pixel(cam, p0, centred, line_delay_s, P_W);
    EXPECT_GT((u - grid).norm(), 1.0);
    EXPECT_LT(((cam.K() * ray_at_epoch(cam, u, m)).hnormalized() - grid).norm(), 0.01) << depth;
  }
}

TEST(RollingShutterTest, FisheyeRaysAreUndistortedBeforeTheCorrection) {
  CameraModel cam;
  cam.distortion = CameraModel::Distortion::kEquidistant;
  cam.D = {-0.05, 0.01, 0.0, 0.0, 0.0};
  const CameraMount mount = downward_mount();
  const PoseSample p0 = moving_pose();
  const double line_delay_s = 20e-6;
  const Readout m = readout_motion(p0, mount, line_delay_s, ScenePlane{Vector3d::UnitZ(), 0.0});
  const Isometry3d X_C0W = camera_at(p0, mount, 0).inverse();
  const Vector3d c_W = X_C0W.inverse().translation();
  for (const Vector2d& grid : {Vector2d(60, 50), Vector2d(580, 420)}) {
    const Vector3d d_W = X_C0W.inverse().linear() * cam.ray(grid);
    const Vector3d P_W = c_W + d_W * (-c_W.z() / d_W.z());
    const Vector2d u = recorded_pixel(cam, p0, mount, line_delay_s, P_W);
    const Vector3d r = ray_at_epoch(cam, u, m);
    EXPECT_LT((r - cam.ray(grid)).norm() * cam.fx, 0.05);
  }
}

// The tabulated inverse against the exact one at every pixel of the frame and half a pixel off
// it, for the three lenses, under a fast readout (40 us a row, 19 ms) while turning at 0.6 rad/s
// and moving at 0.6 m/s 1.5 m over the floor.
TEST(RollingShutterTest, TheGridMapsEveryPixelAsTheExactInverse) {
  CameraModel pinhole, radtan, fisheye;
  radtan.D = {-0.25, 0.07, 0.001, -0.001, 0.0};
  fisheye.distortion = CameraModel::Distortion::kEquidistant;
  fisheye.D = {-0.05, 0.01, 0.0, 0.0, 0.0};
  const CameraMount mount = downward_mount();
  const PoseSample p0 = moving_pose();
  for (const auto& plane : {std::optional<ScenePlane>(ScenePlane{Vector3d::UnitZ(), 0.0}),
                            std::optional<ScenePlane>()}) {
    const Readout m = readout_motion(p0, mount, 40e-6, plane);
    for (const CameraModel* cam : {&pinhole, &radtan, &fisheye}) {
      const EpochPixelGrid grid(*cam, m);
      double worst_px = 0, largest_shift_px = 0;
      for (double v = -0.25; v < cam->height; v += 0.5)
        for (double u = -0.25; u < cam->width; u += 0.5) {
          const Vector3d r0 = cam->ray({u, v});
          const auto exact = pixel_of_epoch_ray(*cam, r0, m);
          const auto fast = grid.pixel(r0);
          ASSERT_EQ(exact.has_value(), fast.has_value());
          if (!exact) continue;
          worst_px = std::max(worst_px, (*fast - *exact).norm());
          largest_shift_px = std::max(largest_shift_px, (*exact - Vector2d(u, v)).norm());
        }
      EXPECT_GT(largest_shift_px, 3.0);  // a readout that matters
      EXPECT_LT(worst_px, 1e-3) << cam->D[0] << (plane ? " on the floor" : " rotation only")
                                << ", shifts up to " << largest_shift_px << " px";
    }
  }
}

// Off the grid (far outside the image) the exact inverse answers, to the bit; behind the camera
// nothing.
TEST(RollingShutterTest, TheGridLeavesRaysOffItToTheExactInverse) {
  const CameraModel cam;
  const Readout m =
      readout_motion(moving_pose(), downward_mount(), 40e-6, ScenePlane{Vector3d::UnitZ(), 0.0});
  const EpochPixelGrid grid(cam, m);
  for (const Vector3d& r0 : {Vector3d(-0.7, 0.1, 1.0), Vector3d(0.2, 0.9, 1.0)}) {
    ASSERT_TRUE(pixel_of_epoch_ray(cam, r0, m));
    EXPECT_EQ(*grid.pixel(r0), *pixel_of_epoch_ray(cam, r0, m));
  }
  EXPECT_FALSE(grid.pixel(Vector3d(0.1, 0.1, -1.0)));
}

}  // namespace
}  // namespace alight::vision

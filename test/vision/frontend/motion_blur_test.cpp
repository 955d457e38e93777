// The floor's smear over an exposure (motion_blur.hpp) against the motion field worked by hand.
#include "vision/frontend/motion_blur.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace alight::vision {
namespace {

// An ideal 640 x 480 camera looking straight down from the body's origin.
struct Rig {
  CameraModel camera;  // defaults: f 666.667 px, principal point at the centre, no distortion
  CameraMount mount;
  Rig() { mount.R_BC = R_BC_downward(); }
};

PoseSample hover_at(double height_m) {
  PoseSample p;
  p.p_W_B = Vector3d(0.3, -0.2, height_m);
  return p;
}

TEST(MotionBlurTest, SidewaysFlightSmearsALevelFloorEvenly) {
  const Rig r;
  PoseSample p = hover_at(1.5);
  p.v_W_B = Vector3d(0.6, -0.8, 0);  // 1 m/s
  // Every ray meets the floor at depth 1.5 m (a level floor, a level camera): f v t / h.
  EXPECT_NEAR(floor_motion_blur_px(r.camera, r.mount, p, 0.0, 0.01), 666.667 * 1.0 * 0.01 / 1.5,
              1e-6);
  // A floor 0.5 m up is nearer: the smear grows as 1 / h.
  EXPECT_NEAR(floor_motion_blur_px(r.camera, r.mount, p, 0.5, 0.01), 666.667 * 0.01 / 1.0, 1e-6);
}

TEST(MotionBlurTest, YawSmearsTheCornersFarthest) {
  const Rig r;
  PoseSample p = hover_at(1.5);
  p.omega_B = Vector3d(0, 0, 2.0);  // rad/s about the optical axis
  // A point d px from the principal point moves d * w px/s; the farthest grid points are the
  // corners, (319.5, 239.5) px away.
  EXPECT_NEAR(floor_motion_blur_px(r.camera, r.mount, p, 0.0, 0.005),
              std::hypot(319.5, 239.5) * 2.0 * 0.005, 1e-6);
}

TEST(MotionBlurTest, PitchSmearsTheCornersMoreThanTheCentre) {
  const Rig r;
  PoseSample p = hover_at(1.5);
  p.omega_B = Vector3d(0, 1.5, 0);  // pitching, as at a turn of the search path
  const double f = 666.667, x = 319.5 / f, y = 239.5 / f;  // a corner, normalised
  // The downward camera's x axis is the body's y: at the corner (x, y) a turn w about camera x
  // moves the image by w (x y, 1 + y^2) (the motion field), the farthest of the grid.
  const double blur_px = floor_motion_blur_px(r.camera, r.mount, p, 0.0, 0.008);
  EXPECT_NEAR(blur_px, f * 1.5 * 0.008 * std::hypot(x * y, 1 + y * y), 1e-6);
  EXPECT_GT(blur_px, f * 1.5 * 0.008 * 1.1);  // more than at the principal point
  // The lever arm: a camera 10 cm below the body's centre moves as the body pitches, which adds
  // to the rotation's smear seen on a floor 1.4 m below it.
  Rig below = r;
  below.mount.t_B_C = Vector3d(0, 0, -0.1);
  EXPECT_NE(floor_motion_blur_px(below.camera, below.mount, p, 0.0, 0.008), blur_px);
}

TEST(MotionBlurTest, NoExposureNoSmearAndAFloorOutOfSightCountsAsFar) {
  const Rig r;
  PoseSample p = hover_at(1.5);
  p.v_W_B = Vector3d(1, 0, 0);
  EXPECT_EQ(floor_motion_blur_px(r.camera, r.mount, p, 0.0, 0.0), 0.0);
  EXPECT_EQ(floor_motion_blur_px(r.camera, r.mount, p, 0.0, -1.0), 0.0);
  // Upside down over the floor: no ray meets it, so translation smears nothing.
  p.q_WB = Quaterniond(Eigen::AngleAxisd(M_PI, Vector3d::UnitX()));
  EXPECT_EQ(floor_motion_blur_px(r.camera, r.mount, p, 0.0, 0.01), 0.0);
  // A camera below the floor's plane sees no floor either.
  EXPECT_EQ(floor_motion_blur_px(r.camera, r.mount, hover_at(-0.5), 0.0, 0.01), 0.0);
}

}  // namespace
}  // namespace alight::vision

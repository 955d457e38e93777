// The kept per-pixel rays (vision/geometry/pixel_rays.hpp) are CameraModel::ray's bit for bit:
// on first use and when read again, for a plumb_bob and a fisheye lens, after the camera
// changes, and outside the image.
#include "vision/geometry/pixel_rays.hpp"

#include <gtest/gtest.h>

#include <utility>

namespace alight::vision {
namespace {

CameraModel lens(CameraModel::Distortion kind, double k1) {
  CameraModel c = CameraModel::firefly_mv_4mm();
  c.distortion = kind;
  c.D = {k1, 0.02, kind == CameraModel::Distortion::kPlumbBob ? 0.001 : 0.0, 0.0, 0.0};
  return c;
}

void expect_rays_of(const CameraModel& camera) {
  PixelRays& rays = pixel_rays(camera);
  for (int pass = 0; pass < 2; ++pass)  // computed, then kept
    for (int y = 0; y < camera.height; y += 37)
      for (int x = 0; x < camera.width; x += 29) {
        const Vector3d expected = camera.ray(Vector2d(x, y));
        const Vector3d got = rays.at(x, y);
        ASSERT_EQ(got.x(), expected.x()) << x << ", " << y << " pass " << pass;
        ASSERT_EQ(got.y(), expected.y()) << x << ", " << y << " pass " << pass;
        ASSERT_EQ(got.z(), 1.0);
      }
  for (const auto& [x, y] : {std::pair{-1, 5}, std::pair{camera.width, 5}, std::pair{5, -3},
                             std::pair{5, camera.height}})
    EXPECT_EQ(rays.at(x, y), camera.ray(Vector2d(x, y))) << x << ", " << y;
}

TEST(PixelRaysTest, AreTheCamerasRaysBitForBitAcrossLensesAndCameraChanges) {
  const CameraModel barrel = lens(CameraModel::Distortion::kPlumbBob, -0.25);
  const CameraModel fisheye = lens(CameraModel::Distortion::kEquidistant, 0.03);
  expect_rays_of(barrel);
  expect_rays_of(fisheye);
  expect_rays_of(barrel);  // the table is made again for the first lens, not the second's
  CameraModel moved = barrel;
  moved.cx += 1.5;
  expect_rays_of(moved);
}

}  // namespace
}  // namespace alight::vision

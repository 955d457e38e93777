#include "common/camera_model.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <random>

#include "common/build_paths.hpp"
#include "common/params.hpp"

namespace alight {
namespace {

CameraModel distorted() {
  CameraModel c;
  c.D = {-0.21, 0.05, 0.001, -0.0008, 0.0};
  return c;
}

TEST(CameraModelTest, DefaultIsThePapersFireflyWithA4mmLens) {
  const CameraModel c = CameraModel::firefly_mv_4mm();
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_NEAR(c.fx, 4.0e-3 / 6.0e-6, 0.01);
  const auto px = c.project(Vector3d(0, 0, 2));
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x(), 319.5, 1e-12);
}

TEST(CameraModelTest, ProjectionMatchesOpenCvWithDistortion) {
  const CameraModel c = distorted();
  cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  cv::Mat D = (cv::Mat_<double>(1, 5) << c.D[0], c.D[1], c.D[2], c.D[3], c.D[4]);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  std::vector<cv::Point3d> pts;
  for (int i = 0; i < 200; ++i) pts.emplace_back(u(rng), u(rng), 1.0 + 0.5 * (u(rng) + 0.4));
  std::vector<cv::Point2d> ref;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, ref);
  for (size_t i = 0; i < pts.size(); ++i) {
    const auto px = c.project(Vector3d(pts[i].x, pts[i].y, pts[i].z));
    ASSERT_TRUE(px);
    EXPECT_NEAR(px->x(), ref[i].x, 1e-9);
    EXPECT_NEAR(px->y(), ref[i].y, 1e-9);
  }
}

TEST(CameraModelTest, RayInvertsProjection) {
  const CameraModel c = distorted();
  for (double u = 10; u < 640; u += 57.3) {
    for (double v = 10; v < 480; v += 41.9) {
      const Vector3d r = c.ray(Vector2d(u, v));
      EXPECT_DOUBLE_EQ(r.z(), 1.0);
      const auto px = c.project(2.5 * r);
      ASSERT_TRUE(px);
      EXPECT_NEAR(px->x(), u, 1e-6);
      EXPECT_NEAR(px->y(), v, 1e-6);
    }
  }
}

TEST(CameraModelTest, PointsBehindTheCameraDoNotProject) {
  EXPECT_FALSE(CameraModel{}.project(Vector3d(0.1, 0.1, -1.0)).has_value());
  EXPECT_FALSE(CameraModel{}.project(Vector3d(0.1, 0.1, 0.0)).has_value());
}

TEST(CameraModelTest, CameraInfoRoundTripsThroughYaml) {
  const CameraModel c = distorted();
  const auto path = std::filesystem::temp_directory_path() / "alight_camera_info_test.yaml";
  save_camera_info(path.string(), c);
  const CameraModel back = load_camera_info(path.string());
  EXPECT_EQ(back.width, c.width);
  EXPECT_EQ(back.name, c.name);
  EXPECT_DOUBLE_EQ(back.fx, c.fx);
  EXPECT_DOUBLE_EQ(back.cy, c.cy);
  for (int i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(back.D[i], c.D[i]);
  std::filesystem::remove(path);
}

TEST(CameraModelTest, ShippedFireflyFileLoads) {
  const auto c = load_camera_info(std::string(alight::build::source_dir()) +
                                  "/config/cameras/firefly_mv_4mm.yaml");
  EXPECT_EQ(c.width, 640);
  EXPECT_NEAR(c.fx, 666.667, 1e-9);
}

TEST(CameraModelTest, BadCameraInfoNamesTheKey) {
  const auto path = std::filesystem::temp_directory_path() / "alight_bad_camera_info.yaml";
  {
    std::ofstream f(path);
    f << "image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [-5, 0, "
         "320, 0, 600, 240, 0, 0, 1]}\n";
  }
  try {
    load_camera_info(path.string());
    FAIL() << "accepted fx < 0";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.key(), "camera_matrix.data[0]");
    EXPECT_EQ(e.value(), "-5");
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace alight

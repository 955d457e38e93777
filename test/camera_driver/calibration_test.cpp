// alight-calibrate's library on rendered chessboard views with known intrinsics.

#include "camera_driver/calibration.hpp"

#include <gtest/gtest.h>

#include "render_chessboard.hpp"

namespace alight::camera {
namespace {

TEST(CalibrationTest, RecoversKnownIntrinsicsWithinHalfAPercent) {
  // Not the default firefly values: a non-square pixel and an off-centre principal point.
  const double fx = 702.0, fy = 694.0, cx = 331.0, cy = 236.0;
  const cv::Matx33d K(fx, 0, cx, 0, fy, cy, 0, 0, 1);
  ChessboardParams board;  // 9x6 inner corners, 25 mm squares
  std::vector<cv::Mat> images;
  for (const auto& pose : testing::calibration_poses())
    images.push_back(testing::render_chessboard(K, board, pose, cv::Size(640, 480)));
  std::string err;
  const auto r = calibrate_chessboard(images, {}, board, "rendered", &err);
  ASSERT_TRUE(r) << err;
  EXPECT_EQ(r->used_views, static_cast<int>(images.size()));
  EXPECT_NEAR(r->model.fx, fx, 0.005 * fx);
  EXPECT_NEAR(r->model.fy, fy, 0.005 * fy);
  EXPECT_NEAR(r->model.cx, cx, 0.005 * cx);
  EXPECT_NEAR(r->model.cy, cy, 0.005 * cy);
  EXPECT_EQ(r->model.width, 640);
  EXPECT_EQ(r->model.height, 480);
  EXPECT_EQ(r->model.name, "rendered");
  // An ideal pinhole: the distortion estimate stays near zero and k3 is held at zero.
  EXPECT_LT(std::abs(r->model.D[0]), 0.05);
  EXPECT_EQ(r->model.D[4], 0.0);
  EXPECT_LT(r->rms_px, 0.3);
  for (const auto& v : r->views) EXPECT_LT(v.rms_px, 0.5) << v.name;
}

TEST(CalibrationTest, TooFewBoardsIsAnErrorNamingTheCount) {
  const cv::Matx33d K(700, 0, 320, 0, 700, 240, 0, 0, 1);
  ChessboardParams board;
  std::vector<cv::Mat> images;
  const auto poses = testing::calibration_poses();
  for (int i = 0; i < 3; ++i)
    images.push_back(testing::render_chessboard(K, board, poses[i], cv::Size(640, 480)));
  images.push_back(cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)));  // no board at all
  std::string err;
  EXPECT_FALSE(calibrate_chessboard(images, {}, board, "x", &err));
  EXPECT_NE(err.find("found in 3 of 4 images"), std::string::npos) << err;
}

TEST(CalibrationTest, FindsTheBoardCornersWhereTheyProject) {
  const cv::Matx33d K(700, 0, 320, 0, 700, 240, 0, 0, 1);
  ChessboardParams board;
  const testing::BoardPose pose{10, -15, 5, 0.01, 0.0, 0.5};
  const cv::Mat img = testing::render_chessboard(K, board, pose, cv::Size(640, 480));
  const auto corners = find_chessboard(img, board);
  ASSERT_TRUE(corners);
  ASSERT_EQ(corners->size(), 54u);
  // Where the corners must be: project the board points with the same pose.
  const double d2r = CV_PI / 180;
  cv::Matx33d Rx, Ry, Rz;
  cv::Rodrigues(cv::Vec3d(pose.rx_deg * d2r, 0, 0), Rx);
  cv::Rodrigues(cv::Vec3d(0, pose.ry_deg * d2r, 0), Ry);
  cv::Rodrigues(cv::Vec3d(0, 0, pose.rz_deg * d2r), Rz);
  const cv::Matx33d R = Rz * Ry * Rx;
  const cv::Vec3d centre(4 * board.square_m, 2.5 * board.square_m, 0);
  const cv::Vec3d t = cv::Vec3d(pose.x_m, pose.y_m, pose.z_m) - R * centre;
  cv::Vec3d rvec;
  cv::Rodrigues(R, rvec);
  std::vector<cv::Point2f> expected;
  cv::projectPoints(chessboard_object_points(board), rvec, t, K, cv::noArray(), expected);
  // OpenCV may order the corners from either end of the symmetric board.
  double fwd = 0, rev = 0;
  for (size_t i = 0; i < expected.size(); ++i) {
    fwd = std::max(fwd, cv::norm((*corners)[i] - expected[i]));
    rev = std::max(rev, cv::norm((*corners)[expected.size() - 1 - i] - expected[i]));
  }
  EXPECT_LT(std::min(fwd, rev), 0.3);
}

}  // namespace
}  // namespace alight::camera

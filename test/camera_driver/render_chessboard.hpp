#pragma once
// Chessboard views rendered with known intrinsics: a board texture warped into the image by the
// plane-induced homography H = K [r1 r2 t] A (A: texture pixels to board metres), as a pinhole
// camera without distortion sees it.

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "camera_driver/calibration.hpp"

namespace alight::camera::testing {

struct BoardPose {
  double rx_deg, ry_deg, rz_deg;  ///< board rotation in the camera frame
  double x_m, y_m, z_m;           ///< board centre in the camera frame [m]
};

inline cv::Mat render_chessboard(const cv::Matx33d& K, const ChessboardParams& board,
                                 const BoardPose& pose, cv::Size size) {
  const int P = 48, B = 24;  // texture pixels per square, white border [px]
  const int sq_x = board.inner_cols + 1, sq_y = board.inner_rows + 1;
  cv::Mat tex(sq_y * P + 2 * B, sq_x * P + 2 * B, CV_8UC1, cv::Scalar(255));
  for (int r = 0; r < sq_y; ++r)
    for (int c = 0; c < sq_x; ++c)
      if ((r + c) % 2 == 0) tex(cv::Rect(B + c * P, B + r * P, P, P)).setTo(0);
  // Texture pixel centres at integers: square edges at B + k P - 0.5; inner corner (0, 0) is
  // board point (0, 0).
  const double s = board.square_m / P, o = (0.5 - B - P) * s;
  const cv::Matx33d A(s, 0, o, 0, s, o, 0, 0, 1);
  cv::Matx33d R;
  const double d2r = CV_PI / 180.0;
  cv::Rodrigues(cv::Vec3d(pose.rx_deg * d2r, 0, 0), R);
  cv::Matx33d Ry, Rz;
  cv::Rodrigues(cv::Vec3d(0, pose.ry_deg * d2r, 0), Ry);
  cv::Rodrigues(cv::Vec3d(0, 0, pose.rz_deg * d2r), Rz);
  R = Rz * Ry * R;
  const cv::Vec3d centre_board((board.inner_cols - 1) * board.square_m / 2,
                               (board.inner_rows - 1) * board.square_m / 2, 0);
  const cv::Vec3d t = cv::Vec3d(pose.x_m, pose.y_m, pose.z_m) - R * centre_board;
  const cv::Matx33d Rt(R(0, 0), R(0, 1), t[0], R(1, 0), R(1, 1), t[1], R(2, 0), R(2, 1), t[2]);
  const cv::Matx33d H = K * Rt * A;
  cv::Mat img;
  cv::warpPerspective(tex, img, cv::Mat(H), size, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                      cv::Scalar(128));
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.7);  // a real lens does not alias
  return img;
}

/// Twelve varied poses (tilts up to 35 degrees, distances 0.4 to 0.6 m) that keep the board in
/// a 640x480 view with f ~ 700 px.
inline std::vector<BoardPose> calibration_poses() {
  return {{0, 0, 0, 0, 0, 0.45},
          {25, 0, 5, 0.02, 0.01, 0.45},
          {-25, 0, -5, -0.02, 0, 0.45},
          {0, 30, 10, 0, 0.02, 0.5},
          {0, -30, -10, 0.01, -0.02, 0.5},
          {20, 20, 30, -0.05, -0.03, 0.5},
          {-20, 25, -20, 0.05, 0.04, 0.55},
          {15, -25, 45, 0.06, -0.04, 0.6},
          {-30, -15, 15, -0.06, 0.05, 0.55},
          {35, 10, -30, 0.0, -0.05, 0.5},
          {10, 35, 0, -0.08, 0.0, 0.6},
          {-10, -35, 90, 0.08, 0.0, 0.55}};
}

}  // namespace alight::camera::testing

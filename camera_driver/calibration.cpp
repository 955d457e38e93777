#include "camera_driver/calibration.hpp"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace alight::camera {

std::vector<cv::Point3f> chessboard_object_points(const ChessboardParams& board) {
  std::vector<cv::Point3f> pts;
  for (int r = 0; r < board.inner_rows; ++r)
    for (int c = 0; c < board.inner_cols; ++c)
      pts.emplace_back(static_cast<float>(c * board.square_m),
                       static_cast<float>(r * board.square_m), 0.f);
  return pts;
}

std::optional<std::vector<cv::Point2f>> find_chessboard(const cv::Mat& image,
                                                        const ChessboardParams& board) {
  cv::Mat gray = image;
  if (image.channels() == 3) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  std::vector<cv::Point2f> corners;
  const cv::Size pattern(board.inner_cols, board.inner_rows);
  const int flags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE;
  if (!cv::findChessboardCorners(gray, pattern, corners, flags)) return std::nullopt;
  cv::cornerSubPix(gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
  return corners;
}

std::optional<CalibrationResult> calibrate_chessboard(const std::vector<cv::Mat>& images,
                                                      const std::vector<std::string>& names,
                                                      const ChessboardParams& board,
                                                      const std::string& camera_name,
                                                      std::string* error) {
  auto fail = [&](const std::string& why) -> std::optional<CalibrationResult> {
    if (error) *error = why;
    return std::nullopt;
  };
  if (images.empty()) return fail("no images");
  CalibrationResult result;
  const cv::Size size = images.front().size();
  std::vector<std::vector<cv::Point2f>> image_points;
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<size_t> used;  // index of each used view in `images`
  const auto board_pts = chessboard_object_points(board);
  for (size_t i = 0; i < images.size(); ++i) {
    ViewResult v;
    v.name = i < names.size() ? names[i] : "view " + std::to_string(i);
    if (images[i].size() != size)
      return fail(v.name + " is " + std::to_string(images[i].cols) + "x" +
                  std::to_string(images[i].rows) + ", the first image " +
                  std::to_string(size.width) + "x" + std::to_string(size.height));
    if (auto corners = find_chessboard(images[i], board)) {
      v.found = true;
      image_points.push_back(std::move(*corners));
      object_points.push_back(board_pts);
      used.push_back(i);
    }
    result.views.push_back(v);
  }
  result.used_views = static_cast<int>(used.size());
  if (result.used_views < board.min_views)
    return fail("a " + std::to_string(board.inner_cols) + "x" + std::to_string(board.inner_rows) +
                " inner-corner chessboard was found in " + std::to_string(result.used_views) +
                " of " + std::to_string(images.size()) + " images; " +
                std::to_string(board.min_views) + " needed");

  int flags = 0;
  if (board.fix_k3) flags |= cv::CALIB_FIX_K3;
  if (board.fix_tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  cv::Mat K, D;
  std::vector<cv::Mat> rvecs, tvecs;
  result.rms_px = cv::calibrateCamera(
      object_points, image_points, size, K, D, rvecs, tvecs, flags,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  for (size_t j = 0; j < used.size(); ++j) {
    std::vector<cv::Point2f> projected;
    cv::projectPoints(object_points[j], rvecs[j], tvecs[j], K, D, projected);
    double sq = 0.0;
    for (size_t k = 0; k < projected.size(); ++k) {
      const cv::Point2f d = projected[k] - image_points[j][k];
      sq += d.dot(d);
    }
    result.views[used[j]].rms_px = std::sqrt(sq / projected.size());
  }
  CameraModel& m = result.model;
  m.name = camera_name;
  m.width = size.width;
  m.height = size.height;
  m.fx = K.at<double>(0, 0);
  m.fy = K.at<double>(1, 1);
  m.cx = K.at<double>(0, 2);
  m.cy = K.at<double>(1, 2);
  for (int k = 0; k < 5; ++k) m.D[k] = static_cast<size_t>(k) < D.total() ? D.at<double>(k) : 0.0;
  return result;
}

}  // namespace alight::camera

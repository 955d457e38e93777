#pragma once
// Chessboard calibration of the pinhole + plumb_bob model the rest of alight uses
// (common/camera_model.hpp): Zhang, "A flexible new technique for camera calibration"
// (IEEE PAMI 22(11), 2000) with Brown-Conrady distortion, as implemented by OpenCV's
// calibrateCamera; corners by findChessboardCorners refined with cornerSubPix.

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/camera_model.hpp"

namespace alight::camera {

struct ChessboardParams {
  int inner_cols = 9;           ///< inner corners along a row (squares - 1)
  int inner_rows = 6;           ///< inner corners along a column
  double square_m = 0.025;      ///< side of one square [m] (scales extrinsics only, not K)
  bool fix_k3 = true;           ///< hold k3 at 0: narrow lenses do not constrain it (over-fits)
  bool fix_tangential = false;  ///< hold p1, p2 at 0
  int min_views = 5;            ///< fewer views with a board found is an error
};

struct ViewResult {
  std::string name;
  bool found = false;   ///< board detected
  double rms_px = 0.0;  ///< reprojection RMS of this view after calibration [px]
};

struct CalibrationResult {
  CameraModel model;
  double rms_px = 0.0;  ///< overall reprojection RMS (calibrateCamera's return) [px]
  std::vector<ViewResult> views;
  int used_views = 0;
};

/// Inner corners of the board in an 8-bit image, sub-pixel refined; nullopt when not found.
std::optional<std::vector<cv::Point2f>> find_chessboard(const cv::Mat& image,
                                                        const ChessboardParams& board);

/// The board's inner corners in its own plane (z = 0) [m], row by row as OpenCV orders them.
std::vector<cv::Point3f> chessboard_object_points(const ChessboardParams& board);

/// Calibrates from images (all the same size). nullopt and *error when too few boards are
/// found or sizes differ.
std::optional<CalibrationResult> calibrate_chessboard(const std::vector<cv::Mat>& images,
                                                      const std::vector<std::string>& names,
                                                      const ChessboardParams& board,
                                                      const std::string& camera_name,
                                                      std::string* error);

}  // namespace alight::camera

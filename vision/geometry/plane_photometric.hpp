#pragma once
// Dense photometric check of a platform top (false tops over a bare floor): where,
// between the floor's plane and the top's, the current image's pixels inside the top's hull are
// explained by the reference image. Plane plus parallax (Irani & Anandan, "Parallax geometry of
// pairs of points for 3D scene analysis", ECCV 1996; Sawhney, "3D geometry from planar parallax",
// CVPR 1994): with the floor's homography registered, a pixel's residual motion runs along its
// epipolar line and grows with the point's height above the floor, so one scalar, gamma (0: on
// the floor, 1: on the top's plane), indexes the planes parallel to both. A top found from
// features tracked a few pixels wrong is floor to every other pixel in its hull; a true top's
// pixels follow its plane. Beyond the paper, which tests the features alone.

#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "common/camera_model.hpp"
#include "common/geometry.hpp"
#include "vision/geometry/rolling_shutter.hpp"

namespace alight::vision {

struct PlanePhotometry {
  double gamma = 0;        ///< best fit between floor (0) and top (1), parabola-refined
  double sigma_gamma = 0;  ///< its standard deviation from the fit's curvature and residual
  double ncc_best = 0;     ///< zero-mean normalised cross-correlation at the best grid gamma
  int n = 0;               ///< pixels compared
};

/// gray_1 / gray_2: the reference and current raw images (CV_8UC1, the camera's size);
/// H_floor_px / H_top_px map undistorted reference pixels (K * ray) to the current ones;
/// pixels_u2: the current raw image's pixels compared (at least one pixel inside its border).
/// nullopt when fewer than min_pixels of them are seen in the reference at every gamma.
/// grid_1 / readout_2: the reference's rolling-shutter readout, tabulated, and the current
/// frame's (null or not rolling: a global shutter), with which the homographies, fitted to rays
/// at each frame's row 0 (rolling_shutter.hpp), are taken back to the raw pixels.
std::optional<PlanePhotometry> plane_photometry(
    const cv::Mat& gray_1, const cv::Mat& gray_2, const CameraModel& camera,
    const Matrix3d& H_floor_px, const Matrix3d& H_top_px, const std::vector<cv::Point>& pixels_u2,
    int min_pixels, const EpochPixelGrid* grid_1 = nullptr, const Readout* readout_2 = nullptr);

}  // namespace alight::vision

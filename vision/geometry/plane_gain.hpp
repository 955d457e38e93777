#pragma once
// The smooth gain between two views of one plane (beyond the paper). A real camera's image of a
// fixed point changes brightness as the point moves across the image: vignetting falls off
// towards the corners (to about half on small lenses), and what is left of an exposure change
// after the global correction is a gain too. Differencing the reference warped by the plane's
// homography against the current image (plane-induced parallax, warp_diff.hpp) then reads that
// falloff as disagreement on the plane itself, and the threshold that follows the plane's own
// difference rises until weak parallax in dim parts of the view is lost.
//
// The ratio of the current view to the reference's at a point of the plane is the ratio of the
// falloff at its two image positions, V(x_2) / V(x_1): smooth, and for a radial falloff and a
// near-affine homography quadratic in x_2 to first order (the falloff's gradient is linear in the
// position, the displacement near affine in it). So the log of the ratio of local means around
// the plane's inlier features is fitted with a quadratic in the current view's normalised
// coordinates, robustly (inliers next to the plane's border straddle it), kept only where it
// explains the points better than a constant by more than their noise, and the current image is
// divided by it: its pixels at the reference's photometry wherever the plane is seen. Beyond the
// points it was fitted to the gain is held within the range it takes on them; where too few
// points set it, there is none (1).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "common/camera_model.hpp"
#include "common/geometry.hpp"

namespace alight::vision {

/// log(current / reference) = c . [1, x, y, x^2, xy, y^2] at the current view's normalised
/// coordinates (x, y) = ((u - cx) / fx, (v - cy) / fy), bounded to [log_min, log_max] (the range
/// the fit takes at the points it was fitted to: no extrapolation beyond the plane's support).
struct PlaneGain {
  Eigen::Matrix<double, 6, 1> c = Eigen::Matrix<double, 6, 1>::Zero();
  double log_min = 0.0, log_max = 0.0;
  int n_used = 0;  ///< points the final fit kept

  double log_gain(double x, double y) const;
};

/// Fewer points than this fit a constant gain only: a quadratic needs support across the view.
inline constexpr int kMinPointsQuadratic = 24;
/// Fewer points than this: no gain (1).
inline constexpr int kMinPointsConstant = 6;

/// image / reference: the current and reference grey images as the caller differences them,
/// `scale` times smaller than the camera's (1: full size; pixel centres map as u_full =
/// scale (u + 0.5) - 0.5). H_21 maps the reference's undistorted pixels (K * ray) to the
/// current's; plane_px are the plane's inlier features in the current raw image (full size).
/// nullopt when fewer than kMinPointsConstant points have both windows inside their images and
/// a level above the noise.
std::optional<PlaneGain> fit_plane_gain(const cv::Mat& image, const cv::Mat& reference,
                                        double scale, const Matrix3d& H_21,
                                        const CameraModel& camera,
                                        const std::vector<Vector2d>& plane_px);

/// The current image (CV_8UC1, `scale` times smaller than the camera's) divided by the gain:
/// at the reference's photometry on the plane.
cv::Mat remove_gain(const cv::Mat& image, double scale, const CameraModel& camera,
                    const PlaneGain& gain);

}  // namespace alight::vision

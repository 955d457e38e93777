#pragma once
// Upright SURF descriptor (paper 3.1.1; Bay, Ess, Tuytelaars & Van Gool, "Speeded-Up Robust
// Features (SURF)", CVIU 110(3), 2008): Haar wavelet responses of size 2s on the integral image,
// sampled every s over a 20s x 20s window around the keypoint, weighted by a Gaussian of
// sigma 3.3s, summed per 4 x 4 sub-region as (sum dx, sum dy, sum |dx|, sum |dy|): 64 values,
// normalised to unit length. s follows the detected CenSurE scale.
//
// Beyond the paper: the sampling pattern (and the wavelet axes) can be rotated by a known
// angle. Upright descriptors tolerate about +-15 deg of rotation; when motion capture gives the
// camera orientation, describing every frame with its pattern aligned to one fixed world
// direction (waypoint.hpp pattern_angle) keeps frames matchable under any yaw, and costs no
// orientation assignment.

#include <opencv2/core.hpp>
#include <vector>

#include "vision/params.hpp"
#include "vision/star_detector.hpp"

namespace alight::vision {

constexpr int kSurfLength = 64;

/// Descriptors of the keypoints (one CV_32F row of 64 per keypoint, unit length), the sampling
/// pattern rotated by pattern_angle_rad (from the image u axis towards v).
cv::Mat describe_surf(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                      const SurfParams& params, double pattern_angle_rad = 0.0);

/// The SURF scale s of a keypoint.
double surf_scale(const Keypoint& kp, const SurfParams& params);

}  // namespace alight::vision

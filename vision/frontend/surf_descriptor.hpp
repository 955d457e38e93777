#pragma once
// Upright SURF descriptor (paper 3.1.1; Bay, Ess, Tuytelaars & Van Gool, "Speeded-Up Robust
// Features (SURF)", CVIU 110(3), 2008): Haar wavelet responses of size 2s on the integral image,
// sampled every s over a 20s x 20s window around the keypoint, summed per 4 x 4 sub-region as
// (sum dx, sum dy, sum |dx|, sum |dy|): 64 values, normalised to unit length. s follows the
// detected CenSurE scale.
//
// The sub-regions are laid out as in MU-SURF, the descriptor the CenSurE paper pairs with its
// detector (Agrawal, Konolige & Blas, ECCV 2008, sec. 4): they overlap by 2s on each side
// (8s x 8s every 4s), each is weighted by a Gaussian of sigma 2.5s about its own centre, and
// the 4 x 4 grid by a Gaussian of sigma 1.5 (sub-region units). SURF's disjoint 5s x 5s
// sub-regions under one window Gaussian (sigma 3.3s) remain as an option. Why: with disjoint
// sub-regions a sample moves from one bin to the next under a fraction of a pixel of shift, a
// few degrees of rotation or a scale error, so on fine texture (fur, foliage, gravel) the
// descriptor of the same point changed more between two views than it differs from its
// neighbours'; the warped photographs of features_test (baboon, graf1 at 12 deg, x0.9, blurred)
// gain a third to a half more correct matches with the overlapping layout, at equal cost.
//
// Beyond the paper: the sampling pattern (and the wavelet axes) can be rotated by a known
// angle. Upright descriptors tolerate about +-15 deg of rotation; when motion capture gives the
// camera orientation, describing every frame with its pattern aligned to one fixed world
// direction (waypoint.hpp pattern_angle) keeps frames matchable under any yaw, and costs no
// orientation assignment.

#include <opencv2/core.hpp>
#include <vector>

#include "vision/frontend/star_detector.hpp"
#include "vision/params.hpp"

namespace alight::vision {

constexpr int kSurfLength = 64;

/// Descriptors of the keypoints (one CV_32F row of 64 per keypoint, unit length), the sampling
/// pattern rotated by pattern_angle_rad (from the image u axis towards v).
cv::Mat describe_surf(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                      const SurfParams& params, double pattern_angle_rad = 0.0);

/// The same without the AVX2 variant (exposed for the test that both agree bit for bit).
cv::Mat describe_surf_scalar(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                             const SurfParams& params, double pattern_angle_rad = 0.0);

/// The SURF scale s of a keypoint.
double surf_scale(const Keypoint& kp, const SurfParams& params);

}  // namespace alight::vision

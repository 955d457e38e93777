#pragma once
// Ingress target (paper 3.3, Fig. 7): the dominant homography is the wall; matches off it are
// seen through the opening. Straight edges (Canny, then the probabilistic Hough transform of
// Matas, Galambos & Kittler, CVIU 2000, as cv::HoughLinesP) kept only when near-vertical or
// near-horizontal cut the image into cells; a 2D histogram counts wall inliers and off-wall
// features per cell, and the rectangular block of cells without any inlier that holds the most
// off-wall features (at least min_outliers; the smallest such block on a tie) is the opening.
// Its centre, intersected with the wall plane (paper 3.1.3), is the waypoint; its left and
// right borders at the centre row give the width (paper Fig. 12), top and bottom the height.

#include <opencv2/core.hpp>

#include "vision/mission_params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// `image` is the current grey image (raw pixels, as c.u2). Fails with kTooFewMatches /
/// kNoDominantPlane (no wall), kSmallBaseline / kDecompositionFailed, or kNoOpening.
TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const PipelineParams& params);

/// The near-vertical (x) and near-horizontal (y) cut positions of the image's straight edges,
/// sorted, merged, including the image borders. Exposed for tests.
void line_cuts(const cv::Mat& image, const IngressParams& params, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept_segments);

}  // namespace alight::vision

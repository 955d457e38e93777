#pragma once
// Ingress target (paper 3.3, Fig. 7): the opening in a wall in one frame, as four named stages:
//
//   1. wall (wall.hpp): which plane is the wall, the dominant homography or the nearer of two;
//      beyond the paper, where what is seen through it lies in front of it, a smooth wall's
//      plane from a handful of features under motion capture's motion (stages 2-4 again);
//   2. blocks (mask.hpp, cuts.hpp, blocks.hpp): the image cut into cells by straight lines (the
//      paper's edges of the grey image or, beyond it, the border of the off-wall mask), a 2-D
//      histogram of the wall's inliers and the features seen through the wall, and the block of
//      cells seen through the wall;
//   3. faces (faces.hpp, beyond the paper): each side of the block out across the wall's inner
//      face to its front edge;
//   4. opening (opening.hpp): the block on the wall plane (paper 3.1.3) gives the waypoint, the
//      width (paper Fig. 12) and the height, and the checks that it is an opening seen whole.
//
// docs/vision-ingress.md lists every rule, parameter and test.

#include <opencv2/core.hpp>

#include "vision/ingress/cuts.hpp"
#include "vision/ingress/faces.hpp"
#include "vision/ingress/mask.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// `image` is the current grey image (raw pixels, as c.u2), `reference` the reference frame's
/// (as c.u1; empty: the paper's edges of `image`, as with params.ingress.parallax_mask false).
/// Fails with kTooFewMatches / kNoDominantPlane (no wall homography), kSmallBaseline, the wall's
/// reason (kMotionDisagrees, kDecompositionFailed: wall.hpp), kNoOpening (no block of
/// min_outliers features seen through the wall), a waypoint's reason, or an opening's check
/// (opening.hpp: kOpeningTooSmall, kNotBehindWall, kPartialNotFramed, kPartialNotBehind,
/// kLowParallax); kPartialView for a block cut by the image border.
TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& reference, const PipelineParams& params);
/// The same with both frames' parallax_image() already made (`image_parallax`,
/// `reference_parallax`; an empty reference_parallax: the paper's edges of `image`).
TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& image_parallax, const cv::Mat& reference_parallax,
                                  const PipelineParams& params);

}  // namespace alight::vision

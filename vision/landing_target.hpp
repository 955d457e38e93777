#pragma once
// Landing target (paper 3.2, Fig. 5): the dominant homography of the matches is one plane, a
// second, locally sampled homography on its outliers another (homography.hpp
// fit_two_homographies); both are aligned and decomposed together (alignment.hpp). The nearer
// plane, parallel to the other and above it by a plausible step, is the elevated platform. Its
// inliers in the current image, intersected with its plane (paper 3.1.3, eqs. 4-6), give the
// platform's visible extent; the centre of that extent is the aiming point and its 3D waypoint,
// the extent widened by the features' expected shortfall (side_from_extent) its size.
// The platform height is the difference of the two planes' distances along the aiming ray.
//
// The paper takes the first homography as the floor; here the roles follow the geometry,
// because a richly textured platform top can hold more matches than the floor in view.

#include <opencv2/core.hpp>

#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// A side of the platform top from the extent (range) of its n features along it. Features
/// never sit on the top's edges (none where the detector's support reaches the floor, and n
/// draws over a side of length L span on average L (n - 1) / (n + 1): order statistics of the
/// uniform distribution), so the range falls short of the side; range (n + 1) / (n - 1) is its
/// unbiased estimate for features spread uniformly over the top (the minimum-variance unbiased
/// estimator of a uniform distribution's width). n < 2: the range itself.
double side_from_extent(double range_m, size_t n);

/// Fails with kTooFewMatches / kNoDominantPlane (no first plane), kNoTargetPlane (no second
/// plane, or it is no platform, or the images show its pixels or its floor's on another plane:
/// vision.landing.photometric_tol), kSmallBaseline / kDecompositionFailed. gray_1 / gray_2: the
/// reference and current raw images, CV_8UC1 of the camera's size; either empty or of another
/// kind: the features alone decide.
TargetOutcome find_landing_target(const Correspondences& c, const PipelineParams& params,
                                  const cv::Mat& gray_1 = cv::Mat(),
                                  const cv::Mat& gray_2 = cv::Mat());

}  // namespace alight::vision

#pragma once
// Landing target (paper 3.2, Fig. 5): the elevated platform's top in one frame, as three named
// stages:
//
//   1. planes (planes.hpp): the floor and the top as two planes of the matches, the paper's two
//      homographies or, beyond the paper, the known floor under motion capture's motion;
//   2. gates (gates.hpp): the checks that the second plane is a platform's top, each refusing
//      with its own reason;
//   3. extent (extent.hpp, rim.hpp): the top's features on its plane (paper 3.1.3, eqs. 4-6),
//      their rectangle widened by the features' expected shortfall, out to the top's rims
//      where the images show them; its centre is the aiming point and its waypoint, the height
//      the difference of the two planes' distances along the aiming ray.
//
// The gates that need the measured top (its level, its height, the images' check) run after
// the extent it depends on; docs/vision-landing.md lists every rule, parameter and test. The
// paper takes the first homography as the floor; here the roles follow the geometry, because a
// richly textured platform top can hold more matches than the floor in view.

#include <opencv2/core.hpp>

#include "vision/landing/extent.hpp"
#include "vision/landing/gates.hpp"
#include "vision/landing/outline.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// The platform in one frame, or why not. vision.landing.floor_prior chooses the planes:
/// "fallback" keeps the paper's where they give a platform (found or a partial view) on a floor
/// that is the known floor (floor_agrees) and takes the known floor's otherwise, the paper's
/// outcome standing where neither gives one; "always" and "off" use one source only. Fails with
/// the planes' reasons (planes.hpp), a gate's (gates.hpp), kTopPointsFew (under four
/// distinct top features placed on its plane), or the extent's (extent.hpp); kPartialView for a top
/// cut by either image's border (cut_by_border), kTopParallaxGap for one reaching into the
/// epipole's parallax gap (top_clear_of_epipole): both located, their centre not measured. gray_1 /
/// gray_2: the reference and current raw images, CV_8UC1 of the camera's size (the photometric
/// gate, and the extent out to the top's rim); either empty or of another kind: the features alone
/// decide. Where the planes find the floor alone (kNoTargetPlane) with both images and the known
/// floor, a top without features is measured by its outline (outline.hpp: found, a partial view, or
/// kOutlineOnFloor / kOutlineUnmatched and the stage's other refusals); regions_2: gray_2's
/// plain regions where the caller keeps them for other stages (outline.hpp's PlainRegions).
TargetOutcome find_landing_target(const Correspondences& c, const PipelineParams& params,
                                  const cv::Mat& gray_1 = cv::Mat(),
                                  const cv::Mat& gray_2 = cv::Mat(),
                                  const PlainRegions* regions_2 = nullptr);

}  // namespace alight::vision

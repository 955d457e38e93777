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
// Beyond the paper (issue 15, landing_lowtex): the rim search. The paper (Brockers et al., SPIE
// 2011, 3.2) finds the top's plane and its centre from the top's features and measures no size;
// its Fig. 6b notes that features alone fall short of a featureless region's true size, which is
// what a nearly blank top does here: its extent fell short by more than side_from_extent
// restores (20.4 and 22.1 cm tops measured 18.8 and 17.9 cm, refused as too narrow). Given both
// images, each side of the extent of a top seen whole (a cut top's size is never used) is
// searched outward in the top's plane (rim_search_m) for the top's rim: the mean grey level
// along lines parallel to the side, at offsets from it, read in the current image and in the
// reference at the same points of the top's plane (the top's homography: the plane-induced
// comparison of Irani & Anandan, ECCV 1996, as in warp_diff.hpp, but only along the lines
// searched). The rim is the first step outward that darkens (the top is lit as the floor is and
// the side faces, turned from the light, less; a top darker than what lies beyond keeps its
// features' extent) and stays dark to the search's end (a row of print on the top darkens and
// brightens again), and the reference must show it within rim_max_disagreement_px on the top's
// plane: the rim lies on the plane, while an edge of the floor or of a side face beyond moves
// differently between the views. The features' rectangle can be turned from the top's edges, and
// a line across a turned rim spreads its step: the rim's turn (at most rim_max_turn_deg) is the
// straight line through the steps of short stretches of the side, and the lines are read along
// it. Rims that agree on a turn turn the rectangle onto them. A side without a rim keeps the
// features' extent and its half of side_from_extent's widening (never wider than the evidence
// shows); with one, the side ends at the rim. The plane check (plane_photometric.hpp) reads the
// features' hull, not the rim's rectangle: the rim is measured only on a top the check accepts.
//
// The top's end (issue 15, landing_photo; beyond the paper): over a busy floor the mean grey
// beyond a rim need not step at all (a pale margin of print against a patterned floor, a
// photograph's mid-grey against a circuit board). A side without a rim step is then searched
// outward (top_end_search_m) for where the top's homography stops explaining the two images:
// at each offset, the share of the pixels whose grey differs between the views, read at the
// same point of the top's plane, by more than a threshold (top_end_min_diff, and twice the top's
// own differences just inside the side). On the top that share is near zero, whatever its
// texture; on a textured floor, which lies off the top's plane, it is large. The end is where
// it steps up (by top_end_min_rise) in most stretches of the side along one straight line, the
// line's turn read as the rim's. Where the floor beyond is flat, the top's homography explains
// it too and the step lies wherever the floor's texture begins: an upper bound, not the rim.
// So an end counts only where the share stays up over the 30 pixels beyond it (a busy floor,
// not the band that the edge of a rug moves by between the views) and where the floor's
// homography explains most of what the top's does not; a flat band of floor that ends along a
// straight line parallel to the side still passes, and would widen the top by the band.
//
// The paper takes the first homography as the floor; here the roles follow the geometry,
// because a richly textured platform top can hold more matches than the floor in view.

#include <opencv2/core.hpp>
#include <vector>

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

/// The plane check's verdict on the floor (beyond the paper, plane_photometric.hpp) from the
/// gammas of the patches around the floor's features (0 the floor's plane, 1 the top's): false
/// when their median is farther than photometric_tol from 0, or when 5 or more spread wider than
/// photometric_max_floor_spread (1.4826 times their median absolute deviation). A floor
/// homography that does not register the floor (a plane turned about a line through the view)
/// puts its patches on both sides of 0 while their median may still sit near it. Fewer than
/// photometric_min_patches: no verdict (true).
bool floor_patches_agree(std::vector<double> gammas, const LandingParams& params);

/// Beyond the paper: a second plane is told from the floor by its inliers that the floor's
/// homography (pixels, image 1 to 2) does not carry within threshold_px. False when more than
/// max_share of the top's inliers (top_in) fit the floor too: the "top" is the floor split by
/// tracking noise into two planes a few centimetres apart, or a plane fitted through the top and
/// the floor beside it. A true top's matches lie off the floor's transfer.
bool top_told_from_floor(const Correspondences& c, const std::vector<uint8_t>& top_in,
                         const Matrix3d& H_floor_px, double threshold_px, double max_share);

/// Fails with kTooFewMatches / kNoDominantPlane (no first plane), kNoTargetPlane (no second
/// plane, or it is no platform, or the images show its pixels or its floor's on another plane:
/// vision.landing.photometric_tol), kSmallBaseline / kDecompositionFailed. gray_1 / gray_2: the
/// reference and current raw images, CV_8UC1 of the camera's size (the plane check, and the
/// extent's sides out to the top's rim: rim_search_m); either empty or of another kind: the
/// features alone decide.
TargetOutcome find_landing_target(const Correspondences& c, const PipelineParams& params,
                                  const cv::Mat& gray_1 = cv::Mat(),
                                  const cv::Mat& gray_2 = cv::Mat());

}  // namespace alight::vision

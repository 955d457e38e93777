#pragma once
// Landing, stage 2 of 3 (planes -> gates -> extent): the checks that the second plane is a
// platform's top and not the floor, a chance set of matches or a plane through the top's edge
// and the floor beyond. Each refuses the frame with its own reason (vision/status.hpp), so a
// frame's target_t.reason says which gate refused it. In the order find_landing_target applies
// them: the top parallel to the floor (kTopNotParallel), the floor seen around it
// (kNoFloorAroundTop), its matches not the floor's (kTopFitsFloor), a baseline for a scale
// (kSmallBaseline); once the top's features are placed on
// its plane, the top level (kTopTilted); once it is measured (extent.hpp), its height in range
// (kHeightOutOfRange) and the images' check of both planes (kTopPhotometry, kFloorPhotometry).

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "vision/geometry/waypoint.hpp"
#include "vision/landing/planes.hpp"

namespace alight::vision {

/// A true top's matches fit the floor's transfer too only by their noise where the planes'
/// parallax is small (near the epipole, on a low top): a quarter of them at most; a floor split
/// by tracking noise into two planes a few centimetres apart has nearly half its "top" on the
/// floor's transfer.
constexpr double kMaxTopOnFloorShare = 0.25;

/// The gates on the planes alone, in order: the top's normal within max_normal_angle_deg of the
/// floor's (kTopNotParallel); unless the top is alone, the floor seen around it in at least
/// min_floor_inliers places (kNoFloorAroundTop, floor_seen_around_top); at most
/// kMaxTopOnFloorShare of the top's matches carried by the floor's homography too
/// (kTopFitsFloor, top_told_from_floor); motion capture's baseline_m at least min_baseline_m
/// for the scale of eq. 3 (kSmallBaseline). kOk when all pass. H_top_px / H_floor_px: the
/// planes' pixel homographies, image 1 to 2.
Reason plane_gates(const Correspondences& c, const LandingPlanes& planes, const Matrix3d& H_top_px,
                   const Matrix3d& H_floor_px, double baseline_m, const PipelineParams& params);

/// A platform top is opaque: the floor is seen around it, never through it. The floor's
/// matches seen outside the convex hull of the top's in image 2 (by more than threshold_px, or
/// inside it but off the top's plane: a match near the epipole fits both planes). The paper's
/// planes can split a bare floor into a "top" a few centimetres up that holds most of the view
/// and a "floor" of the rest, all of it inside that "top".
int floor_seen_around_top(const Correspondences& c, const LandingPlanes& planes,
                          const Matrix3d& H_top_px, double threshold_px);

/// Beyond the paper: a second plane is told from the floor by its inliers that the floor's
/// homography (pixels, image 1 to 2) does not carry within threshold_px. False when more than
/// max_share of the top's inliers (top_in) fit the floor too: the "top" is the floor split by
/// tracking noise into two planes a few centimetres apart, or a plane fitted through the top and
/// the floor beside it. A true top's matches lie off the floor's transfer.
bool top_told_from_floor(const Correspondences& c, const std::vector<uint8_t>& top_in,
                         const Matrix3d& H_floor_px, double threshold_px, double max_share);

/// A match fits a plane within threshold_px, about three times the tracking noise; where the two
/// planes' parallax is under kMinParallaxThresholds times that, a top match fits the floor's
/// transfer too by its noise alone.
constexpr double kMinParallaxThresholds = 2.0;

/// Beyond the paper: the top told from the floor all over it. The planes' parallax at a point of
/// the top in image 2 is how far the floor's homography puts it from where the top's does
/// (|H_floor H_top^-1 u - u|). Two parallel planes' homographies differ by a homology about the
/// epipole: the parallax vanishes there and grows with the distance from it. Where the camera
/// moved towards or away from the top (a descent or a climb over it) the epipole lies on or near
/// the top, the top's matches around it fit the floor as well and drop out of the top, and the
/// ones left make a rectangle of a part of the top, off its centre: such a top is located, not
/// measured (kTopParallaxGap, reported like a view cut by the border). False when the parallax at
/// the point of the top's inliers' convex hull nearest the epipole (none with the epipole inside
/// the hull) is under kMinParallaxThresholds x threshold_px. `mocap` places the epipole (camera
/// 1's centre seen from camera 2); fewer than 3 top inliers: true (the other gates decide).
bool top_clear_of_epipole(const Correspondences& c, const std::vector<uint8_t>& top_in,
                          const Matrix3d& H_floor_px, const Matrix3d& H_top_px,
                          const MocapMotion& mocap, double threshold_px);

/// The top level: its unit normal n_W (world, towards the camera) within max_tilt_deg of world
/// up. A "plane" through the platform's edge and the floor beyond is tilted by atan(h / d).
bool top_level(const Vector3d& n_W, const LandingParams& params);

/// The measured height between the planes within [min_height_m, max_height_m].
bool height_in_range(double height_m, const LandingParams& params);

/// A top cut by the border of either image (two or more of its inliers within edge_margin_px
/// of it): only features seen in both images are matched, so its extent is that of its visible
/// part, and one stray inlier there is no cut.
bool cut_by_border(const Correspondences& c, const LandingPlanes& planes,
                   const LandingParams& params);

/// The photometric gate's limits on gamma (0 the floor's plane, 1 the top's). find_landing_target
/// uses the defaults; each is a constant of the camera's noise and the planes' geometry.
struct PhotometricLimits {
  /// A pixel set sits on its own plane within this much of the height between the planes: a
  /// quarter, so a set placed within it is on one plane and not the other (a false top's pixels
  /// follow one surface, which is rarely both 1 for its hull and 0 for the floor's patches).
  double tol = 0.25;
  /// A pixel set whose best normalised cross-correlation between the images is lower shares too
  /// little texture to say where it is (blank paper, a grey tile): no verdict.
  double min_ncc = 0.5;
  /// A gamma less certain than this (its standard deviation, from the fit's curvature and
  /// residual) gives no verdict: under half the tolerance, so a certain gamma inside it is not
  /// a chance one. A floor patch (a hundred-odd pixels, not a hull's thousand) may be 3 times it.
  double max_sigma = 0.1;
  /// The top's pixels less certain than max_sigma still refuse it when their gamma lies beyond
  /// the tolerance by this many standard deviations (a chance of about 0.1 %): a hull on a false
  /// top over a busy floor can be blurred to a wide fit that still places it far from 1.
  double far_sigmas = 3.0;
  /// The floor's patches (5 or more) spread at most this far in gamma (1.4826 times their
  /// median absolute deviation): twice the tolerance. A floor homography that registers the
  /// floor spreads them by their noise (a tenth); one that does not (a plane turned about a line
  /// through the view) spreads them across both planes.
  double max_floor_spread = 0.5;
};

/// Beyond the paper, the images' verdict on the planes the features found (plane plus parallax,
/// geometry/plane_photometric.hpp): the pixels inside the top's features (their convex hull in
/// the current image) must follow the top's plane (else kTopPhotometry), and the patches around
/// the floor's features outside it the floor's (floor_patches_agree, else kFloorPhotometry).
/// False tops over a bare floor are features tracked a few pixels wrong: every other pixel of
/// their "top" and their "floor" lies on one surface, at one gamma, and rarely at 1 and 0. A
/// pixel set too bland or too uncertain to tell gives no verdict (blank paper, a grey tile): the
/// features decide. gray_1 / gray_2: the reference and current raw images of the camera's size.
Reason photometric_gate(const Correspondences& c, const LandingPlanes& planes,
                        const Matrix3d& H_floor_px, const Matrix3d& H_top_px, const cv::Mat& gray_1,
                        const cv::Mat& gray_2, const PhotometricLimits& limits = {});

/// The plane check's verdict on the floor from the gammas of the patches around the floor's
/// features (0 the floor's plane, 1 the top's): false when their median is farther than
/// limits.tol from 0, or when 5 or more spread wider than limits.max_floor_spread (1.4826 times
/// their median absolute deviation). A floor homography that does not register the floor (a
/// plane turned about a line through the view) puts its patches on both sides of 0 while their
/// median may still sit near it. No patch: no verdict (true); one decides: a false top that
/// covers most of the view leaves one or two of the floor's features clear of it.
bool floor_patches_agree(std::vector<double> gammas, const PhotometricLimits& limits = {});

}  // namespace alight::vision

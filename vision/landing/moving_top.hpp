#pragma once
// A moving platform's top between two frames (beyond the paper; its 3.2 and eqs. 2-6 assume a
// still scene).
//
// Why the paper's planes miss a moving platform: both homographies, and the known floor's
// fit, explain the matches by the camera's motion alone. The top's matches still lie on one
// plane, but that plane moved between the exposures: its homography is that of the camera's
// motion composed with the platform's, so decomposed with the camera's motion it gives a height
// and a position that are the platform's motion in disguise (a cart at 1 m/s moves 25 cm in a
// quarter second, ten times the parallax of a 15 cm top), and the gates refuse it.
//
// What is measured instead. Motion capture (or the estimate) gives both camera poses, so the
// camera's own motion is removed exactly: every ray is placed in the world. The floor's matches
// are the ones the known floor (z = floor_z_m) carries from one view to the other (eq. 2 with
// motion capture's metric motion). The others are intersected with a level plane at the top's
// height, once from each view; for a level top these two point sets are the top's points at the
// two exposures, related by the platform's rigid motion (a turn about z and a displacement).
// Where the assumed height is off by dh, each view's points are scaled about its camera's nadir
// by (z_c - h_assumed) / (z_c - h), so the two sets are related by a similarity whose scale
// s = k_2 / k_1 also carries the top's heave (a deck) over the interval. A similarity fitted by
// RANSAC (two matches a draw, seeded) gives the top's inliers, its displacement, its turn and
// its heave (a few matches apart from the rest that share its motion by chance left out: the
// top is one region); the inliers' rectangle its centre, size and yaw, on a top seen whole along
// the axes of the top's edges by the pixels that follow its motion (moving_edges.hpp: a print's
// subject can be a blob off the top's centre and turned from it). A set that is a cluster
// of the floor's matches, or whose motion no platform makes (a floor pattern matched to its next
// copy), is set aside and the next motion taken; gates refuse the floor's alone, an implausible
// motion alone, a size out of range, and a motion that a still top explains as well (a pattern
// repeated along the top: its descriptors match the next copy, one period away, and those
// matches share one rigid motion), each with its own reason.
//
// The height: a plane that moves on its own has no observable depth from two views with a level
// camera (its motion absorbs the baseline). It is taken as moving_top.top_height_m; the error
// this leaves (position: dh times the tangent of the view angle; velocity: dh over the camera's
// height times the speed relative to the camera) vanishes as the vehicle comes over the
// platform and matches its speed, which is what the approach does. Over many pairs the height is
// observable: a camera climbing or descending reads a top dh above the plane as rising at
// dh (z_1 - z_2) / (dt (z_1 - h)). So each measurement carries its two cameras and the plane,
// and autonomy's platform filter measures the height and places the top again (TopHeight).

#include <cassert>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "common/geometry.hpp"
#include "vision/landing/moving_top_params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// Why no moving top was measured; values equal platform_motion_t's REASON_*.
enum class MovingReason : int8_t {
  kOk = 0,
  kNoEarlierFrame = 1,  ///< no frame within max_interval_s (and kMovingMaxScaleChange of the
                        ///< camera's range to the top, pipeline.hpp) to measure the motion against
  kNotAboveFloor = 2,   ///< a camera not above the floor (no known floor)
  kTooFewCandidates = 3,  ///< fewer than min_inliers matches off the floor
  kNoCommonMotion = 4,    ///< no min_inliers of them share one rigid motion
  kOnFloor = 5,           ///< the set's matches are the floor's (max_floor_share)
  kTooFast = 6,           ///< faster than max_speed_mps / max_yaw_rate_dps, or a scale change
                          ///< beyond max_scale_change (the first set set aside so)
  kSizeOutOfRange = 7,    ///< the inliers' extent outside [min_size_m, max_size_m] (a cut
                          ///< top: longer than max_size_m)
  kStillTop = 8,          ///< a still top explains as many matches (a pattern repeated along
                          ///< the top matched to its next copy)
  kStillPixels = 9,       ///< a still top explains the set's pixels as well as its motion does
                          ///< (a repeated pattern whose still matches the ratio test dropped)
  kOutlineUnpaired = 10,  ///< too few features, and a featureless outline in view that no
                          ///< earlier outline follows by a platform's motion (moving_outline.hpp)
};

const char* to_string(MovingReason r);

/// A set of matches is the floor's (kOnFloor) when more than max_floor_share of them lie within
/// this many floor_tol_px of where the known floor carries them: a floor cluster just outside the
/// tolerance (motion capture's noise and stamp) is set aside with the floor.
inline constexpr double kFloorClusterTols = 3.0;

/// The top's state at the current exposure, from its motion since the earlier one.
struct MovingTop {
  MovingReason reason = MovingReason::kOk;
  bool found() const { return reason == MovingReason::kOk; }
  double dt_s = 0.0;                ///< between the two exposures [s]
  Vector3d p_W = Vector3d::Zero();  ///< centre of the inliers' rectangle (z: top_height_m + heave)
  /// p_W's mean velocity over the interval as a point of the top (its turn's lever arm from the
  /// matches' centroid included; z: from the heave) [m/s]
  Vector3d v_W = Vector3d::Zero();
  double yaw_rad = 0.0;       ///< long axis of the inliers' rectangle, (-pi/2, pi/2]
  double yaw_rate_rps = 0.0;  ///< its turn over the interval / dt_s [rad/s]
  double scale = 1.0;         ///< s of the similarity (heave, height error)
  /// The cameras the top was placed from (current, earlier) and the plane it was placed on
  /// (floor_z_m + top_height_m): a reader that follows the top measures its height from them.
  Vector3d camera_W = Vector3d::Zero(), ref_camera_W = Vector3d::Zero();
  double plane_z_m = 0.0;
  /// The top cut by the current image's border (edge_margin_px): its motion is measured, its
  /// centre is not (cov_p_W's horizontal block 100 m^2; p_W the visible part's centre).
  bool cut = false;
  Matrix3d cov_p_W = Matrix3d::Zero();  ///< [m^2]
  Matrix3d cov_v_W = Matrix3d::Zero();  ///< [m^2/s^2]
  double var_yaw = 0.0, var_yaw_rate = 0.0;
  /// The inliers' extent (long, short); zero where they reach two opposite borders (the top
  /// fills the view across: the extent is the view's) [m]
  double size_m[2] = {0, 0};
  int n_candidates = 0;  ///< matches off the floor (by its outline: the outlines in view)
  int n_inliers = 0;     ///< matches on the top (by its outline: its four corners)
  /// Measured by its outline in both frames (moving_outline.hpp), not by its features.
  bool outline = false;
  /// Its rectangle's axes (yaw) are the top's edges' by its motion (moving_edges.hpp), and so are
  /// its centre and size where the features cover under kBlobShare of it.
  bool edges = false;
  /// The set's pixels against the earlier image (kStillPixels): their normalised
  /// cross-correlation where a still top had them and where the measured motion had them; NaN
  /// where not compared (no images, too few pixels seen in both).
  double ncc_still = NAN, ncc_moving = NAN;
  std::vector<uint8_t> inliers;  ///< per correspondence
};

/// The top's motion between c's reference (pose_1) and current (pose_2) views, dt_s apart.
/// gray_1 / gray_2: the two raw images (CV_8UC1 of the camera's size) for the kStillPixels
/// gate; empty: no such gate.
MovingTop find_moving_top(const Correspondences& c, double dt_s, double floor_z_m,
                          const MovingTopParams& params, const cv::Mat& gray_1 = {},
                          const cv::Mat& gray_2 = {});

/// A 2-D similarity q = s R(theta) p + t.
struct Similarity2 {
  double s = 1.0, theta = 0.0;
  Vector2d t = Vector2d::Zero();
  Vector2d apply(const Vector2d& p) const;
};

/// Matches that stay put inside the moving set's footprint, against the moving set's inliers: at
/// least this share and a still top explains the view as well (kStillTop). A cart hides the
/// floor under it and has no still matches of its own (a stopped one's are its moving set); a
/// still top whose pattern repeats keeps its true matches beside the ones to the next copy,
/// though the ratio test drops most of both (each feature has a twin), so a quarter is asked.
inline constexpr double kStillShare = 0.25;

/// The set's pixels that a still top explains (the median patch correlation where a still top
/// had each feature) within this of what its motion explains: the motion is no better than a
/// still top's, and the set is a pattern repeated along a still top (kStillPixels). Each
/// feature of a repeated print has a twin in its own image, so the ratio test drops most of
/// its still matches with the ones to the next copy and what survives of either is chance:
/// kStillTop's count of still matches misses it, the pixels do not (they follow both within a
/// few hundredths). Where a moving top's feature was lies now the floor or another part of
/// it, a third or more below the motion's correlation.
inline constexpr double kStillNccGap = 0.15;

/// A motion no platform makes (kTooFast): faster than max_speed_mps, turning faster than
/// max_yaw_rate_dps, or scaled beyond max_scale_change over dt_s.
bool motion_beyond_a_platform(double speed_mps, const Similarity2& S, double dt_s,
                              const MovingTopParams& params);

/// The covariances of a top measured from n points on its plane (out->plane_z_m set), their
/// fit's residual variance var_r per coordinate [m^2] and spread (their summed squared distance
/// from their centre) [m^2]: position and velocity from the residuals over n points and the
/// height's uncertainty (a height error scales each view's points about its camera's nadir: the
/// centre moves along its offset from the current camera's nadir, the velocity along the speed
/// relative to the camera), z from the scale's variance var_r / spread, and the turn's rate.
/// Sets cov_p_W, cov_v_W, var_yaw_rate; returns the scale's (and the turn's) variance.
double set_covariances(double var_r, double n, double spread, const Vector2d& centre_W,
                       const Vector2d& vel_W, const Vector3d& ref_camera_W,
                       const Vector3d& camera_W, double dt_s, const MovingTopParams& params,
                       MovingTop* out);

/// Least-squares similarity from p to q (Umeyama 1991, in 2-D); nullopt when p has no extent.
std::optional<Similarity2> fit_similarity(const std::vector<Vector2d>& p,
                                          const std::vector<Vector2d>& q);

}  // namespace alight::vision

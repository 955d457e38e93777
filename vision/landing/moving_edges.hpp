#pragma once
// A moving top's edges by its motion (beyond the paper, as moving_top.hpp; a stage of
// find_moving_top after its gates).
//
// A top whose print gives features over part of it (a photograph's subject in its middle, the
// background plain) has a features' rectangle that is the subject's: its sides, centre and yaw
// are those of a blob that can sit anywhere on the top at any angle, the same in every view, so
// no number of views tells it from the top. The top's edges are in both images, and the top's
// plane follows the top's measured motion (the similarity S over the interval) while the floor
// stays put. Over a window of the top's plane around the features, at the current exposure:
//
//   1. cells: a square grid on the top's plane, a cell kCellGsd ground samples of the current
//      camera at the top's depth (or the window over kMaxCells, whichever is larger); each cell's
//      pixel in the current image, in the earlier image where the top's motion had it (S^-1) and
//      where the floor point on the same current ray lies (a still floor); the three images
//      resampled on the grid (Irani & Anandan's plane-induced comparison, ECCV 1996, with the top's
//      motion in the plane's place) and smoothed over a cell (the poses' noise);
//   2. votes: over kPatchCells^2 cells, the mean squared difference of the current resample from
//      each hypothesis's; a cell is the top's where the motion's difference is at most kVoteRatio^2
//      of the still floor's and the floor's is above kMinDiff^2 (a plain area on both sides, or
//      noise, votes for neither), the floor's the other way round; a cell the two hypotheses place
//      within kMinSeparationPx of each other in the earlier image has no vote. The top's rim, an
//      edge that moves with the top, votes for the top on every side whatever the print inside;
//   3. rectangle: the top's cells' minimum-area rectangle, its extent along each direction trimmed
//      of kTrimShare at both ends (cells of a floor pattern that follow the motion by chance);
//   4. checks: each side carried by top cells within kBandCells of it along kSideSupport of its
//      length (the rim seen all round: the rectangle of a blob in plain print has no votes along
//      most of its sides), at most kMaxFloorInside of the cells inside it the floor's, the
//      rectangle and kBandCells around it inside both images and the window (a side at the image's
//      border is the border's), every feature of the set inside it, and its sides within the
//      sizes a top has (min_size_m, max_size_m);
//   5. the sides: the votes also carry what moves with the top below it (a side face in view,
//      the platform's shadow on the floor), a few centimetres past a rim; where the features'
//      extent along the rectangle's axes (widened by their shortfall, extent.hpp) covers
//      kBlobShare of its area or more, it gives the sides (its yaw the rectangle's); under that,
//      the print's subject is a blob and the votes' sides stand.
//
// nullopt where any of stages 1-4 fails: the features' rectangle stands.
//
// A print plain towards the top's trailing end: where the top covered the floor at the earlier
// exposure too, both hypotheses explain a plain print, and the trailing rim's patches hold floor
// that neither explains: the votes can stop at the print's subject there, and the rectangle is
// short of the top on that side (its yaw still the sides').

#include <optional>
#include <vector>

#include "vision/landing/extent.hpp"
#include "vision/landing/moving_top.hpp"

namespace alight::vision {

/// A cell spans this many ground samples of the current camera: a resample at about the image's
/// own resolution smoothed over one cell loses no edge and averages the pixel's noise.
inline constexpr double kCellGsd = 2.0;
/// At most this many cells along the window's side (its cost grows with their square).
inline constexpr int kMaxCells = 201;
/// The window reaches this far past the features' rectangle on every side [m]: a 0.44 m top whose
/// print's subject covers a 0.2 m blob off its centre, turned 35 deg from the top.
inline constexpr double kEdgeReachM = 0.25;
/// Cells along a patch's side: a rim's step seen across several cells.
inline constexpr int kPatchCells = 5;
/// One hypothesis explains a cell when its mean squared difference is at most kVoteRatio^2 of the
/// other's.
inline constexpr double kVoteRatio = 0.5;
/// A hypothesis is refuted only by a difference above this RMS [grey levels] (sensor noise of a
/// few levels, an exposure's step of a few more).
inline constexpr double kMinDiff = 8.0;
/// A hypothesis explains a cell only within this RMS [grey levels]: where the platform uncovered
/// the floor during the interval (behind a moving top) neither does, and neither votes.
inline constexpr double kExplainedDiff = 30.0;
/// The two hypotheses place a cell at least this far apart in the earlier image to vote [px].
inline constexpr double kMinSeparationPx = 3.0;
/// The rectangle's extents trimmed of this share of the top's cells at each end.
inline constexpr double kTrimShare = 0.01;
/// A side is the rim where top cells lie within this many cells inside it ...
inline constexpr int kBandCells = 3;
/// ... along at least this share of its length (in kSideSegments stretches).
inline constexpr double kSideSupport = 0.5;
inline constexpr int kSideSegments = 8;
/// At most this share of the cells inside the rectangle may vote for the floor.
inline constexpr double kMaxFloorInside = 0.03;
/// Features whose extent covers under this share of the votes' rectangle are a print's subject,
/// not the top: a top printed all over gives features to within their shortfall of its rims
/// (nine tenths of its area and more), the orange photograph's fruit a third of it.
inline constexpr double kBlobShare = 0.5;

/// The top's rectangle at the current exposure with the edges' axes (long, short) and its yaw's
/// variance.
struct EdgesRect {
  TopRect rect;
  double var_yaw = 0;  ///< [rad^2]
};

/// The top's EdgesRect; nullopt where no rectangle passes the checks. features: the set's
/// features' rectangle (features_extent) of pts_W, its features on the top's plane z_top (current
/// exposure); S: the top's motion over the interval (earlier to current, on the plane at z_top);
/// X_WC1 / X_WC2: the cameras; gray_1 / gray_2: the raw images, of the camera's size.
std::optional<EdgesRect> edges_by_motion(const Correspondences& c, const Isometry3d& X_WC1,
                                         const Isometry3d& X_WC2, const Similarity2& S,
                                         double z_top, double floor_z_m, const TopRect& features,
                                         const std::vector<Vector3d>& pts_W,
                                         const MovingTopParams& params, const cv::Mat& gray_1,
                                         const cv::Mat& gray_2);

}  // namespace alight::vision

#pragma once
// A moving platform's top without features enough for its common motion, measured from its
// outline in both frames (beyond the paper, as moving_top.hpp; the outlines are outline.hpp's).
//
// A top whose print is plain at the search height (a smooth photograph at a millimetre a texel,
// a painted board) gives a handful of matches; fewer than min_inliers share one motion and
// find_moving_top refuses kTooFewCandidates or kNoCommonMotion (or, over a floor whose pattern
// repeats, for the floor's sets found first: kTooFast, kOnFloor), while the top is plain to see
// as a featureless rectangle over a busy floor. The still landing finds such a top by its outline
// (featureless_outlines) and reads its height from the reference's rim; a moving top's rim is not
// where any still plane puts it (kOutlineUnmatched). Here the outline is found in both frames and
// its corners, placed on the top's plane from each view, are the top's corners at both
// exposures, related by the top's similarity as its features would be:
//
//   1. placed: each outline's corners on the plane floor_z_m + top_height_m from its own camera;
//   2. still: a current outline that an outline of the same shading in any recent frame at
//      least interval_s old (a younger one leaves a slow platform's motion within the tolerance)
//      matches as a rectangle that stayed put at some height from the floor up to kStillTopHeights
//      times the top's assumed height (the level plane through it carries each corner from view to
//      view within kOutlineStillPx) is the floor's pattern or a still top, the still landing's
//      (kOnFloor below half the assumed top height, else kStillTop): a chessboard's square is
//      such an outline in every frame, and a square paired with its neighbour would move by one
//      period, at a platform's speed;
//   3. paired: in each recent frame, among its outlines of the same shading and the cyclic
//      orders of their corners (a quadrilateral's order around it is kept by a turn, its start
//      is not), the similarity that carries every corner within kOutlinePairPx at its depth,
//      with a scale within max_scale_change, and of those the least turn (a platform turns a few
//      degrees an interval; a quarter turn is the next order of a rectangle's corners); then two
//      such frames at least kMinOutlineSpanS apart whose paired outlines' centres lie with the
//      current one's on one straight track at one speed (within kOutlinePairPx): a floor's
//      repeated pattern paired with a copy one period on stays put between the earlier frames
//      [else kOutlineUnpaired]. The longer interval of the two is measured;
//   4. gates: a motion no platform makes (max_speed_mps, max_yaw_rate_dps) [kTooFast]; sides
//      outside [min_size_m, max_size_m] [kSizeOutOfRange];
//   5. the measurement: the current corners' centre, sides and heading; the centres'
//      displacement, the turn and the heave (the scale, as find_moving_top's) over the
//      interval; covariances from the corners' fit and kOutlineCornerPx, and the height's
//      uncertainty as find_moving_top's.
//
// The outline's corners are the top's whole rectangle, not a shortfall of features, so its size
// is not widened and its centre has no lever arm.

#include <vector>

#include "vision/landing/moving_top.hpp"
#include "vision/landing/outline.hpp"

namespace alight::vision {

/// A corner of a refined outline is where two fitted edge lines meet; its error is about a
/// pixel (the edges' step located to a few tenths over a side, the blur of the exposure's
/// motion across it): the floor of its variance in the covariances [px].
inline constexpr double kOutlineCornerPx = 1.0;

/// The same top's outline in two frames a quarter second apart puts its corners up to several
/// pixels apart beyond the top's motion (a plain print's region grows or shrinks with the
/// exposure and the blur, a deck tilts a degree, the top's side faces show on one side): the
/// corners that a pairing (stage 3) or a still rectangle (stage 2) must carry within [px].
/// A quarter turn of a rectangle's corners is tens of pixels off; the half turn fits as well
/// and the least turn chooses.
inline constexpr double kOutlinePairPx = 8.0;

/// An outline shows a motion of its own only where no still rectangle explains its corners
/// within twice that [px]: a floor's plain patch whose region changes a little from frame to
/// frame (the exposure, the blur) fits a similarity with a few centimetres of motion, a still
/// rectangle a few pixels worse; a platform moves tens of pixels in an interval (a deck at
/// 0.3 m/s under a camera 1.4 m above, 36 px), and more where the camera follows it.
inline constexpr double kOutlineStillPx = 2 * kOutlinePairPx;

/// The outlines found per frame for the moving top (featureless_outlines' largest): twice the
/// still landing's, as the top must be among them in both frames, and a busy floor's plain
/// patches of the top's size often outnumber it in one of them.
inline constexpr size_t kMaxMovingOutlines = 2 * kMaxOutlines;

/// The still rectangles stage 2 sets aside stand from the floor up to this many times the top's
/// assumed height (top_height_m): the floor's pattern and still tops of a platform's height.
/// A rectangle moving along the camera's baseline reads as still at some other height (its
/// motion and the baseline's parallax are one), so the heights are bounded: a platform at the
/// assumed height moving along the camera's travel by more than about a tenth of it reads as
/// still only above twice that height or below the floor.
inline constexpr double kStillTopHeights = 2.0;

/// Two earlier frames that confirm a pairing (stage 3) are at least this far apart in time
/// [s]: a floor pattern's region paired with a copy one period on in two frames close together
/// shows one speed in both, the copy staying put between them; over a tenth of a second and more
/// the copy's stillness is tens of pixels off the track a platform's motion draws.
inline constexpr double kMinOutlineSpanS = 0.1;

/// An earlier frame's outlines, its pose and readout (null: a global shutter), dt_s before the
/// current exposure.
struct EarlierOutlines {
  const std::vector<Outline>* outlines = nullptr;
  PoseSample pose;
  const Readout* readout = nullptr;
  double dt_s = 0.0;
};

/// The top's motion from its outline: `now` the current frame's plain outlines (not empty),
/// `earlier` those of recent frames; c gives the camera, its mount, the current pose and
/// readout (its matches and reference are not used). The measurement as find_moving_top's,
/// against the earlier frame *used (n_candidates: the current outlines; n_inliers: the four
/// corners; `outline` set), or the first current outline's refusal (stages 2-4),
/// kOutlineUnpaired where none was paired and confirmed.
MovingTop find_moving_outline(const std::vector<EarlierOutlines>& earlier,
                              const std::vector<Outline>& now, const Correspondences& c,
                              double floor_z_m, const MovingTopParams& params,
                              size_t* used = nullptr);

}  // namespace alight::vision

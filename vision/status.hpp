#pragma once
// Vision's runtime outcomes (docs/ARCHITECTURE.md "Errors: three tiers"): a stage that cannot
// give a trustworthy answer returns a Reason instead of a value, never garbage. The numeric values
// of Reason equal target_t's REASON_* constants (lcmtypes/target_t.lcm), so the node copies them
// without a table; test/vision/status_test.cpp pins the correspondence.

#include <cassert>
#include <cstdint>
#include <optional>
#include <utility>

namespace alight::vision {

enum class Reason : int8_t {
  kOk = 0,
  kNoPose = 1,               ///< no motion-capture pose at the image time
  kNoReference = 2,          ///< no reference frame yet (first frames, after a reset)
  kTooFewFeatures = 3,       ///< blank / textureless image
  kTooFewMatches = 4,        ///< fewer than 4 correspondences (or fewer than the minimum)
  kSmallBaseline = 5,        ///< camera moved too little for a usable scale / decomposition
  kNoDominantPlane = 6,      ///< no homography with enough inliers (all outliers)
  kNoTargetPlane = 7,        ///< only one plane in view
  kNoOpening = 8,            ///< ingress: no block of cells seen through the wall
  kDecompositionFailed = 9,  ///< no decomposition puts the plane in front of both cameras
  kBadImage = 10,            ///< empty, wrong type or too small
  kPartialView = 11,         ///< target found but cut by the image border: its centre is unknown
  kLowParallax = 12,  ///< ingress: the opening in view, but too little parallax to measure it
  kMotionBlur = 13,   ///< landing: the frame or its reference smeared by the camera's motion
  // Each gate of the landing and ingress targets refuses with its own reason (gates.hpp,
  // known_floor.hpp, wall.hpp, opening.hpp; docs/vision-landing.md, docs/vision-ingress.md).
  kTopNotParallel = 14,       ///< landing: the top's plane not parallel to the floor's
  kNoFloorAroundTop = 15,     ///< landing: the floor not seen around the top (a top is opaque)
  kTopFitsFloor = 16,         ///< landing: the top's matches fit the floor's homography too
  kTopTilted = 17,            ///< landing: the measured top not level
  kHeightOutOfRange = 18,     ///< landing: the top's height above the floor out of range
  kTopPhotometry = 19,        ///< landing: the top's pixels do not follow the top's plane
  kFloorPhotometry = 20,      ///< landing: the floor's patches do not follow the floor's plane
  kTopFitDiverged = 21,       ///< landing, known floor: the pair's refinement left its bounds
  kTopAloneTooFew = 22,       ///< landing, top alone: too few matches share its distance
  kTopAloneFloorSeen = 23,    ///< landing, top alone: the floor is in sight beside it
  kTopAloneLowRise = 24,      ///< landing, top alone: too little above the floor
  kTopAloneLowParallax = 25,  ///< landing, top alone: parallax under the rotation's error
  kMotionDisagrees = 26,      ///< a plane's motion disagrees with motion capture's
  kOpeningTooSmall = 27,      ///< ingress: the opening narrower or lower than min_size_m
  kNotBehindWall = 28,        ///< ingress: the block's view not behind the wall
  kPartialNotFramed = 29,     ///< ingress: a block at the border without the wall around it
  kPartialNotBehind = 30,     ///< ingress: a block at the border whose view is not behind
  // A frame refused for what the camera or its driver did to it (frontend/frame_checks.hpp).
  kExposureChange = 31,  ///< the brightness stepped beyond ExposureGuard::kStepEv: not tracked
  kDuplicateFrame = 32,  ///< the previous frame's pixels again (the driver's repeat): not tracked
  kFrameGap = 33,        ///< no reference: a gap in the frames' times broke the tracks
  kTopParallaxGap = 34,  ///< landing: seen in part, the top reaching into the epipole's gap
  // A top without features, found by its outline (landing/outline.hpp).
  kOutlineOnFloor = 35,    ///< landing: a featureless outline that moves with the floor
  kOutlineUnmatched = 36,  ///< landing: a featureless outline the reference does not show
  kOutlineSilent = 37,     ///< landing: a featureless outline none of whose sides tells a height
  kTopRunsOn = 38,    ///< landing: seen in part, the top running on past its features (rim.hpp)
                      ///< or past a featureless outline printed on it (outline.hpp)
  kTopTooSmall = 39,  ///< landing: a featureless outline narrower than the vehicle's gear
  // The geometry's refusals past the homographies, each its own (decomposition.hpp,
  // alignment.hpp, waypoint.hpp, extent.hpp, outline.hpp).
  kDecompositionAmbiguous = 40,  ///< two decompositions in front, no prior to choose between them
  kPlanesDisagree = 41,          ///< no pair of the two planes' decompositions agrees in motion
  kAlignedPlaneBehind = 42,      ///< the jointly refined motion puts a plane behind a camera
  kAimBehindCamera = 43,         ///< the target's centre or its ray not in front on its plane
  kCornerOffPlane = 44,          ///< landing: a featureless outline's corner ray misses its plane
  kTopPointsFew = 45,  ///< landing: under 4 distinct top features placed on the top's plane
  // The known floor's refusals of a top (known_floor.hpp).
  kTopMatchesFew = 46,  ///< landing: a top's height shared by under min_platform_inliers matches
  kNoTopHeight = 47,    ///< landing: no match off the known floor in the top's height range
};

/// The floor alone explains the view, no top plane with enough matches on it (the paper's second
/// homography, or the known floor's top): where a top without features may still be outlined.
inline bool no_top_plane(Reason r) {
  return r == Reason::kNoTargetPlane || r == Reason::kTopMatchesFew || r == Reason::kNoTopHeight;
}

const char* to_string(Reason r);

/// Not found, but located: in view and worth flying to, never averaged into an estimate.
inline bool located_only(Reason r) {
  return r == Reason::kPartialView || r == Reason::kLowParallax || r == Reason::kTopParallaxGap ||
         r == Reason::kTopRunsOn;
}

/// A value or the reason there is none.
template <class T>
class Result {
 public:
  static Result ok(T value) { return Result(std::move(value)); }
  static Result fail(Reason reason) {
    assert(reason != Reason::kOk);
    return Result(reason);
  }

  bool has_value() const { return value_.has_value(); }
  explicit operator bool() const { return has_value(); }
  Reason reason() const { return reason_; }
  const T& value() const {
    assert(has_value());
    return *value_;
  }
  T& value() {
    assert(has_value());
    return *value_;
  }
  const T& operator*() const { return value(); }
  const T* operator->() const { return &value(); }

 private:
  explicit Result(T value) : value_(std::move(value)), reason_(Reason::kOk) {}
  explicit Result(Reason reason) : reason_(reason) {}
  std::optional<T> value_;
  Reason reason_;
};

}  // namespace alight::vision

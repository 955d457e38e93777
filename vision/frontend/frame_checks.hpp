#pragma once
// Checks of a frame as the camera delivered it, before its features (beyond the paper, whose
// camera had a fixed exposure and a dependable driver).
//
// Automatic exposure. A camera on automatic exposure changes its exposure and gain in steps (up
// to +-2 EV when a window or a bright top enters the view) and brings them back over a few
// frames. The front end is mostly invariant to a gain: the SURF descriptor is normalised to unit
// length and its Haar responses cancel an offset. Three things are not. The STAR detector's
// threshold is in grey levels while a blob's response scales with the gain, so at -1 EV the
// weaker half of the blobs fall under it; a step saturates (up) or buries in noise (down) much of
// the frame, so the frame-to-frame tracks break and the reference is lost; and the comparisons
// of the reference's pixels with the current ones (the landing's rim and top-end search, the
// ingress parallax mask) difference grey levels. So:
// - the frame's brightness level is its mean grey level over every fourth pixel of every fourth
//   row, and the settled level an exponential average of the levels of the frames taken within
//   kDeadBandEv of it (a frame farther is on its way back from a step);
// - a frame more than kStepEv from the settled level, or with kClipStep more of its pixels
//   clipped than the settled share (a step up on a bright view saturates, so its level's ratio
//   falls short of the step), is an exposure step: refused
//   (REASON_EXPOSURE_CHANGE) before its features and never tracked, so the tracks and the
//   reference live on across the step, as across a dropped frame. A step that lasts longer than
//   kMaxStepS is no step of the exposure control (which settles within a few frames) but the
//   scene's own change: its level becomes the settled one;
// - between kDeadBandEv and kStepEv the detector's threshold is scaled by the level's ratio, so
//   the same blobs pass it, and a reference image is scaled by the ratio of the two frames'
//   levels before it is differenced with the current one (gain_between). Within kDeadBandEv
//   nothing changes: the scene's own brightness varies that much as the view moves.
//
// The driver. A driver that hands the previous buffer out again under a new stamp (a V4L2
// requeue race, a USB camera repeating a frame it could not refresh) delivers pixels exposed one
// period earlier than their stamp says: measured against the pose at that stamp, every feature
// is off by the camera's motion over a frame. No two exposures of a real sensor are equal to the
// bit (its noise), so a frame equal to the previous one while the camera moved between their
// stamps is such a repeat (pixel_hash; the pipeline compares the poses), refused
// (REASON_DUPLICATE_FRAME) and not tracked. A still camera's equal frames (a rendered view
// without noise) are left alone: they are true.

#include <cstdint>
#include <opencv2/core.hpp>

namespace alight::vision {

/// A frame's brightness level: mean grey level on a 1-in-16 sample (CV_8UC1) [grey levels].
double frame_level(const cv::Mat& gray);

/// The share of the same sample at kClippedLevel or above (the sensor's or the 8-bit range's
/// ceiling) [0, 1].
double clipped_share(const cv::Mat& gray);
constexpr int kClippedLevel = 250;

/// What the exposure check says about a frame.
struct ExposureCheck {
  double ev = 0.0;               ///< the frame's level against the settled one [EV]
  bool step = false;             ///< an exposure step: refuse the frame, do not track it
  double threshold_scale = 1.0;  ///< the detector's threshold factor (1 within kDeadBandEv)
};

/// The settled brightness level and the steps away from it (see above). Pure: a function of the
/// levels and times it was given.
class ExposureGuard {
 public:
  /// Beyond this a frame is an exposure step [EV]: at +1 EV the bright half of an indoor view's
  /// histogram (the simulator's exposure holds its 240-level quantile) saturates, at -1 EV the
  /// weaker half of the blobs fall under the detector's threshold.
  static constexpr double kStepEv = 1.0;
  /// Within this nothing is scaled [EV]: the scene's own mean brightness moves about as much
  /// while the view sweeps over a floor and a top of other shades.
  static constexpr double kDeadBandEv = 0.5;
  /// A step lasting longer is the scene's own change [s]: exposure controls settle within a few
  /// frames (the simulator's in 6 at 30 Hz, 0.2 s).
  static constexpr double kMaxStepS = 0.4;
  /// The settled level's weight for each frame within kDeadBandEv: it follows the scene's own
  /// slow changes over ~5 frames.
  static constexpr double kSettleWeight = 0.2;

  /// Beyond this rise of the clipped share a frame is an exposure step: a fifth of the view
  /// newly white has lost its blobs and descriptors, whatever the level's ratio says.
  static constexpr double kClipStep = 0.2;

  /// Checks the frame of `level` and `clipped` share exposed at `utime` [us] and updates the
  /// state.
  ExposureCheck check(double level, int64_t utime, double clipped = 0.0);
  void reset();
  double settled_level() const { return settled_; }

 private:
  double settled_ = 0.0;  // 0: no frame yet
  double settled_clipped_ = 0.0;
  int64_t step_start_ = -1;  // the first refused frame of the current step (-1: none)
};

/// The factor bringing the reference's pixels (level_ref) to the current frame's brightness
/// (level_now): exactly 1 within ExposureGuard::kDeadBandEv of each other or without levels.
double gain_between(double level_ref, double level_now);

/// A 64-bit hash of the frame's pixels (CV_8UC1): equal frames, equal hashes; two different
/// frames collide with probability ~2^-64.
uint64_t pixel_hash(const cv::Mat& gray);

}  // namespace alight::vision

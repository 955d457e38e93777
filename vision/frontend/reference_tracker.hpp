#pragma once
// Reference frame selection (paper 3.1.1): "the most current frame is matched against a
// reference frame, which is selected by tracking features in subsequent frames and picking the
// frame in the past for which a minimum number of features can be tracked continuously."
//
// Each new frame is matched to the previous one (matcher.hpp), the matches checked against one
// loose frame-to-frame homography (wrong matches would make false tracks); a matched keypoint
// inherits the previous keypoint's track id, an unmatched one starts a new track. A track therefore
// links a feature through every frame since it started, and the number of features tracked
// continuously from a past frame f to now is |ids(f) & ids(now)|. That count can only fall as
// time goes on, so the reference is the oldest kept frame where it is still >= min_tracked, and
// older frames are dropped for good. The longest baseline with enough common features is what
// maximises the accuracy of the reconstruction.
//
// Reset rules (the history is cleared and the new frame starts it again):
//  - the new frame has fewer than min_tracked keypoints (blank / blurred image): it is not kept;
//  - its time is not after the previous frame's, or more than max_frame_gap_s after it
//    (a replay jumped, or frames were lost: tracks across the gap are not trustworthy);
//  - no past frame keeps min_tracked features (the view changed too fast);
//  - reset() by the caller (e.g. a new mission).
// Frames older than max_reference_age_s and beyond max_history frames are dropped.

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "vision/frontend/matcher.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/geometry/rolling_shutter.hpp"
#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

/// One processed image: its features and their track ids.
struct TrackedFrame {
  int64_t utime = 0;  ///< exposure time [us]
  std::vector<Keypoint> keypoints;
  cv::Mat descriptors;             ///< CV_32F, one row per keypoint
  double pattern_angle_rad = 0.0;  ///< SURF pattern rotation used for the descriptors
  cv::Mat image;  ///< ingress: the grey image smoothed (parallax_image); landing: the grey image
                  ///< as captured (the rim search, landing_target.hpp)
  std::vector<int64_t> track_id;  ///< filled by ReferenceTracker::add
  /// The floor's smear over the exposure [px] (motion_blur.hpp): a smeared frame is tracked
  /// through but never the reference (landing.max_motion_blur_px).
  double blur_px = 0.0;
  /// The same smear from the camera's turning alone [px]: what also smears a top that moves
  /// with the camera (the moving top is measured on frames whose floor only the camera's
  /// travel smeared). Computed only for a frame smeared past the bound; 0 otherwise.
  double spin_blur_px = 0.0;
  /// The camera's motion over the readout (rolling_shutter.hpp; not rolling: a global shutter).
  Readout readout;
  double level = 0.0;  ///< brightness level (frame_checks.hpp) [grey levels]
};

class ReferenceTracker {
 public:
  explicit ReferenceTracker(const TrackerParams& params = {});

  struct Update {
    Reason status = Reason::kOk;  ///< kOk: a reference exists; else kNoReference/kTooFewFeatures
    std::shared_ptr<const TrackedFrame> current;    ///< null when the frame was not kept
    std::shared_ptr<const TrackedFrame> reference;  ///< null unless status == kOk
    int n_tracked = 0;        ///< features tracked continuously from the reference to now
    int n_frame_matches = 0;  ///< verified matches with the previous frame
    bool reset = false;       ///< the history was cleared by this frame
  };

  /// Adds the newest frame (its track_id is assigned here) and selects the reference.
  Update add(TrackedFrame frame);
  void reset();

  size_t history_size() const { return history_.size(); }
  /// The kept frames, oldest first (the newest is the last one added). Every frame from the
  /// reference on shares at least min_tracked tracks with the newest.
  const std::deque<std::shared_ptr<TrackedFrame>>& history() const { return history_; }

 private:
  TrackerParams params_;
  std::deque<std::shared_ptr<TrackedFrame>> history_;  // oldest first; back() is the newest
  int64_t next_id_ = 0;
};

/// Correspondences between two frames of one history through their common track ids (features
/// tracked continuously from `a` to `b`): i1 indexes a's keypoints, i2 b's.
std::vector<Match> tracked_matches(const TrackedFrame& a, const TrackedFrame& b);

}  // namespace alight::vision

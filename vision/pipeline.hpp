#pragma once
// One camera frame to one target measurement (paper 3.1-3.3): STAR features and upright SURF
// descriptors (pattern aligned to a fixed world direction from motion capture), reference frame
// by continuous tracking, reference-to-current matches, then the mission's target (landing:
// two homographies, platform; ingress: wall homography, opening) and its waypoint. Pure: the
// caller passes the image, its exposure time and the pose interpolated at that time; same
// inputs in the same order give the same results (all RANSAC seeded, no clock).

#include <deque>
#include <optional>
#include <utility>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "vision/params.hpp"
#include "vision/reference_tracker.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// The outcome of one frame; reason says why nothing was found.
struct FrameResult {
  int64_t utime = 0;      ///< exposure time of the current image [us]
  int64_t ref_utime = 0;  ///< exposure time of the reference image (0: none) [us]
  int64_t seq = 0;        ///< frames processed so far, this one included
  Mission mission = Mission::kNone;
  Reason reason = Reason::kOk;
  bool found() const { return reason == Reason::kOk; }
  TargetEstimate target;    ///< valid when found(); counts always
  double baseline_m = 0.0;  ///< camera translation reference -> current [m]
  int n_features = 0, n_matches = 0, n_tracked = 0;
  // For the diagnostic image:
  std::vector<Vector2d> features_px;  ///< all current features (raw pixels)
  std::vector<Vector2d> matched_px;   ///< matched current features (raw pixels)
  std::vector<Label> labels;          ///< one per matched feature
  std::vector<cv::Vec4i> lines;       ///< ingress Hough segments
};

class Pipeline {
 public:
  Pipeline(Mission mission, const PipelineParams& params, const CameraModel& camera,
           const CameraMount& mount);

  /// Processes one frame (CV_8UC1). `pose` is the body pose at the exposure time; nullopt gives
  /// kNoPose and leaves the history untouched.
  FrameResult process(const cv::Mat& gray, int64_t utime, const std::optional<PoseSample>& pose);
  void reset();

  Mission mission() const { return mission_; }
  const CameraModel& camera() const { return camera_; }

 private:
  Mission mission_;
  PipelineParams params_;
  CameraModel camera_;
  CameraMount mount_;
  ReferenceTracker tracker_;
  std::deque<std::pair<int64_t, PoseSample>> poses_;  // of the frames the tracker keeps
  int64_t seq_ = 0;
};

}  // namespace alight::vision

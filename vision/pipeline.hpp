#pragma once
// One camera frame to one target measurement (paper 3.1-3.3): STAR features and upright SURF
// descriptors (pattern aligned to a fixed world direction from motion capture), reference frame
// by continuous tracking, reference-to-current matches, then the mission's target (landing:
// two homographies, platform; ingress: wall homography, opening) and its waypoint. Pure: the
// caller passes the image, its exposure time and the pose interpolated at that time; same
// inputs in the same order give the same results (all RANSAC seeded, no clock).
//
// Beyond the paper (landing.hold_reference): the paper's reference is the oldest frame
// with N features tracked continuously to now. While the vehicle hovers (a refinement vantage's
// dwell, an approach waiting for e_r), that frame moves forward in time: tracks break (a feature
// missed in one frame ends its track for good) and max_history frames pass in 2 s, so within 1-2 s
// of hovering every frame left was taken from the hover point and the baseline falls towards
// zero. The platform top's parallax over the floor, f b (1/Z_top - 1/Z_floor), then falls under
// the 2 x threshold that tells it from the floor (4 px: b ~ 9 cm for a 15 cm top at 1.5 m, 15 cm
// for a 9 cm top), and the target is lost although it has not moved. So while the tracked
// reference is closer than max_reference_baseline_m, the previous frame's reference is held when
// it is farther from the current camera, no farther than max_reference_baseline_m, younger than
// landing.hold_max_age_s, and still matches N features directly (the overlap the paper's tracking
// rule asks for): the longer baseline still in view, which is what the paper's rule aims at. A
// tracked reference at max_reference_baseline_m or more is used as the paper has it (and becomes
// the held one). The held reference is a function of the frames and poses received, as the tracker
// is; a gap or jump in the frames' times drops it. A reset of the tracker for broken tracks (a
// changed view, a frame of few features) does not: over a pale floor the tracks break every 1-2 s
// while the held frame still matches, and where the tracker has no reference at all the held one
// serves alone (without it, a refinement over a pale floor loses the top at every retry).
//
// Beyond the paper (landing.max_motion_blur_px): a frame exposed while the floor's image
// moved farther than that (motion_blur.hpp) is tracked through, so the tracks and the held
// reference live on, but it is never measured and never the reference: its features are smears,
// placed where no plane puts them, and such frames at the search path's turns made tops of a
// bare floor.
//
// Beyond the paper, a real camera (frontend/frame_checks.hpp, geometry/rolling_shutter.hpp): a
// frame equal to the previous one (the driver's repeat) and a frame whose brightness stepped
// (automatic exposure) are refused before their features and never tracked; the detector's
// threshold and the reference's pixels follow smaller exposure changes; under a rolling shutter
// every feature's ray is brought to its frame's row 0, the time of the frame's stamp and pose,
// before any geometry (with a global shutter nothing changes).
//
// Beyond the paper (moving_top): a platform that moves breaks the still scene the paper's planes
// assume. Each landing frame is also matched against a recent earlier frame (moving_top.interval_s
// back) and the moving top measured between them (vision/landing/moving_top.hpp), in
// FrameResult::moving; the paper's target (FrameResult::target, VISION_TARGET) does not depend on
// it. A frame smeared past landing.max_motion_blur_px by the camera's travel alone is still
// measured for the moving top (never for the target): a camera following a platform at 0.7 m/s
// smears the floor by 4-6 px and more, but not the top it keeps pace with, and refusing those
// frames lost the platform while the vehicle caught up with it. The camera's turning smears the
// top as much as the floor: such frames stay refused for both.

#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "vision/frontend/frame_checks.hpp"
#include "vision/frontend/reference_tracker.hpp"
#include "vision/landing/moving_top.hpp"
#include "vision/landing/outline.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// A held reference older than this [s] is dropped. An approach held by gusts hovers 10 s and
/// more with the target in view; what shows that the held frame still sees the same scene is its
/// direct match of tracker.min_tracked features, not its age, so the bound is three times
/// tracker.max_reference_age_s's 10 s and only retires a frame the scene may have changed under.
constexpr double kHoldMaxAgeS = 30.0;

/// The moving top's earlier frame is taken within this change of the camera's range to the top:
/// a level top's features scale between two views as that range, the matcher's descriptors are
/// sampled at the detector's scale, which comes in steps, and a feature is matched again across
/// a few per cent of zoom, not across the third that a quarter second of the last drop makes.
constexpr double kMovingMaxScaleChange = 0.1;

/// Whether a frame whose camera is range_m from the top's plane shows the top at the current
/// frame's scale (range_now_m): both positive, within kMovingMaxScaleChange.
bool same_moving_scale(double range_now_m, double range_m);

/// While landing, the reference may lie this share of the view's short side (across the floor at
/// the camera's range) from the camera when that is more than max_reference_baseline_m. The bound
/// keeps a top in view in both images, which the view's footprint sets (0.3 m is this share of
/// it 1.5 m over the floor, the search height); the top's parallax, what tells it from the
/// floor, falls with the range squared at a fixed baseline, and a vantage climbed to fit a large
/// top keeps it only with a baseline that grows with its view.
constexpr double kReferenceViewShare = 0.27;

/// The reference's farthest distance from a landing camera range_m over the floor [m]:
/// max_reference_baseline_m, or kReferenceViewShare of the view's short side where that is more.
double landing_baseline_bound_m(double max_reference_baseline_m, const CameraModel& camera,
                                double range_m);

/// The earlier frame the moving top is measured against, among recent frames (oldest first, their
/// ages and the camera's ranges to the top's assumed height) [index]: the newest at least
/// interval_s old within kMovingMaxScaleChange of the current range; in a fast descent none is,
/// and then the oldest within it (close over the top a frame's displacement is tens of pixels).
/// nullopt: no earlier frame within that change.
std::optional<size_t> moving_reference(const std::vector<double>& ages_s,
                                       const std::vector<double>& ranges_m, double range_now_m,
                                       double interval_s);

/// A top whose features the known floor carries (MovingReason::kOnFloor) may be a platform
/// creeping through its turn: at 5 cm/s it moves 1.3 cm in a quarter second, under the floor
/// test's tolerance (3 floor_tol_px, 1.9 cm at 1.4 m), where the still landing refuses it as a
/// top whose plane moved against the floor's. It is measured again against the oldest frame within
/// max_interval_s, when that is at least this many times the first interval (less shows it
/// hardly farther from the floor's prediction).
constexpr double kSlowTopIntervalGain = 1.5;

/// What the longer interval measures is kept only where the first could not have told it from the
/// floor: its displacement over the first interval within this many times the floor cluster's
/// reach (kFloorClusterTols floor_tol_px at the top's depth). A floor whose pattern repeats (a
/// chessboard) matched to its next copy is set aside at the first interval as faster than
/// max_speed_mps, but over the longer one its period may read under it.
constexpr double kSlowTopMaxShift = 2.0;

/// Whether the top m, measured over a longer interval, moved over first_dt_s within
/// kSlowTopMaxShift of the floor cluster's reach for a camera of focal_px.
bool creeping_top(const MovingTop& m, double first_dt_s, double focal_px,
                  const MovingTopParams& params);

/// The earlier frame a top set aside as the floor's against the frame first_age_s old is measured
/// against (kSlowTopIntervalGain) [index]: the oldest within kMovingMaxScaleChange of the current
/// range, if kSlowTopIntervalGain times first_age_s old or more; else nullopt.
std::optional<size_t> slow_top_reference(const std::vector<double>& ages_s,
                                         const std::vector<double>& ranges_m, double range_now_m,
                                         double first_age_s);

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
  bool ref_held = false;  ///< the reference is the held one (landing.hold_reference)
  double blur_px = 0.0;   ///< the floor's smear over the exposure (0: guard off; motion_blur.hpp)
  // For the diagnostic image:
  std::vector<Vector2d> features_px;  ///< all current features (raw pixels)
  std::vector<Vector2d> matched_px;   ///< matched current features (raw pixels)
  std::vector<Label> labels;          ///< one per matched feature
  std::vector<cv::Vec4i> lines;       ///< ingress Hough segments
  /// Landing with moving_top.enabled: the moving top's measurement (not found: its reason),
  /// against the frame of exposure moving_ref_utime; nullopt where the frame never got that far
  /// (no pose, a bad image, no features, a smeared frame).
  std::optional<MovingTop> moving;
  int64_t moving_ref_utime = 0;
  /// For the diagnostic image: the moving top's inliers in the current frame (raw pixels).
  std::vector<Vector2d> moving_px;
};

class Pipeline {
 public:
  Pipeline(Mission mission, const PipelineParams& params, const CameraModel& camera,
           const CameraMount& mount);

  /// Processes one frame (CV_8UC1). `pose` is the body pose at the exposure time; nullopt gives
  /// kNoPose and leaves the history untouched. `exposure_s`: the frame's exposure time [s]
  /// (nullopt: landing.assumed_exposure_s), for the motion blur guard. `line_delay_s`: a
  /// rolling shutter's row-to-row delay (row v exposed at utime + v x line_delay_s) [s];
  /// nullopt or 0: a global shutter.
  FrameResult process(const cv::Mat& gray, int64_t utime, const std::optional<PoseSample>& pose,
                      std::optional<double> exposure_s = std::nullopt,
                      std::optional<double> line_delay_s = std::nullopt);
  void reset();

  Mission mission() const { return mission_; }
  const CameraModel& camera() const { return camera_; }

 private:
  // The reference a frame is matched against, its pose and baseline (pipeline.cpp).
  struct Reference;

  // Stages of process(), in order (pipeline.cpp).
  Result<TrackedFrame> front_end(const cv::Mat& gray, int64_t utime, const PoseSample& pose,
                                 std::optional<double> exposure_s, double threshold_scale,
                                 std::optional<double> line_delay_s, FrameResult* r) const;
  std::optional<ScenePlane> depth_plane() const;
  bool camera_moved(const PoseSample& a, const PoseSample& b) const;
  ReferenceTracker::Update track(TrackedFrame frame, int64_t utime, const PoseSample& pose);
  Reference tracked_reference(const ReferenceTracker::Update& up, const PoseSample& pose) const;
  void hold_reference(Reference* ref, const TrackedFrame& current, int64_t utime,
                      const PoseSample& pose) const;
  Correspondences correspondences(const TrackedFrame& a, const TrackedFrame& b,
                                  const std::vector<Match>& matches) const;
  /// landing.max_motion_blur_px while landing; 0 (no bound) otherwise.
  double max_blur_px() const;
  bool smeared(const TrackedFrame& f) const;
  /// Smeared by the camera's turning (spin_blur_px past the same bound).
  bool spun(const TrackedFrame& f) const;
  /// regions_now: the current frame's plain regions, shared with the still landing's outline
  /// stage on the same frame.
  void measure_moving(const std::shared_ptr<const TrackedFrame>& current, int64_t utime,
                      const PoseSample& pose, const PlainRegions& regions_now, FrameResult* r);
  /// The moving top by its outline (moving_outline.hpp) against the recent frames, the earlier
  /// frame k first; its earlier frame's utime in *ref_utime.
  MovingTop measure_moving_outline(const TrackedFrame& current, const PoseSample& pose,
                                   const std::vector<Outline>& now, size_t k,
                                   const std::vector<double>& ages_s,
                                   const std::vector<double>& ranges_m, double range_now_m,
                                   int64_t* ref_utime) const;
  std::vector<Outline> plain_outlines(const PlainRegions& regions) const;
  bool holds() const;
  /// The reference's farthest distance from the camera at `pose` [m]: max_reference_baseline_m,
  /// or while landing kReferenceViewShare of the view's short side at the camera's range to the
  /// floor where that is more.
  double max_baseline_m(const PoseSample& pose) const;

  Mission mission_;
  PipelineParams params_;
  CameraModel camera_;
  CameraMount mount_;
  ReferenceTracker tracker_;
  std::deque<std::pair<int64_t, PoseSample>> poses_;  // of the frames the tracker keeps
  // The previous frame's reference and its pose (landing.hold_reference): it may be older than
  // every frame the tracker still keeps.
  std::shared_ptr<const TrackedFrame> held_;
  PoseSample held_pose_;
  int64_t last_utime_ = 0;  // the previous frame's time: a gap drops the held reference
  // The real camera's checks (frame_checks.hpp) and the wall the previous frame measured (the
  // rolling-shutter correction's depths for ingress).
  ExposureGuard exposure_;
  std::optional<uint64_t> last_hash_;
  PoseSample last_pose_;  // the pose of last_hash_'s frame
  std::optional<ScenePlane> wall_plane_;
  // The last max_interval_s of frames and their poses, for the moving top (moving_top), and
  // each one's plain regions' outlines (moving_outline).
  struct Recent {
    std::shared_ptr<const TrackedFrame> frame;
    PoseSample pose;
    std::vector<Outline> outlines;  ///< its plain regions' (plain_outlines)
  };
  std::deque<Recent> recent_;
  int64_t seq_ = 0;
};

}  // namespace alight::vision

// Per-frame pipeline, paper 3.1-3.3 (see pipeline.hpp).
#include "vision/pipeline.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/geometry.hpp"
#include "vision/frontend/frame_checks.hpp"
#include "vision/frontend/matcher.hpp"
#include "vision/frontend/motion_blur.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/frontend/surf_descriptor.hpp"
#include "vision/geometry/waypoint.hpp"
#include "vision/ingress/ingress_target.hpp"
#include "vision/landing/landing_target.hpp"
#include "vision/landing/moving_outline.hpp"

namespace alight::vision {

Pipeline::Pipeline(Mission mission, const PipelineParams& params, const CameraModel& camera,
                   const CameraMount& mount)
    : mission_(mission), params_(params), camera_(camera), mount_(mount), tracker_(params.tracker) {
  assert(mission != Mission::kNone);
  params_.validate();
  // The moving top's cut bound is the still landing's (moving_top_params.hpp).
  params_.moving_top.edge_margin_px = params_.landing.edge_margin_px;
}

void Pipeline::reset() {
  tracker_.reset();
  poses_.clear();
  held_.reset();
  recent_.clear();
  last_utime_ = 0;
  exposure_.reset();
  last_hash_.reset();
  wall_plane_.reset();
}

// The reference a frame is matched against: a tracked one or the held one, its pose and its
// baseline to the current camera. `matches` are the held reference's, made while choosing it.
struct Pipeline::Reference {
  std::shared_ptr<const TrackedFrame> frame;  // null: none serves
  PoseSample pose;
  double baseline_m = 0.0;  // none tracked: any held baseline is longer
  bool skipped_smeared = false;
  bool held = false;
  std::vector<Match> matches;
};

namespace {

// Matches of frame a's features to frame b's (paper 3.1.1): ratio test, mutual check,
// same-sign blobs.
std::vector<Match> match_frames(const TrackedFrame& a, const TrackedFrame& b,
                                const MatchParams& params) {
  const auto sa = response_signs(a.keypoints);
  const auto sb = response_signs(b.keypoints);
  return match_descriptors(a.descriptors, b.descriptors, params, &sa, &sb);
}

}  // namespace

double Pipeline::max_blur_px() const {
  return mission_ == Mission::kLanding ? params_.landing.max_motion_blur_px : 0;
}

bool Pipeline::smeared(const TrackedFrame& f) const {
  return max_blur_px() > 0 && f.blur_px > max_blur_px();
}

bool Pipeline::spun(const TrackedFrame& f) const {
  return max_blur_px() > 0 && f.spin_blur_px > max_blur_px();
}

double landing_baseline_bound_m(double max_reference_baseline_m, const CameraModel& camera,
                                double range_m) {
  const double view_m = range_m * std::min(camera.width / camera.fx, camera.height / camera.fy);
  return std::max(max_reference_baseline_m, kReferenceViewShare * view_m);
}

double Pipeline::max_baseline_m(const PoseSample& pose) const {
  if (mission_ != Mission::kLanding) return params_.max_reference_baseline_m;
  const double range_m =
      camera_in_world(pose.X_WB(), mount_.X_BC()).translation().z() - params_.landing.floor_z_m;
  return landing_baseline_bound_m(params_.max_reference_baseline_m, camera_, range_m);
}

bool Pipeline::holds() const {
  return mission_ == Mission::kLanding && params_.landing.hold_reference;
}

// Features, descriptors and the frame's smear (paper 3.1.1). Descriptors of every frame share
// one world-fixed pattern orientation, so yaw between the reference and now does not break
// matching: world x for the downward camera, world up for the forward one (world x is near its
// optical axis). Ingress keeps each frame's image smoothed as the off-wall mask compares it,
// made once; landing keeps the image itself for the photometric gate and the rim search (the
// caller's pixels are not ours to keep; with both off no copy is made). threshold_scale: the
// exposure's (frame_checks.hpp); line_delay_s: the rolling shutter's, for the frame's readout.
// Fails with the detector's reason.
Result<TrackedFrame> Pipeline::front_end(const cv::Mat& gray, int64_t utime, const PoseSample& pose,
                                         std::optional<double> exposure_s, double threshold_scale,
                                         std::optional<double> line_delay_s, FrameResult* r) const {
  const cv::Mat integral = integral_image(gray);
  StarParams star = mission_ == Mission::kIngress ? params_.ingress_star : params_.star;
  if (threshold_scale != 1.0) star.response_threshold *= threshold_scale;
  auto kps = detect_star(gray, integral, star);
  if (!kps) return Result<TrackedFrame>::fail(kps.reason());
  r->n_features = static_cast<int>(kps->size());
  for (const auto& k : *kps) r->features_px.emplace_back(k.x, k.y);
  const Isometry3d X_WC = camera_in_world(pose.X_WB(), mount_.X_BC());
  const Vector3d d_W = mission_ == Mission::kIngress ? Vector3d::UnitZ() : Vector3d::UnitX();
  TrackedFrame frame;
  frame.utime = utime;
  frame.pattern_angle_rad = pattern_angle(X_WC.linear(), d_W);
  frame.descriptors = describe_surf(integral, *kps, params_.surf, frame.pattern_angle_rad);
  frame.keypoints = std::move(*kps);
  if (max_blur_px() > 0) {
    const double exposure = exposure_s.value_or(params_.landing.assumed_exposure_s);
    frame.blur_px =
        floor_motion_blur_px(camera_, mount_, pose, params_.landing.floor_z_m, exposure);
    // The turning's share matters only to a frame smeared past the bound (spun()).
    if (smeared(frame)) {
      PoseSample turning = pose;
      turning.v_W_B.setZero();
      frame.spin_blur_px =
          floor_motion_blur_px(camera_, mount_, turning, params_.landing.floor_z_m, exposure);
    }
  }
  r->blur_px = frame.blur_px;
  if (line_delay_s && *line_delay_s > 0)
    frame.readout = readout_motion(pose, mount_, *line_delay_s, depth_plane());
  if (mission_ == Mission::kIngress && params_.ingress.parallax_mask)
    frame.image = parallax_image(gray, params_.ingress);
  if (mission_ == Mission::kLanding) frame.image = gray.clone();  // the plane check, the rims
  return Result<TrackedFrame>::ok(std::move(frame));
}

// Whether the camera moved between two poses by more than leaves a still view's pixels equal (a
// still camera's frames may be equal to the bit where nothing adds noise, as rendered ones):
// 1 mm or 1 mrad, under a pixel at 1 m for a 667 px focal length.
bool Pipeline::camera_moved(const PoseSample& a, const PoseSample& b) const {
  constexpr double kStillM = 1e-3, kStillRad = 1e-3;
  const Isometry3d X_WC_a = camera_in_world(a.X_WB(), mount_.X_BC());
  const Isometry3d X_WC_b = camera_in_world(b.X_WB(), mount_.X_BC());
  return (X_WC_a.translation() - X_WC_b.translation()).norm() > kStillM ||
         Eigen::AngleAxisd(X_WC_a.linear().transpose() * X_WC_b.linear()).angle() > kStillRad;
}

// The plane a rolling shutter's translation takes its depths from (rolling_shutter.hpp): the
// landing's floor, the wall the ingress last measured (none yet: rotation only).
std::optional<ScenePlane> Pipeline::depth_plane() const {
  if (mission_ == Mission::kLanding)
    return ScenePlane{Vector3d::UnitZ(), params_.landing.floor_z_m};
  return wall_plane_;
}

// The frame into the tracker (paper 3.1.1), and the poses of the frames it can still pick.
ReferenceTracker::Update Pipeline::track(TrackedFrame frame, int64_t utime,
                                         const PoseSample& pose) {
  const auto up = tracker_.add(std::move(frame));
  if (up.reset) {
    poses_.clear();
    // Tracks broken by a changed view or a frame of few features (a pale floor loses its weak
    // features from frame to frame) say nothing about the held reference: it is used only where
    // it still matches min_tracked features directly (a gap in time drops it). Dropping it with
    // every reset would restart the baseline from zero every 1-2 s over a pale floor, short of
    // the top's parallax.
    if (!holds()) held_.reset();
  }
  if (up.current) poses_.emplace_back(utime, pose);
  const int64_t oldest = up.reference ? up.reference->utime : utime;
  while (!poses_.empty() && poses_.front().first < oldest) poses_.pop_front();
  return up;
}

// The tracked reference: the oldest qualifying frame within max_reference_baseline_m of the
// current camera (the newest previous frame when even that one is farther); never a smeared
// one.
Pipeline::Reference Pipeline::tracked_reference(const ReferenceTracker::Update& up,
                                                const PoseSample& pose) const {
  Reference ref;
  ref.frame = up.reference && !smeared(*up.reference) ? up.reference : nullptr;
  if (up.reference) {
    const auto& h = tracker_.history();
    const Vector3d c_now = camera_in_world(pose.X_WB(), mount_.X_BC()).translation();
    const double max_baseline = max_baseline_m(pose);
    for (size_t k = 0; k + 1 < h.size(); ++k) {
      const auto pose_k = std::find_if(poses_.begin(), poses_.end(),
                                       [&](const auto& e) { return e.first == h[k]->utime; });
      if (pose_k == poses_.end()) continue;
      if (smeared(*h[k])) {
        ref.skipped_smeared = true;
        continue;
      }
      ref.frame = h[k];
      if ((camera_in_world(pose_k->second.X_WB(), mount_.X_BC()).translation() - c_now).norm() <=
          max_baseline)
        break;
    }
  }
  if (ref.frame) {
    const auto ref_pose = std::find_if(poses_.begin(), poses_.end(),
                                       [&](const auto& e) { return e.first == ref.frame->utime; });
    assert(ref_pose != poses_.end());
    ref.pose = ref_pose->second;
    ref.baseline_m = mocap_motion(ref.pose, pose, mount_).baseline_m;
  }
  return ref;
}

// Hovering (pipeline.hpp): the held reference while the tracked one is nearer than
// max_reference_baseline_m, where the held one is farther, within max_reference_baseline_m and
// kHoldMaxAgeS, and still matches min_tracked of the current frame's features. A frame that
// matches it with fewer hands the hold to the tracked one: keeping it held through such frames
// multiplies the false targets over floors without a platform.
void Pipeline::hold_reference(Reference* ref, const TrackedFrame& current, int64_t utime,
                              const PoseSample& pose) const {
  const double max_baseline = max_baseline_m(pose);
  if (!(holds() && ref->baseline_m < max_baseline && held_ && held_->utime < utime &&
        double(utime - held_->utime) * 1e-6 <= kHoldMaxAgeS))
    return;
  const double held_baseline_m = mocap_motion(held_pose_, pose, mount_).baseline_m;
  if (!(held_baseline_m > ref->baseline_m && held_baseline_m <= max_baseline)) return;
  auto m = match_frames(*held_, current, params_.match);
  if (static_cast<int>(m.size()) < params_.tracker.min_tracked) return;
  ref->frame = held_;
  ref->pose = held_pose_;
  ref->baseline_m = held_baseline_m;
  ref->matches = std::move(m);
  ref->held = true;
}

bool same_moving_scale(double range_now_m, double range_m) {
  return range_now_m > 0 && range_m > 0 &&
         std::abs(range_now_m / range_m - 1.0) <= kMovingMaxScaleChange;
}

std::optional<size_t> moving_reference(const std::vector<double>& ages_s,
                                       const std::vector<double>& ranges_m, double range_now_m,
                                       double interval_s) {
  assert(ages_s.size() == ranges_m.size());
  std::optional<size_t> newest_old_enough, oldest_same_scale;
  for (size_t k = 0; k < ages_s.size(); ++k) {
    if (!same_moving_scale(range_now_m, ranges_m[k]) || !(ages_s[k] > 0)) continue;
    if (!oldest_same_scale) oldest_same_scale = k;
    if (ages_s[k] >= interval_s) newest_old_enough = k;
  }
  return newest_old_enough ? newest_old_enough : oldest_same_scale;
}

std::optional<size_t> slow_top_reference(const std::vector<double>& ages_s,
                                         const std::vector<double>& ranges_m, double range_now_m,
                                         double first_age_s) {
  // No frame is an infinite interval old: the oldest at this scale.
  const auto k = moving_reference(ages_s, ranges_m, range_now_m, INFINITY);
  if (k && first_age_s > 0 && ages_s[*k] >= kSlowTopIntervalGain * first_age_s) return k;
  return std::nullopt;
}

bool creeping_top(const MovingTop& m, double first_dt_s, double focal_px,
                  const MovingTopParams& params) {
  const double depth_m = m.camera_W.z() - m.plane_z_m;
  if (!(depth_m > 0 && focal_px > 0 && first_dt_s > 0)) return false;
  const double reach_m = kFloorClusterTols * params.floor_tol_px * depth_m / focal_px;
  return m.v_W.head<2>().norm() * first_dt_s <= kSlowTopMaxShift * reach_m;
}

// Whether the features found no set moving as a platform: too few off the floor, none sharing
// a motion, or every set found the floor's or beyond a platform (a floor's pattern matched to
// its next copy, found before a plain top's few features). A set found and refused by a later
// gate (size, a still top) is the top's features' verdict.
namespace {
bool features_found_no_set(MovingReason r) {
  return r == MovingReason::kTooFewCandidates || r == MovingReason::kNoCommonMotion ||
         r == MovingReason::kOnFloor || r == MovingReason::kTooFast;
}
}  // namespace

// The moving top (pipeline.hpp) against the earlier frame moving_reference picks among those
// within max_interval_s; the current frame then joins the recent ones. Where the features find
// no set moving as a platform, the top is measured by its outline (moving_outline.hpp).
void Pipeline::measure_moving(const std::shared_ptr<const TrackedFrame>& current, int64_t utime,
                              const PoseSample& pose, const PlainRegions& regions_now,
                              FrameResult* r) {
  const MovingTopParams& mp = params_.moving_top;
  if (mission_ != Mission::kLanding || !mp.enabled) return;
  const auto age_s = [&](int64_t t) { return double(utime - t) * 1e-6; };
  while (!recent_.empty() && age_s(recent_.front().frame->utime) > mp.max_interval_s)
    recent_.pop_front();
  // The camera's height over the top's assumed plane (find_moving_top's z_top).
  const double z_top = params_.landing.floor_z_m + mp.top_height_m;
  const auto range_m = [&](const PoseSample& s) {
    return camera_in_world(s.X_WB(), mount_.X_BC()).translation().z() - z_top;
  };
  std::vector<double> ages_s, ranges_m;
  for (const auto& e : recent_) {
    ages_s.push_back(age_s(e.frame->utime));
    ranges_m.push_back(range_m(e.pose));
  }
  const auto k = moving_reference(ages_s, ranges_m, range_m(pose), mp.interval_s);
  // Every frame's outlines are found with it, wanted now or not: a later frame whose features
  // find no set measures against all the recent ones, and finding the regions of a run of
  // frames at once (a second of them) would stall that one frame.
  Recent now{current, pose, plain_outlines(regions_now)};
  MovingTop m;
  if (!k) {
    m.reason = MovingReason::kNoEarlierFrame;
  } else {
    // The current frame matched against recent frame j, and the moving top between them.
    const auto against = [&](size_t j, Correspondences* c) {
      const TrackedFrame& a = *recent_[j].frame;
      *c = correspondences(a, *current, match_frames(a, *current, params_.match));
      c->pose_1 = recent_[j].pose;
      c->pose_2 = pose;
      return find_moving_top(*c, ages_s[j], params_.landing.floor_z_m, mp, a.image, current->image);
    };
    Correspondences c;
    m = against(*k, &c);
    r->moving_ref_utime = recent_[*k].frame->utime;
    if (m.reason == MovingReason::kOnFloor) {
      if (const auto k2 = slow_top_reference(ages_s, ranges_m, range_m(pose), ages_s[*k])) {
        Correspondences c2;
        MovingTop slow = against(*k2, &c2);
        if (slow.found() && creeping_top(slow, ages_s[*k], camera_.K()(0, 0), mp)) {
          m = std::move(slow);
          c = std::move(c2);
          r->moving_ref_utime = recent_[*k2].frame->utime;
        }
      }
    }
    if (features_found_no_set(m.reason) && !now.outlines.empty())
      m = measure_moving_outline(*current, pose, now.outlines, *k, ages_s, ranges_m, range_m(pose),
                                 &r->moving_ref_utime);
    if (m.found() && !m.outline)
      for (size_t i = 0; i < m.inliers.size() && i < c.size(); ++i)
        if (m.inliers[i]) r->moving_px.push_back(c.u2[i]);
  }
  r->moving = std::move(m);
  recent_.push_back(std::move(now));
}

// A frame's plain regions by the image alone (featureless_outlines with no matches): a top plain
// enough to give too few features for its motion may still give some, more in one frame than in
// the next, and its outline is wanted in both.
std::vector<Outline> Pipeline::plain_outlines(const PlainRegions& regions) const {
  Correspondences none;
  none.camera = &camera_;
  return featureless_outlines(regions, none, params_, kMaxMovingOutlines);
}

// The recent frames moving_reference would accept at some interval (the range within
// kMovingMaxScaleChange, at least half interval_s old), frame k among them: a plain top's region
// is found in most frames, not in all (its print's own edges split it in some), and its motion is
// confirmed by two (moving_outline.hpp). *ref_utime: the earlier frame measured against, or k's.
MovingTop Pipeline::measure_moving_outline(const TrackedFrame& current, const PoseSample& pose,
                                           const std::vector<Outline>& now, size_t k,
                                           const std::vector<double>& ages_s,
                                           const std::vector<double>& ranges_m, double range_now_m,
                                           int64_t* ref_utime) const {
  const MovingTopParams& mp = params_.moving_top;
  std::vector<EarlierOutlines> earlier;
  std::vector<size_t> frame_of;
  for (size_t j = 0; j < recent_.size(); ++j) {
    if (!(j == k ||
          (ages_s[j] >= 0.5 * mp.interval_s && same_moving_scale(range_now_m, ranges_m[j]))))
      continue;
    const Recent& e = recent_[j];
    if (e.outlines.empty()) continue;
    earlier.push_back({&e.outlines, e.pose, &e.frame->readout, ages_s[j]});
    frame_of.push_back(j);
  }
  Correspondences views;  // the cameras alone: the outlines' corners need no matches
  views.camera = &camera_;
  views.mount = &mount_;
  views.readout_2 = &current.readout;
  views.pose_2 = pose;
  size_t used = 0;
  MovingTop m = find_moving_outline(earlier, now, views, params_.landing.floor_z_m, mp, &used);
  if (m.found()) *ref_utime = recent_[frame_of[used]].frame->utime;
  return m;
}

// The matches as undistorted (K * ray) and raw pixels of both frames; under a rolling shutter
// the rays are each frame's row 0's (rolling_shutter.hpp), and kept.
Correspondences Pipeline::correspondences(const TrackedFrame& a, const TrackedFrame& b,
                                          const std::vector<Match>& matches) const {
  Correspondences c;
  c.camera = &camera_;
  c.mount = &mount_;
  c.readout_1 = &a.readout;
  c.readout_2 = &b.readout;
  if (a.readout.rolling()) c.grid_1 = std::make_shared<const EpochPixelGrid>(camera_, a.readout);
  if (b.readout.rolling()) c.grid_2 = std::make_shared<const EpochPixelGrid>(camera_, b.readout);
  const bool rolling = a.readout.rolling() || b.readout.rolling();
  const Matrix3d K = camera_.K();
  for (const auto& m : matches) {
    const auto& k1 = a.keypoints[m.i1];
    const auto& k2 = b.keypoints[m.i2];
    if (rolling) {
      c.r1.push_back(ray_at_epoch(camera_, {k1.x, k1.y}, a.readout));
      c.r2.push_back(ray_at_epoch(camera_, {k2.x, k2.y}, b.readout));
      c.x1.push_back((K * c.r1.back()).hnormalized());
      c.x2.push_back((K * c.r2.back()).hnormalized());
    } else {
      c.x1.push_back((K * camera_.ray({k1.x, k1.y})).hnormalized());
      c.x2.push_back((K * camera_.ray({k2.x, k2.y})).hnormalized());
    }
    c.u1.emplace_back(k1.x, k1.y);
    c.u2.emplace_back(k2.x, k2.y);
  }
  return c;
}

FrameResult Pipeline::process(const cv::Mat& gray, int64_t utime,
                              const std::optional<PoseSample>& pose,
                              std::optional<double> exposure_s,
                              std::optional<double> line_delay_s) {
  FrameResult r;
  r.utime = utime;
  r.seq = ++seq_;
  r.mission = mission_;
  auto fail = [&](Reason reason) {
    r.reason = reason;
    return r;
  };
  if (!pose) return fail(Reason::kNoPose);
  if (gray.empty() || gray.type() != CV_8UC1 || gray.cols != camera_.width ||
      gray.rows != camera_.height)
    return fail(Reason::kBadImage);
  // The driver's repeat and the exposure's steps (frame_checks.hpp): refused before their
  // features, not tracked, not counted as the previous frame.
  const uint64_t hash = pixel_hash(gray);
  const bool repeated = last_hash_ && *last_hash_ == hash && camera_moved(last_pose_, *pose);
  last_hash_ = hash;
  last_pose_ = *pose;
  if (repeated) return fail(Reason::kDuplicateFrame);
  const double level = frame_level(gray);
  const ExposureCheck exposure = exposure_.check(level, utime, clipped_share(gray));
  if (exposure.step) return fail(Reason::kExposureChange);
  // A gap or a jump in the frames' times: nothing from before it is trusted, the held reference
  // included (the tracker sees such a gap only while its history holds frames).
  const bool gap =
      last_utime_ != 0 && double(utime - last_utime_) * 1e-6 > params_.tracker.max_frame_gap_s;
  if (last_utime_ != 0 && (utime <= last_utime_ || gap)) {
    held_.reset();
    recent_.clear();
  }
  last_utime_ = utime;

  auto frame =
      front_end(gray, utime, *pose, exposure_s, exposure.threshold_scale, line_delay_s, &r);
  if (!frame) return fail(frame.reason());
  frame.value().level = level;
  const auto up = track(std::move(frame.value()), utime, *pose);
  r.n_tracked = up.n_tracked;
  // The current frame's plain regions, found where first wanted (the moving top's outline, the
  // still landing's) and shared.
  const PlainRegions regions_now(up.current ? up.current->image : cv::Mat());
  if (up.current && smeared(*up.current)) {
    if (!spun(*up.current)) measure_moving(up.current, utime, *pose, regions_now, &r);
    return fail(Reason::kMotionBlur);
  }
  if (up.current) measure_moving(up.current, utime, *pose, regions_now, &r);
  // No tracked reference (the tracks just broke): only the held one can serve.
  const bool held_only = up.status == Reason::kNoReference && up.current && holds() && held_;
  if (up.status != Reason::kOk && !held_only)
    return fail(gap && up.status == Reason::kNoReference ? Reason::kFrameGap : up.status);
  Reference ref = tracked_reference(up, *pose);
  const TrackedFrame& b = *up.current;
  hold_reference(&ref, b, utime, *pose);
  if (!ref.frame)
    return fail(ref.skipped_smeared        ? Reason::kMotionBlur
                : up.status != Reason::kOk ? up.status
                                           : Reason::kNoReference);
  if (holds()) {
    held_ = ref.frame;
    held_pose_ = ref.pose;
  }
  r.ref_utime = ref.frame->utime;
  r.ref_held = ref.held;
  r.baseline_m = ref.baseline_m;
  if (r.baseline_m < params_.waypoint.min_baseline_m) return fail(Reason::kSmallBaseline);

  const TrackedFrame& a = *ref.frame;
  const std::vector<Match> matches =
      ref.held ? std::move(ref.matches) : match_frames(a, b, params_.match);
  r.n_matches = static_cast<int>(matches.size());
  Correspondences c = correspondences(a, b, matches);
  c.pose_1 = ref.pose;
  c.pose_2 = *pose;
  r.matched_px = c.u2;
  const bool parallax = mission_ == Mission::kIngress && params_.ingress.parallax_mask;
  // The reference's pixels at the current frame's exposure, for the stages that difference them.
  cv::Mat image_1 = a.image;
  if (const double g = gain_between(a.level, b.level); g != 1.0 && !a.image.empty()) {
    cv::Mat scaled;  // a new buffer: the tracked frame's image stays as captured
    a.image.convertTo(scaled, CV_8U, g);
    image_1 = scaled;
  }
  const TargetOutcome t = mission_ == Mission::kLanding
                              ? find_landing_target(c, params_, image_1, gray, &regions_now)
                              : find_ingress_target(c, gray, parallax ? b.image : cv::Mat(),
                                                    parallax ? image_1 : cv::Mat(), params_);
  if (mission_ == Mission::kIngress && (t.reason == Reason::kOk || located_only(t.reason)))
    wall_plane_ = ScenePlane{t.estimate.n_W, t.estimate.n_W.dot(t.estimate.p_W)};
  r.target = t.estimate;
  r.labels = t.labels;
  r.lines = t.lines;
  r.reason = t.reason;
  return r;
}

}  // namespace alight::vision

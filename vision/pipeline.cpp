// Per-frame pipeline, paper 3.1-3.3 (see pipeline.hpp).
#include "vision/pipeline.hpp"

#include <algorithm>

#include "vision/frontend/matcher.hpp"
#include "vision/frontend/motion_blur.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/frontend/surf_descriptor.hpp"
#include "vision/geometry/waypoint.hpp"
#include "vision/ingress/ingress_target.hpp"
#include "vision/landing/landing_target.hpp"

namespace alight::vision {

Pipeline::Pipeline(Mission mission, const PipelineParams& params, const CameraModel& camera,
                   const CameraMount& mount)
    : mission_(mission), params_(params), camera_(camera), mount_(mount), tracker_(params.tracker) {
  assert(mission != Mission::kNone);
  params_.validate();
}

void Pipeline::reset() {
  tracker_.reset();
  poses_.clear();
  held_.reset();
  last_utime_ = 0;
}

FrameResult Pipeline::process(const cv::Mat& gray, int64_t utime,
                              const std::optional<PoseSample>& pose,
                              std::optional<double> exposure_s) {
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
  // A gap or a jump in the frames' times: nothing from before it is trusted, the held reference
  // included (the tracker sees such a gap only while its history holds frames).
  if (last_utime_ != 0 && (utime <= last_utime_ ||
                           double(utime - last_utime_) * 1e-6 > params_.tracker.max_frame_gap_s))
    held_.reset();
  last_utime_ = utime;

  const cv::Mat integral = integral_image(gray);
  auto kps = detect_star(gray, integral,
                         mission_ == Mission::kIngress ? params_.ingress_star : params_.star);
  if (!kps) return fail(kps.reason());
  r.n_features = static_cast<int>(kps->size());
  for (const auto& k : *kps) r.features_px.emplace_back(k.x, k.y);

  // Descriptors of every frame share one world-fixed pattern orientation, so yaw between the
  // reference and now does not break matching: world x for the downward camera, world up for
  // the forward one (world x is near its optical axis).
  const Isometry3d X_WC = camera_in_world(pose->X_WB(), mount_.X_BC());
  const Vector3d d_W = mission_ == Mission::kIngress ? Vector3d::UnitZ() : Vector3d::UnitX();
  TrackedFrame frame;
  frame.utime = utime;
  frame.pattern_angle_rad = pattern_angle(X_WC.linear(), d_W);
  frame.descriptors = describe_surf(integral, *kps, params_.surf, frame.pattern_angle_rad);
  frame.keypoints = std::move(*kps);
  const double max_blur_px = mission_ == Mission::kLanding ? params_.landing.max_motion_blur_px : 0;
  if (max_blur_px > 0)
    frame.blur_px = floor_motion_blur_px(camera_, mount_, *pose, params_.landing.floor_z_m,
                                         exposure_s.value_or(params_.landing.assumed_exposure_s));
  r.blur_px = frame.blur_px;
  const auto smeared = [&](const TrackedFrame& f) {
    return max_blur_px > 0 && f.blur_px > max_blur_px;
  };
  // Ingress compares the current image with the reference's warped by the wall homography: each
  // frame keeps its image smoothed as that comparison wants it, made once (issue 15).
  const bool parallax = mission_ == Mission::kIngress && params_.ingress.parallax_mask;
  if (parallax) frame.image = parallax_image(gray, params_.ingress);
  // Landing checks its planes against both images and looks for the top's rim in them
  // (landing_target.hpp): the caller's pixels are not ours to keep, and with both off no copy
  // is made.
  const bool landing_images =
      mission_ == Mission::kLanding &&
      (params_.landing.photometric_tol > 0 || params_.landing.rim_search_m > 0);
  if (landing_images) frame.image = gray.clone();

  const auto up = tracker_.add(std::move(frame));
  const bool hold = mission_ == Mission::kLanding && params_.landing.hold_reference;
  if (up.reset) {
    poses_.clear();
    // Tracks broken by a changed view or a frame of few features (a pale floor loses its weak
    // features from frame to frame) say nothing about the held reference: it is used only where
    // it still matches min_tracked features directly (a gap in time dropped it above). Dropping
    // it with every reset restarted the baseline from zero every 1-2 s over landing_lowtex's
    // floor, short of the top's parallax in refinement (seeds 9306, 9309, 9314: target lost with
    // every retry).
    if (!hold) held_.reset();
  }
  if (up.current) poses_.emplace_back(utime, *pose);
  // Keep only the poses of frames the tracker can still pick.
  const int64_t oldest = up.reference ? up.reference->utime : utime;
  while (!poses_.empty() && poses_.front().first < oldest) poses_.pop_front();
  r.n_tracked = up.n_tracked;
  if (up.current && smeared(*up.current)) return fail(Reason::kMotionBlur);
  // No tracked reference (the tracks just broke): only the held one can serve.
  const bool held_only = up.status == Reason::kNoReference && up.current && hold && held_;
  if (up.status != Reason::kOk && !held_only) return fail(up.status);
  // The oldest qualifying frame within max_reference_baseline_m of the current camera (the
  // newest previous frame when even that one is farther); never a smeared one.
  std::shared_ptr<const TrackedFrame> ref =
      up.reference && !smeared(*up.reference) ? up.reference : nullptr;
  PoseSample pose_1;
  double baseline_m = 0.0;  // none tracked: any held baseline is longer
  bool skipped_smeared = false;
  if (up.reference) {
    const auto& h = tracker_.history();
    const Vector3d c_now = X_WC.translation();
    for (size_t k = 0; k + 1 < h.size(); ++k) {
      const auto pose_k = std::find_if(poses_.begin(), poses_.end(),
                                       [&](const auto& e) { return e.first == h[k]->utime; });
      if (pose_k == poses_.end()) continue;
      if (smeared(*h[k])) {
        skipped_smeared = true;
        continue;
      }
      ref = h[k];
      if ((camera_in_world(pose_k->second.X_WB(), mount_.X_BC()).translation() - c_now).norm() <=
          params_.max_reference_baseline_m)
        break;
    }
  }
  if (ref) {
    const auto ref_pose = std::find_if(poses_.begin(), poses_.end(),
                                       [&](const auto& e) { return e.first == ref->utime; });
    assert(ref_pose != poses_.end());
    pose_1 = ref_pose->second;
    baseline_m = mocap_motion(pose_1, *pose, mount_).baseline_m;
  }

  const TrackedFrame& b = *up.current;
  const auto sb = response_signs(b.keypoints);
  auto match_to_current = [&](const TrackedFrame& a) {
    const auto sa = response_signs(a.keypoints);
    return match_descriptors(a.descriptors, b.descriptors, params_.match, &sa, &sb);
  };
  // Hovering: the held reference while the tracked one is too close, the held one farther
  // and still overlapping (pipeline.hpp).
  std::vector<Match> matches;
  if (hold && baseline_m < params_.landing.hold_baseline_m && held_ && held_->utime < utime &&
      double(utime - held_->utime) * 1e-6 <= params_.landing.hold_max_age_s) {
    const double held_baseline_m = mocap_motion(held_pose_, *pose, mount_).baseline_m;
    if (held_baseline_m > baseline_m && held_baseline_m <= params_.max_reference_baseline_m) {
      auto m = match_to_current(*held_);
      if (static_cast<int>(m.size()) >= params_.tracker.min_tracked) {
        ref = held_;
        pose_1 = held_pose_;
        baseline_m = held_baseline_m;
        matches = std::move(m);
        r.ref_held = true;
      }
      // A frame that matches the held reference with fewer than min_tracked features hands the
      // hold to the tracked one: keeping it held through such frames saved no pale-floor draw
      // and multiplied the false targets over floors without a platform.
    }
  }
  // Neither a tracked nor the held reference serves.
  if (!ref)
    return fail(skipped_smeared            ? Reason::kMotionBlur
                : up.status != Reason::kOk ? up.status
                                           : Reason::kNoReference);
  if (hold) {
    held_ = ref;
    held_pose_ = pose_1;
  }
  r.ref_utime = ref->utime;

  Correspondences c;
  c.camera = &camera_;
  c.mount = &mount_;
  c.pose_1 = pose_1;
  c.pose_2 = *pose;
  r.baseline_m = baseline_m;
  if (r.baseline_m < params_.waypoint.min_baseline_m) return fail(Reason::kSmallBaseline);

  const TrackedFrame& a = *ref;
  if (!r.ref_held) matches = match_to_current(a);
  r.n_matches = static_cast<int>(matches.size());
  const Matrix3d K = camera_.K();
  for (const auto& m : matches) {
    const auto& k1 = a.keypoints[m.i1];
    const auto& k2 = b.keypoints[m.i2];
    c.x1.push_back((K * camera_.ray({k1.x, k1.y})).hnormalized());
    c.x2.push_back((K * camera_.ray({k2.x, k2.y})).hnormalized());
    c.u1.emplace_back(k1.x, k1.y);
    c.u2.emplace_back(k2.x, k2.y);
  }
  r.matched_px = c.u2;
  const TargetOutcome t = mission_ == Mission::kLanding
                              ? find_landing_target(c, params_, a.image, gray)
                              : find_ingress_target(c, gray, parallax ? b.image : cv::Mat(),
                                                    parallax ? a.image : cv::Mat(), params_);
  r.target = t.estimate;
  r.labels = t.labels;
  r.lines = t.lines;
  r.reason = t.reason;
  return r;
}

}  // namespace alight::vision

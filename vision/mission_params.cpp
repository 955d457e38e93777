#include "vision/mission_params.hpp"

namespace alight::vision {

void LandingParams::validate() const {
  param_check(min_platform_inliers >= 4, "landing.min_platform_inliers", min_platform_inliers,
              "must be >= 4");
  param_check(min_height_m > 0, "landing.min_height_m", min_height_m, "must be > 0");
  param_check(max_height_m > min_height_m, "landing.max_height_m", max_height_m,
              "must be > min_height_m");
  param_check(max_normal_angle_deg > 0 && max_normal_angle_deg < 90, "landing.max_normal_angle_deg",
              max_normal_angle_deg, "must be in (0, 90)");
  param_check(max_tilt_deg > 0 && max_tilt_deg < 90, "landing.max_tilt_deg", max_tilt_deg,
              "must be in (0, 90)");
  param_check(edge_margin_px >= 0, "landing.edge_margin_px", edge_margin_px, "must be >= 0");
}

void IngressParams::validate() const {
  param_check(canny_low > 0 && canny_high > canny_low, "ingress.canny_high", canny_high,
              "must be > canny_low > 0");
  param_check(hough_threshold >= 1, "ingress.hough_threshold", hough_threshold, "must be >= 1");
  param_check(hough_min_length_frac > 0 && hough_min_length_frac < 1,
              "ingress.hough_min_length_frac", hough_min_length_frac, "must be in (0, 1)");
  param_check(hough_max_gap_px >= 0, "ingress.hough_max_gap_px", hough_max_gap_px, "must be >= 0");
  param_check(max_line_tilt_deg > 0 && max_line_tilt_deg < 45, "ingress.max_line_tilt_deg",
              max_line_tilt_deg, "must be in (0, 45)");
  param_check(merge_px >= 0, "ingress.merge_px", merge_px, "must be >= 0");
  param_check(blur_sigma_px >= 0 && blur_sigma_px <= 10, "ingress.blur_sigma_px", blur_sigma_px,
              "must be in [0, 10]");
  param_check(parallax_blur_sigma_px >= 0 && parallax_blur_sigma_px <= 10,
              "ingress.parallax_blur_sigma_px", parallax_blur_sigma_px, "must be in [0, 10]");
  param_check(parallax_min_diff > 0 && parallax_min_diff < 255, "ingress.parallax_min_diff",
              parallax_min_diff, "must be in (0, 255)");
  param_check(parallax_noise_k >= 0, "ingress.parallax_noise_k", parallax_noise_k, "must be >= 0");
  param_check(parallax_close_px >= 0 && parallax_close_px <= 101, "ingress.parallax_close_px",
              parallax_close_px, "must be in [0, 101]");
  param_check(parallax_open_px >= 0 && parallax_open_px <= 101, "ingress.parallax_open_px",
              parallax_open_px, "must be in [0, 101]");
  param_check(cut_margin_px >= 0 && cut_margin_px <= 50, "ingress.cut_margin_px", cut_margin_px,
              "must be in [0, 50]");
  param_check(snap_px >= 0 && snap_px <= 30, "ingress.snap_px", snap_px, "must be in [0, 30]");
  param_check(snap_min_gradient >= 0, "ingress.snap_min_gradient", snap_min_gradient,
              "must be >= 0");
  param_check(min_outliers >= 1, "ingress.min_outliers", min_outliers, "must be >= 1");
  param_check(min_size_m > 0, "ingress.min_size_m", min_size_m, "must be > 0");
  param_check(behind_margin_m >= 0, "ingress.behind_margin_m", behind_margin_m, "must be >= 0");
  param_check(min_behind_share >= 0 && min_behind_share <= 1, "ingress.min_behind_share",
              min_behind_share, "must be in [0, 1]");
}

void PipelineParams::validate() const {
  star.validate();
  surf.validate();
  tracker.validate();
  match.validate();
  homography.validate();
  decomposition.validate();
  align.validate();
  waypoint.validate();
  landing.validate();
  ingress.validate();
  param_check(max_reference_baseline_m > waypoint.min_baseline_m, "max_reference_baseline_m",
              max_reference_baseline_m, "must exceed waypoint.min_baseline_m");
}

void NodeParams::validate() const {
  pipeline.validate();
  poses.validate();
  // Finite and bounded (NaN fails every comparison): `.inf` made every frame wait for its pose
  // forever, and an infinite wait converted to microseconds is undefined behaviour.
  param_check(max_pose_wait_s >= 0 && max_pose_wait_s <= 5.0, "max_pose_wait_s", max_pose_wait_s,
              "must be in [0, 5] s");
  param_check(diag_rate_hz >= 0 && diag_rate_hz <= 100.0, "diag_rate_hz", diag_rate_hz,
              "must be in [0, 100] Hz");
  param_check(diag_jpeg_quality >= 1 && diag_jpeg_quality <= 100, "diag_jpeg_quality",
              diag_jpeg_quality, "must be in [1, 100]");
}

namespace {

void read_seed(const ParamNode& n, const std::string& key, uint64_t& seed) {
  int64_t s = static_cast<int64_t>(seed);
  n.read(key, s);
  n.check(s >= 0, key, "must be >= 0");
  seed = static_cast<uint64_t>(s);
}

}  // namespace

NodeParams load_node_params(const ParamNode& root) {
  NodeParams p;
  const auto section = root.optional_child("vision");
  if (!section) return p;
  const ParamNode& n = *section;
  PipelineParams& q = p.pipeline;
  n.read("max_pose_wait_s", p.max_pose_wait_s);
  n.read("diag_rate_hz", p.diag_rate_hz);
  n.read("diag_jpeg_quality", p.diag_jpeg_quality);
  n.read("max_reference_baseline_m", q.max_reference_baseline_m);
  if (auto c = n.optional_child("poses")) {
    c->read("history_s", p.poses.history_s);
    c->read("max_gap_s", p.poses.max_gap_s);
    c->finish();
  }
  if (auto c = n.optional_child("star")) {
    c->read("response_threshold", q.star.response_threshold);
    c->read("max_size", q.star.max_size);
    c->read("max_features", q.star.max_features);
    c->read("grid_cols", q.star.grid_cols);
    c->read("grid_rows", q.star.grid_rows);
    c->finish();
  }
  if (auto c = n.optional_child("tracker")) {
    c->read("min_tracked", q.tracker.min_tracked);
    c->read("max_history", q.tracker.max_history);
    c->read("max_frame_gap_s", q.tracker.max_frame_gap_s);
    c->read("max_reference_age_s", q.tracker.max_reference_age_s);
    read_seed(*c, "seed", q.tracker.seed);
    c->finish();
  }
  if (auto c = n.optional_child("match")) {
    c->read("ratio", q.match.ratio);
    c->read("max_distance", q.match.max_distance);
    c->finish();
  }
  if (auto c = n.optional_child("homography")) {
    c->read("threshold_px", q.homography.threshold_px);
    c->read("max_iterations", q.homography.max_iterations);
    c->read("min_inliers", q.homography.min_inliers);
    read_seed(*c, "seed", q.homography.seed);
    c->finish();
  }
  if (auto c = n.optional_child("align")) {
    c->read("max_rotation_disagreement_deg", q.align.max_rotation_disagreement_deg);
    c->read("max_translation_disagreement_deg", q.align.max_translation_disagreement_deg);
    c->read("max_iterations", q.align.max_iterations);
    c->read("robust", q.align.robust);
    c->read("rotation_prior_sigma_deg", q.align.rotation_prior_sigma_deg);
    c->read("feature_sigma_px", q.align.feature_sigma_px);
    c->finish();
  }
  if (auto c = n.optional_child("waypoint")) {
    c->read("min_baseline_m", q.waypoint.min_baseline_m);
    c->read("max_translation_angle_deg", q.waypoint.max_translation_angle_deg);
    c->read("max_rotation_error_deg", q.waypoint.max_rotation_error_deg);
    c->finish();
  }
  if (auto c = n.optional_child("landing")) {
    c->read("min_platform_inliers", q.landing.min_platform_inliers);
    c->read("min_height_m", q.landing.min_height_m);
    c->read("max_height_m", q.landing.max_height_m);
    c->read("max_normal_angle_deg", q.landing.max_normal_angle_deg);
    c->read("max_tilt_deg", q.landing.max_tilt_deg);
    c->read("edge_margin_px", q.landing.edge_margin_px);
    c->finish();
  }
  if (auto c = n.optional_child("ingress")) {
    c->read("parallax_mask", q.ingress.parallax_mask);
    c->read("parallax_blur_sigma_px", q.ingress.parallax_blur_sigma_px);
    c->read("parallax_min_diff", q.ingress.parallax_min_diff);
    c->read("parallax_noise_k", q.ingress.parallax_noise_k);
    c->read("parallax_close_px", q.ingress.parallax_close_px);
    c->read("parallax_open_px", q.ingress.parallax_open_px);
    c->read("snap_px", q.ingress.snap_px);
    c->read("snap_min_gradient", q.ingress.snap_min_gradient);
    c->read("blur_sigma_px", q.ingress.blur_sigma_px);
    c->read("hough_max_gap_px", q.ingress.hough_max_gap_px);
    c->read("merge_px", q.ingress.merge_px);
    c->read("cut_margin_px", q.ingress.cut_margin_px);
    c->read("canny_low", q.ingress.canny_low);
    c->read("canny_high", q.ingress.canny_high);
    c->read("hough_threshold", q.ingress.hough_threshold);
    c->read("hough_min_length_frac", q.ingress.hough_min_length_frac);
    c->read("max_line_tilt_deg", q.ingress.max_line_tilt_deg);
    c->read("min_outliers", q.ingress.min_outliers);
    c->read("min_size_m", q.ingress.min_size_m);
    c->read("behind_margin_m", q.ingress.behind_margin_m);
    c->read("min_behind_share", q.ingress.min_behind_share);
    c->finish();
  }
  n.validate(p);
  n.finish();
  return p;
}

NodeParams load_node_params(const std::string& vehicle_file) {
  return load_node_params(ParamNode::load_file(vehicle_file));
}

Mission mission_from_string(const std::string& s) {
  if (s == "landing") return Mission::kLanding;
  if (s == "ingress") return Mission::kIngress;
  throw ParamError("", "--mission", s, "must be landing or ingress");
}

}  // namespace alight::vision

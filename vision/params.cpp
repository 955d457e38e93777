#include "vision/params.hpp"

#include <cmath>

namespace alight::vision {

const ParamSchema<StarParams>& StarParams::schema() {
  using P = StarParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("min_size", &P::min_size, Range::ge(1), "",
          "smallest filter index n: inner box 2n+1, outer 4n+1 px. Not 1: the 3 x 3 / 5 x 5 "
          "filter answers to single-pixel texture and noise that a little blur or a 10 % scale "
          "change removes, so on fine texture (fur, gravel) those peaks took most of the "
          "max_features budget and were not found again in the other view");
    s.add("max_size", &P::max_size, Range::closed(1, 32), "",
          "largest filter index n (a border of 2n+1 px is skipped)")
        .check([](const P& p) { return p.max_size >= p.min_size; }, "must not be below min_size");
    s.add("response_threshold", &P::response_threshold, Range::ge(0), "grey levels",
          "|mean(inner) - mean(ring)| to keep a peak");
    s.add("line_threshold", &P::line_threshold, Range::gt(1), "",
          "Harris ratio r: reject edges with tr^2/det > (r+1)^2/r");
    s.add("nms_radius_px", &P::nms_radius_px, Range::closed(1, 8), "px",
          "spatial non-maximum suppression radius");
    s.add("max_features", &P::max_features, Range::ge(0), "", "strongest peaks kept (0: all)");
    s.add("grid_cols", &P::grid_cols, Range::closed(0, 64), "",
          "spread over the image (0: off): first at most max_features / (grid_cols * grid_rows) "
          "strongest per cell, then the strongest of the rest. A richly textured patch (a printed "
          "platform top) otherwise takes nearly all features and leaves the floor too few for "
          "its homography");
    s.add("grid_rows", &P::grid_rows, Range::closed(0, 64), "", "rows of that grid")
        .check([](const P& p) { return (p.grid_cols == 0) == (p.grid_rows == 0); },
               "grid_cols and grid_rows are both 0 (off) or both > 0");
    s.add("subpixel", &P::subpixel, Range::any(), "",
          "paper 3.1.1: quadratic refinement of x, y and scale");
    return s;
  }();
  return schema;
}

const ParamSchema<SurfParams>& SurfParams::schema() {
  using P = SurfParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("scale_per_size", &P::scale_per_size, Range::gt(0), "",
          "SURF scale s per CenSurE filter half-width (n + 0.5)");
    s.add("min_scale", &P::min_scale, Range::ge(0.5), "px",
          "lower bound of s (Haar size 2s >= 2 px)");
    s.add("overlapping_subregions", &P::overlapping_subregions, Range::any(), "",
          "MU-SURF sub-regions (Agrawal, Konolige & Blas 2008, sec. 4): overlapping by 2s, each "
          "Gaussian-weighted about its centre, and the 4 x 4 grid weighted again; false: SURF's "
          "disjoint 5s x 5s sub-regions under one window Gaussian");
    return s;
  }();
  return schema;
}

const ParamSchema<MatchParams>& MatchParams::schema() {
  using P = MatchParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("ratio", &P::ratio, Range::open_closed(0, 1), "",
          "Lowe's ratio test: best / second-best distance must be below this");
    s.add("mutual", &P::mutual, Range::any(), "",
          "keep a match only if it is also the reverse best match");
    s.add("max_distance", &P::max_distance, Range::open_closed(0, 2), "",
          "Euclidean distance of unit descriptors above which nothing matches");
    s.add("same_sign_only", &P::same_sign_only, Range::any(), "",
          "match bright blobs with bright, dark with dark (SURF's trick)");
    return s;
  }();
  return schema;
}

const ParamSchema<TrackerParams>& TrackerParams::schema() {
  using P = TrackerParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("min_tracked", &P::min_tracked, Range::ge(4), "",
          "N: features that must be tracked from the reference to now");
    s.add("max_history", &P::max_history, Range::ge(2), "",
          "frames kept (bounds the reference age in frames)");
    // Finite and bounded: an infinite gap or age would keep a reference from any time ago.
    s.add("max_frame_gap_s", &P::max_frame_gap_s, Range::open_closed(0, 60), "s",
          "a larger gap between frames resets the history");
    s.add("max_reference_age_s", &P::max_reference_age_s, Range::open_closed(0, 600), "s",
          "older frames are never the reference");
    s.section("match", &P::match, MatchParams::schema(), "frame-to-frame matching");
    s.add("frame_threshold_px", &P::frame_threshold_px, Range::ge(0), "px",
          "frame-to-frame matches must fit one homography within this; consecutive frames are "
          "close, so off-plane parallax stays below it while wrong matches do not (0: no check)");
    s.add("seed", &P::seed, Range::any(), "", "RANSAC seed of the frame-to-frame check");
    return s;
  }();
  return schema;
}

const ParamSchema<HomographyParams>& HomographyParams::schema() {
  using P = HomographyParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("threshold_px", &P::threshold_px, Range::gt(0), "px",
          "inlier if the transfer error in image 2 is below");
    s.add("confidence", &P::confidence, Range::open(0, 1), "",
          "adaptive stopping: probability of one all-inlier sample");
    s.add("max_iterations", &P::max_iterations, Range::ge(1), "", "hard cap of RANSAC samples");
    s.add("min_inliers", &P::min_inliers, Range::ge(4), "", "fewer inliers: no plane");
    s.add("refine_iterations", &P::refine_iterations, Range::ge(0), "",
          "Levenberg-Marquardt steps on the inliers' transfer error");
    s.add("robust_refinement", &P::robust_refinement, Range::any(), "",
          "final refinement Cauchy-weighted (IRLS) instead of plain least squares over the "
          "inliers, its scale from their median residual, so near-miss matches just inside "
          "threshold_px pull less (Holland & Welsch 1977)");
    s.add("local_neighbours", &P::local_neighbours, Range::ge(3), "",
          "second plane (3.2): the 3 other points of a sample are drawn among the k nearest "
          "neighbours of the first in image 1 (a platform is compact), which also bounds the "
          "work when no second plane exists: stop once a plane of min_inliers would have been "
          "sampled with `confidence`");
    s.add("seed", &P::seed, Range::any(), "", "RANSAC random seed");
    return s;
  }();
  return schema;
}

const ParamSchema<DecompositionParams>& DecompositionParams::schema() {
  using P = DecompositionParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("min_singular_gap", &P::min_singular_gap, Range::gt(0), "",
          "sigma1 - sigma3 of the normalised H below this: no translation");
    s.add("min_front_fraction", &P::min_front_fraction, Range::open_closed(0.5, 1), "",
          "share of inliers that must lie in front of both cameras");
    return s;
  }();
  return schema;
}

const ParamSchema<AlignParams>& AlignParams::schema() {
  using P = AlignParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("max_rotation_disagreement_deg", &P::max_rotation_disagreement_deg, Range::gt(0), "deg",
          "the two planes' R21 must agree within this");
    s.add("max_translation_disagreement_deg", &P::max_translation_disagreement_deg, Range::gt(0),
          "deg", "the two planes' t12 directions must agree within this");
    s.add("max_iterations", &P::max_iterations, Range::ge(0), "",
          "Levenberg-Marquardt iterations of the joint refinement");
    s.add("robust", &P::robust, Range::any(), "",
          "joint refinement Cauchy-weighted (IRLS, each plane's scale from its median residual) "
          "instead of plain least squares, as the final fit of each homography");
    s.add("rotation_prior_sigma_deg", &P::rotation_prior_sigma_deg, Range::ge(0), "deg",
          "motion capture's R21 as a prior on the joint refinement, with this standard "
          "deviation; 0 = vision alone (the paper). Breaks the rotation-translation (bas-relief) "
          "ambiguity of a narrow field of view that leaves the planes' distances a few percent "
          "off");
    s.add("feature_sigma_px", &P::feature_sigma_px, Range::gt(0), "px",
          "feature position noise the prior is weighed against");
    return s;
  }();
  return schema;
}

const ParamSchema<MovingTopParams>& MovingTopParams::schema() {
  using P = MovingTopParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "",
          "measure a moving platform's top on every landing frame (VISION_PLATFORM); "
          "VISION_TARGET does not depend on it");
    s.add("top_height_m", &P::top_height_m, Range::closed(0, 2), "m",
          "the plane the top is placed on, above the floor: an independently moving plane's depth "
          "is not observable from two level views; published with each measurement, so that "
          "autonomy measures the true height over many (a climbing or descending camera)");
    s.add("top_height_sigma_m", &P::top_height_sigma_m, Range::ge(0), "m",
          "its uncertainty, carried into the published covariances");
    s.add("interval_s", &P::interval_s, Range::gt(0), "s",
          "the earlier frame: the newest at least this much older than the current one");
    s.add("max_interval_s", &P::max_interval_s, Range::gt(0), "s",
          "no earlier frame within this: nothing measured; the oldest within it measures again a "
          "top the floor carries over interval_s (one creeping through its turn)")
        .check([](const P& p) { return p.max_interval_s >= p.interval_s; },
               "must not be below interval_s");
    s.add("floor_tol_px", &P::floor_tol_px, Range::gt(0), "px",
          "a match the known floor carries within this lies on the floor");
    s.add("threshold_px", &P::threshold_px, Range::gt(0), "px",
          "a match follows the top's motion within this (converted at its depth)");
    s.add("min_inliers", &P::min_inliers, Range::ge(3), "", "matches on the moving top");
    s.add("iterations", &P::iterations, Range::closed(1, 100000), "",
          "RANSAC draws of two matches");
    s.add("seed", &P::seed, Range::any(), "", "RANSAC random seed");
    s.add("max_speed_mps", &P::max_speed_mps, Range::gt(0), "m/s",
          "a faster top is refused (TOO_FAST)");
    s.add("max_yaw_rate_dps", &P::max_yaw_rate_dps, Range::gt(0), "deg/s",
          "a faster turn is refused (TOO_FAST)");
    s.add("max_scale_change", &P::max_scale_change, Range::open(0, 1), "",
          "|s - 1| of the plane's similarity between the views (heave over the camera's height)");
    s.add("min_size_m", &P::min_size_m, Range::ge(0), "m",
          "the inliers' extent, short side, at least this (SIZE)");
    s.add("max_size_m", &P::max_size_m, Range::gt(0), "m",
          "the inliers' extent, long side, at most this (SIZE)")
        .check([](const P& p) { return p.max_size_m > p.min_size_m; }, "must exceed min_size_m");
    s.add("max_floor_share", &P::max_floor_share, Range::closed(0, 1), "",
          "the top's matches the known floor also carries, at most this share (ON_FLOOR)");
    return s;
  }();
  return schema;
}

const ParamSchema<WaypointParams>& WaypointParams::schema() {
  using P = WaypointParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("min_baseline_m", &P::min_baseline_m, Range::gt(0), "m",
          "smaller camera translation: no usable scale (eq. 3)");
    s.add("max_translation_angle_deg", &P::max_translation_angle_deg, Range::open_closed(0, 180),
          "deg", "vision's t12 direction against motion capture's");
    s.add("max_rotation_error_deg", &P::max_rotation_error_deg, Range::gt(0), "deg",
          "vision's R21 against motion capture's");
    return s;
  }();
  return schema;
}

const ParamSchema<LandingParams>& LandingParams::schema() {
  using P = LandingParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("min_platform_inliers", &P::min_platform_inliers, Range::ge(4), "",
          "fewer second-plane inliers: no platform");
    s.add("min_height_m", &P::min_height_m, Range::gt(0), "m",
          "the platform top is at least this far above the floor");
    s.add("max_height_m", &P::max_height_m, Range::gt(0), "m",
          "and at most this far (a larger step is no landing platform)")
        .check([](const P& p) { return p.max_height_m > p.min_height_m; },
               "must be > min_height_m");
    s.add("max_normal_angle_deg", &P::max_normal_angle_deg, Range::open(0, 90), "deg",
          "floor and platform normals agree within this");
    s.add("max_tilt_deg", &P::max_tilt_deg, Range::open(0, 90), "deg",
          "the platform top is level: its normal within this of world up (motion capture). A "
          "second \"plane\" through the platform's edge and the floor beyond is tilted by "
          "atan(h / d); in flight such false planes came out 3-12 deg, true tops within 1 deg");
    s.add("edge_margin_px", &P::edge_margin_px, Range::ge(0), "px",
          "platform inliers this close to the border of either image: the platform may extend "
          "out of view, the centre of its visible features is not its centre "
          "(REASON_PARTIAL_VIEW). Matched features thin out well inside the STAR border "
          "(2 max_size + 1 px): in flight logs a 24 px band let cut platforms through (waypoints "
          "5-17 cm off), 40 px none beyond 5 cm");
    s.add("floor_z_m", &P::floor_z_m, Range::any(), "m",
          "beyond the paper (known_floor.hpp): the floor is the plane z = floor_z_m of the "
          "motion-capture (world) frame");
    s.add("floor_prior", &P::floor_prior, Range::any(), "",
          "when the known floor and motion find the planes: off = never (the paper's two free "
          "homographies only); fallback = when the paper's planes give no platform, or their "
          "floor is not the known one (floor_tol_frac); always = instead of the paper's")
        .one_of({"off", "fallback", "always"});
    s.add("floor_tol_frac", &P::floor_tol_frac, Range::open(0, 1), "",
          "fallback: the paper's floor is the known floor when their distances from the "
          "reference camera agree within this fraction (and the normals within "
          "max_normal_angle_deg)");
    s.add("min_floor_inliers", &P::min_floor_inliers, Range::ge(1), "",
          "known floor: fewer matches on it, no planes (the rotation correction rests on them)");
    s.add("max_rotation_correction_deg", &P::max_rotation_correction_deg, Range::open(0, 10), "deg",
          "known floor: motion capture's R21 is corrected by at most this (its orientation noise, "
          "0.1 deg a sample, moves the image by 1-2 px; a correction the size of the "
          "platform's parallax would take the top for the floor)");
    s.add("hold_reference", &P::hold_reference, Range::any(), "",
          "beyond the paper: while the tracked reference is closer than max_reference_baseline_m "
          "(the camera hovers), keep the previous frame's reference when it is farther from the "
          "camera (within max_reference_baseline_m, and at most 30 s old) and still matches "
          "tracker.min_tracked features: continuous tracks die within 1-2 s of hovering (or "
          "max_history frames pass), and the tracked reference's baseline then shrinks until the "
          "top's parallax is lost");
    s.add("max_motion_blur_px", &P::max_motion_blur_px, Range::ge(0), "px",
          "beyond the paper (motion_blur.hpp): a frame whose exposure smeared the floor's image "
          "farther than this anywhere in the view (from motion capture's velocity and angular "
          "rate, the camera's exposure time and the floor's plane) is neither measured nor "
          "taken as a reference (REASON_MOTION_BLUR). The turns of the search path smear the "
          "floor several times as far as the frames a platform is found in, and the matches of "
          "such frames can make false tops over bare photographed floors. 0: off");
    s.add("assumed_exposure_s", &P::assumed_exposure_s, Range::open_closed(0, 1), "s",
          "max_motion_blur_px: the exposure time of a frame that does not carry its own (no "
          "exposure_us metadata: a camera on automatic exposure); the longest a camera indoors "
          "would expose, so that the guard errs on the side of refusing");
    return s;
  }();
  return schema;
}

const ParamSchema<IngressParams>& IngressParams::schema() {
  using P = IngressParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("parallax_mask", &P::parallax_mask, Range::any(), "",
          "beyond the paper: Canny and Hough run on the off-wall mask (the reference image "
          "warped by the wall homography disagrees with the current one wherever the view passes "
          "the wall plane) instead of on the grey image, whose wall texture and the frame's "
          "inner faces give edges of their own while the opening's border can lack contrast. "
          "false: the paper's edges");
    s.add("parallax_decimation", &P::parallax_decimation, Range::closed(1, 4), "",
          "the mask is made on a grid this many times coarser and scaled back up (1: full "
          "size; 2 costs a quarter of the warp, blurs and morphology, but widens the "
          "opening's width and height errors' tails)");
    s.add("parallax_blur_sigma_px", &P::parallax_blur_sigma_px, Range::closed(0, 10), "px",
          "smoothing of both images before the difference");
    s.add("parallax_min_diff", &P::parallax_min_diff, Range::open(0, 255), "grey levels",
          "smallest off-wall difference");
    s.add("parallax_noise_k", &P::parallax_noise_k, Range::ge(0), "",
          "or k x the median difference at wall inliers");
    s.add("parallax_close_px", &P::parallax_close_px, Range::closed(0, 101), "px",
          "closing fills texture-poor holes off the wall");
    s.add("parallax_open_px", &P::parallax_open_px, Range::closed(0, 101), "px",
          "opening drops specks on the wall");
    s.add("max_border_lines", &P::max_border_lines, Range::closed(1, 1000), "",
          "the mask border's strongest distinct Hough lines refined into cuts, no more");
    s.add("snap_px", &P::snap_px, Range::closed(0, 30), "px",
          "a cut snaps to the wall's edge within this (0: off)");
    s.add("snap_min_gradient", &P::snap_min_gradient, Range::ge(0), "Sobel units",
          "a weaker mean step along the cut is no edge");
    s.add("blur_sigma_px", &P::blur_sigma_px, Range::closed(0, 10), "px",
          "Gaussian smoothing before Canny (0: none)");
    s.add("canny_low", &P::canny_low, Range::gt(0), "grey levels", "Canny hysteresis: low");
    s.add("canny_high", &P::canny_high, Range::gt(0), "grey levels", "Canny hysteresis: high")
        .check([](const P& p) { return p.canny_high > p.canny_low; }, "must be > canny_low");
    s.add("hough_threshold", &P::hough_threshold, Range::ge(1), "",
          "accumulator votes for a segment");
    s.add("hough_min_length_frac", &P::hough_min_length_frac, Range::open(0, 1), "",
          "shortest segment, share of the image width");
    s.add("hough_max_gap_px", &P::hough_max_gap_px, Range::ge(0), "px",
          "largest gap joined within a segment");
    s.add("max_line_tilt_deg", &P::max_line_tilt_deg, Range::open(0, 45), "deg",
          "near-vertical / near-horizontal within this");
    s.add("merge_px", &P::merge_px, Range::ge(0), "px", "cuts closer than this are one cut");
    s.add("cut_margin_px", &P::cut_margin_px, Range::closed(0, 50), "px",
          "wall inliers this close to a cut do not count");
    s.add("min_outliers", &P::min_outliers, Range::ge(1), "",
          "fewer off-wall features in the block: no opening");
    s.add("behind_margin_m", &P::behind_margin_m, Range::ge(0), "m",
          "a block feature this far behind the wall is seen through it");
    s.add("min_behind_share", &P::min_behind_share, Range::closed(0, 1), "",
          "fewer of the block's features behind the wall: no opening (0: no check)");
    s.add(
        "min_opening_parallax_px", &P::min_opening_parallax_px, Range::ge(0), "px",
        "a whole opening is measured only when what is seen through it (the block's features "
        "behind the wall) moves at least this much against the wall homography, median; less, "
        "REASON_LOW_PARALLAX (located, not measured): the mask covers part of the opening. Tied to "
        "parallax_close_px, the gaps the mask's closing joins (0: no check)");
    s.add("min_size_m", &P::min_size_m, Range::gt(0), "m", "smaller width or height: no opening");
    return s;
  }();
  return schema;
}

const ParamSchema<PipelineParams>& PipelineParams::schema() {
  using P = PipelineParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("max_reference_baseline_m", &P::max_reference_baseline_m, Range::gt(0), "m",
          "the reference is the oldest tracked frame (3.1.1) no farther than this from the "
          "current camera: a target must be in view in both images, and a 0.6 m baseline (a "
          "search pass at 0.4 m/s) leaves a 43 cm platform wholly in neither; landing above "
          "the search height, the view's share kReferenceViewShare where that is more")
        .check([](const P& p) { return p.max_reference_baseline_m > p.waypoint.min_baseline_m; },
               "must exceed waypoint.min_baseline_m");
    s.section("star", &P::star, StarParams::schema(),
              "STAR / CenSurE detector (paper 3.1.1; Agrawal, Konolige & Blas 2008) of the "
              "landing mission (the downward camera); ingress has its own, ingress_star");
    s.section("ingress_star", &P::ingress_star, StarParams::schema(),
              "the STAR detector of the ingress mission (the forward camera): the keys of star, "
              "with a coarser grid and a smaller budget by default");
    s.section("surf", &P::surf, SurfParams::schema(),
              "upright SURF descriptor (Bay, Tuytelaars & Van Gool 2006)");
    s.section("tracker", &P::tracker, TrackerParams::schema(),
              "reference frame by continuous tracking (paper 3.1.1)");
    s.section("match", &P::match, MatchParams::schema(), "reference-to-current matching");
    s.section("homography", &P::homography, HomographyParams::schema(),
              "RANSAC homography of the dominant plane (paper 3.1.2)");
    s.section("decomposition", &P::decomposition, DecompositionParams::schema(),
              "homography decomposition (paper 3.1.2; Longuet-Higgins 1986)");
    s.section("align", &P::align, AlignParams::schema(), "two-plane alignment (paper 3.2)");
    s.section("waypoint", &P::waypoint, WaypointParams::schema(),
              "waypoint geometry (paper 3.1.3, eqs. 3-6)");
    s.section("landing", &P::landing, LandingParams::schema(), "landing target (paper 3.2)");
    s.section("ingress", &P::ingress, IngressParams::schema(), "ingress target (paper 3.3)");
    s.section("moving_top", &P::moving_top, MovingTopParams::schema(),
              "a moving platform's top, its motion between the reference and the current frame");
    return s;
  }();
  return schema;
}

const ParamSchema<NodeParams>& NodeParams::schema() {
  using P = NodeParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    // Finite and bounded: `.inf` made every frame wait for its pose forever, and an infinite
    // wait converted to microseconds is undefined behaviour.
    s.add("max_pose_wait_s", &P::max_pose_wait_s, Range::closed(0, 5), "s",
          "a frame waits for its pose until a frame exposed this much later has arrived "
          "(sensor time, vision/node/frame_pose_pairing.hpp)");
    s.add("diag_rate_hz", &P::diag_rate_hz, Range::closed(0, 100), "Hz",
          "VISION_DIAG images per second (0: none)");
    s.add("diag_jpeg_quality", &P::diag_jpeg_quality, Range::closed(1, 100), "",
          "JPEG quality of VISION_DIAG");
    // Up to LCM's own queue depth (common/node.cpp): beyond it LCM would drop silently first.
    s.add("camera_queue_frames", &P::camera_queue_frames, Range::closed(1, 2048), "frames",
          "CAMERA messages that may wait for the vision; more are dropped and counted");
    s.section("poses", &P::poses, PoseBufferParams::schema(),
              "motion-capture history, looked up at each frame's exposure time");
    s.merge(&P::pipeline, PipelineParams::schema());
    return s;
  }();
  return schema;
}

void StarParams::validate() const { schema().validate(*this); }
void SurfParams::validate() const { schema().validate(*this); }
void MatchParams::validate() const { schema().validate(*this); }
void TrackerParams::validate() const { schema().validate(*this); }
void HomographyParams::validate() const { schema().validate(*this); }
void DecompositionParams::validate() const { schema().validate(*this); }
void AlignParams::validate() const { schema().validate(*this); }
void WaypointParams::validate() const { schema().validate(*this); }
void LandingParams::validate() const { schema().validate(*this); }
void MovingTopParams::validate() const { schema().validate(*this); }
void IngressParams::validate() const { schema().validate(*this); }
void PipelineParams::validate() const { schema().validate(*this); }
void NodeParams::validate() const { schema().validate(*this); }

NodeParams load_node_params(const ParamNode& root) {
  NodeParams p;
  if (const auto n = root.optional_child("vision")) NodeParams::schema().read(*n, p);
  if (const auto a = root.optional_child("autonomy"))
    if (const auto l = a->optional_child("landing")) {
      double& gear = p.pipeline.landing.gear_footprint_m;
      l->read("gear_footprint_m", gear);
      l->check(std::isfinite(gear) && gear > 0, "gear_footprint_m", "must be finite and > 0");
    }
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

#pragma once
// Parameters of the landing / ingress targets, the per-frame pipeline and the alight-vision
// node (issue 6), read from the `vision:` section of a vehicle file. Defaults and units at each
// field; validate() throws ParamError naming the field and its value.

#include <cstdint>
#include <string>

#include "common/params.hpp"
#include "common/pose_buffer.hpp"
#include "vision/params.hpp"

namespace alight::vision {

enum class Mission : int8_t { kNone = 0, kLanding = 1, kIngress = 2 };  // = target_t MISSION_*

/// Landing target (paper 3.2): the second plane is the platform when it is nearer than the
/// floor by more than min_height_m, roughly parallel to it, and has enough inliers.
struct LandingParams {
  int min_platform_inliers = 12;     ///< fewer second-plane inliers: no platform [-]
  double min_height_m = 0.03;        ///< platform top above the floor, at least [m]
  double max_height_m = 1.0;         ///< and at most (a larger step is no landing platform) [m]
  double max_normal_angle_deg = 15;  ///< floor and platform normals agree within [deg]
  /// The platform top is level: its normal within this of world up (motion capture). A second
  /// "plane" through the platform's edge and the floor beyond is tilted by atan(h / d); in flight
  /// such false planes came out 3-12 deg, true tops within 1 deg. [deg]
  double max_tilt_deg = 3.0;
  /// Platform inliers this close to the border of either image: the platform may extend out of
  /// view, the centre of its visible features is not its centre (REASON_PARTIAL_VIEW). Matched
  /// features thin out well inside the STAR border (2 max_size + 1 px): in flight logs a 24 px
  /// band let cut platforms through (waypoints 5-17 cm off), 40 px none beyond 5 cm. [px]
  double edge_margin_px = 40.0;
  void validate() const;
};

/// Ingress target (paper 3.3): Hough lines split the image into cells; the block of cells
/// with no wall inliers and the most off-wall features is the opening.
struct IngressParams {
  /// Beyond the paper: Canny and Hough run on the off-wall mask (the reference image warped by
  /// the wall homography disagrees with the current one wherever the view passes the wall
  /// plane) instead of on the grey image, whose wall texture and the frame's inner faces give
  /// edges of their own while the opening's border can lack contrast. false: the paper's edges.
  bool parallax_mask = true;
  double parallax_blur_sigma_px = 1.5;  ///< smoothing of both images before the difference [px]
  double parallax_min_diff = 8;         ///< smallest off-wall difference [grey levels]
  double parallax_noise_k = 4;          ///< or k x the median difference at wall inliers [-]
  int parallax_close_px = 15;           ///< closing fills texture-poor holes off the wall [px]
  int parallax_open_px = 7;             ///< opening drops specks on the wall [px]
  double snap_px = 6;                   ///< cut to the wall's edge within this [px] (0: off)
  double snap_min_gradient = 8;         ///< weaker mean step along the cut: no edge [Sobel units]
  double blur_sigma_px = 2.0;           ///< Gaussian smoothing before Canny (0: none) [px]
  double canny_low = 50, canny_high = 150;  ///< Canny hysteresis thresholds [grey levels]
  int hough_threshold = 60;                 ///< accumulator votes for a segment [-]
  double hough_min_length_frac = 0.12;      ///< shortest segment, share of the image width [-]
  double hough_max_gap_px = 20;             ///< largest gap joined within a segment [px]
  double max_line_tilt_deg = 8;             ///< near-vertical / near-horizontal within [deg]
  double merge_px = 6;                      ///< cuts closer than this are one cut [px]
  double cut_margin_px = 6;                 ///< wall inliers this close to a cut do not count [px]
  int min_outliers = 8;                     ///< fewer off-wall features in the block: no opening
  double behind_margin_m = 0.02;  ///< a block feature this far behind the wall is seen through [m]
  double min_behind_share = 0.7;  ///< fewer of the block's features behind the wall: no opening
                                  ///< (0: no check)
  double min_size_m = 0.1;        ///< smaller width or height: no opening [m]
  void validate() const;
};

/// Everything the pipeline uses, one struct per stage.
struct PipelineParams {
  /// Features spread over a 4 x 3 grid: the floor keeps enough for its homography when the
  /// platform top (richer texture) fills part of the view (star_detector.hpp).
  StarParams star = [] {
    StarParams s;
    s.grid_cols = 4;
    s.grid_rows = 3;
    return s;
  }();
  SurfParams surf{};
  TrackerParams tracker{};
  MatchParams match{};  ///< reference-to-current matching
  HomographyParams homography{};
  DecompositionParams decomposition{};
  AlignParams align{};
  WaypointParams waypoint{};
  LandingParams landing{};
  IngressParams ingress{};
  /// The reference is the oldest tracked frame (3.1.1) no farther than this from the current
  /// camera: a target must be in view in both images, and a 0.6 m baseline (a search pass at
  /// 0.4 m/s) leaves a 43 cm platform wholly in neither. [m]
  double max_reference_baseline_m = 0.3;
  void validate() const;
};

/// The node's own settings on top of the pipeline.
struct NodeParams {
  PipelineParams pipeline{};
  PoseBufferParams poses{};
  double max_pose_wait_s = 0.2;  ///< a frame waits this long (wall clock) for its pose, <= 5 [s]
  double diag_rate_hz = 2.0;     ///< VISION_DIAG images per second (0: none), <= 100 [Hz]
  int diag_jpeg_quality = 75;    ///< [1..100]
  void validate() const;
};

/// Reads the `vision:` section of a vehicle file (missing keys keep their defaults; unknown
/// keys are an error).
NodeParams load_node_params(const ParamNode& vehicle_root);
NodeParams load_node_params(const std::string& vehicle_file);

Mission mission_from_string(const std::string& s);  ///< "landing" | "ingress", else ParamError

}  // namespace alight::vision

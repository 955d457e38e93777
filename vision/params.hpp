#pragma once
// Parameters of the vision: one struct per stage of the per-frame pipeline (paper 3.1-3.3), the
// landing and ingress targets, and the alight-vision node, read from the optional `vision:`
// section of a vehicle file. The defaults are the initialisers below; key, constraint, unit and
// meaning of each field are declared once in params.cpp (common/param_schema.hpp), and
// `alight-params --defaults vehicle` prints them.

#include <cstdint>
#include <string>

#include "common/param_schema.hpp"
#include "common/pose_buffer.hpp"
#include "vision/landing/moving_top_params.hpp"

namespace alight::vision {

enum class Mission : int8_t { kNone = 0, kLanding = 1, kIngress = 2 };  // = target_t MISSION_*

/// STAR / CenSurE detector (paper 3.1.1; Agrawal, Konolige & Blas, ECCV 2008).
struct StarParams {
  int min_size = 2;
  int max_size = 6;
  double response_threshold = 6.0;
  double line_threshold = 10.0;
  int nms_radius_px = 2;
  int max_features = 600;
  int grid_cols = 0, grid_rows = 0;
  bool subpixel = true;
  static const ParamSchema<StarParams>& schema();
  void validate() const;
};

/// Upright SURF descriptor (Bay, Tuytelaars & Van Gool, ECCV 2006 / CVIU 2008).
struct SurfParams {
  double scale_per_size = 0.8;
  double min_scale = 1.2;
  bool overlapping_subregions = true;
  static const ParamSchema<SurfParams>& schema();
  void validate() const;
};

/// Descriptor matching: nearest neighbour, Lowe's ratio test, mutual check.
struct MatchParams {
  double ratio = 0.8;
  bool mutual = true;
  double max_distance = 0.6;
  bool same_sign_only = true;
  static const ParamSchema<MatchParams>& schema();
  void validate() const;
};

/// Reference frame selection by continuous tracking (paper 3.1.1).
struct TrackerParams {
  int min_tracked = 40;
  int max_history = 60;
  double max_frame_gap_s = 1.0;
  double max_reference_age_s = 10.0;
  MatchParams match{};  ///< frame-to-frame matching
  double frame_threshold_px = 8.0;
  uint64_t seed = 1;
  static const ParamSchema<TrackerParams>& schema();
  void validate() const;
};

/// Robust homography (paper 3.1.2; Fischler & Bolles 1981 RANSAC, Hartley 1997 normalisation,
/// Chum, Matas & Kittler 2003 LO-RANSAC refinement).
struct HomographyParams {
  double threshold_px = 2.0;
  double confidence = 0.995;
  int max_iterations = 2000;
  int min_inliers = 12;
  int refine_iterations = 5;
  bool robust_refinement = true;
  int local_neighbours = 16;
  uint64_t seed = 1;
  static const ParamSchema<HomographyParams>& schema();
  void validate() const;
};

/// Homography decomposition (paper 3.1.2; Longuet-Higgins 1986).
struct DecompositionParams {
  double min_singular_gap = 1e-4;
  double min_front_fraction = 0.9;
  static const ParamSchema<DecompositionParams>& schema();
  void validate() const;
};

/// Two-plane alignment (paper 3.2).
struct AlignParams {
  double max_rotation_disagreement_deg = 5.0;
  double max_translation_disagreement_deg = 20.0;
  int max_iterations = 15;
  bool robust = true;
  double rotation_prior_sigma_deg = 0.0;
  double feature_sigma_px = 0.5;
  static const ParamSchema<AlignParams>& schema();
  void validate() const;
};

/// Waypoint geometry (paper 3.1.3, eqs. 3-6).
struct WaypointParams {
  double min_baseline_m = 0.03;
  double max_translation_angle_deg = 30.0;
  double max_rotation_error_deg = 5.0;
  static const ParamSchema<WaypointParams>& schema();
  void validate() const;
};

/// Landing target (paper 3.2): the second plane is the platform when it is nearer than the
/// floor by more than min_height_m, roughly parallel to it, and has enough inliers.
struct LandingParams {
  int min_platform_inliers = 12;
  double min_height_m = 0.03;
  double max_height_m = 1.0;
  double max_normal_angle_deg = 15;
  double max_tilt_deg = 3.0;
  double edge_margin_px = 40.0;
  // Beyond the paper: the known floor and the known motion (known_floor.hpp).
  double floor_z_m = 0.0;
  std::string floor_prior = "fallback";
  double floor_tol_frac = 0.08;
  int min_floor_inliers = 4;
  double max_rotation_correction_deg = 0.5;
  bool hold_reference = true;  ///< keep a longer-baseline reference while hovering (pipeline.hpp)
  // Beyond the paper: frames smeared by the camera's motion are not used (motion_blur.hpp).
  double max_motion_blur_px = 8.0;
  double assumed_exposure_s = 0.01;
  /// The vehicle's landing gear, square, this wide [m]: not a key of vision's but the vehicle
  /// file's autonomy.landing.gear_footprint_m (load_node_params), declared there once. A
  /// featureless outline narrower than the gear is no top to land on (outline.hpp); autonomy
  /// adds its fit margin to the converged estimate, so the bound here leaves room for a single
  /// frame's error on a top that does fit.
  double gear_footprint_m = 0.15;
  static const ParamSchema<LandingParams>& schema();
  void validate() const;
};

/// Ingress target (paper 3.3): Hough lines split the image into cells; the block of cells
/// with no wall inliers and the most off-wall features is the opening.
struct IngressParams {
  bool parallax_mask = true;
  int parallax_decimation = 1;
  double parallax_blur_sigma_px = 1.5;
  double parallax_min_diff = 8;
  double parallax_noise_k = 4;
  int parallax_close_px = 15;
  int parallax_open_px = 7;
  int max_border_lines = 32;
  double snap_px = 6;
  double snap_min_gradient = 8;
  double blur_sigma_px = 2.0;
  double canny_low = 50, canny_high = 150;
  int hough_threshold = 60;
  double hough_min_length_frac = 0.12;
  double hough_max_gap_px = 20;
  double max_line_tilt_deg = 8;
  double merge_px = 6;
  double cut_margin_px = 6;
  int min_outliers = 8;
  double behind_margin_m = 0.02;
  double min_behind_share = 0.7;
  double min_opening_parallax_px = 15;
  double min_size_m = 0.1;
  static const ParamSchema<IngressParams>& schema();
  void validate() const;
};

/// The detector's defaults with its features spread over a cols x rows grid, at most
/// max_features in all (star_detector.hpp).
inline StarParams star_budget(int cols, int rows, int max_features) {
  StarParams s;
  s.grid_cols = cols;
  s.grid_rows = rows;
  s.max_features = max_features;
  return s;
}

/// Everything the pipeline uses, one struct per stage.
struct PipelineParams {
  /// The landing mission's detector (the downward camera). Features spread over an 8 x 6 grid,
  /// 900 in all: the floor keeps enough for its homography when the platform top (richer texture)
  /// fills part of the view, and a top smoother than the floor keeps its share of a cell it shares
  /// with the floor (star_detector.hpp: with 4 x 3 and 600 a photographed top over a
  /// printed circuit board kept 4-11 matches). The tops it made of frames smeared at the search
  /// path's turns are refused by landing.max_motion_blur_px.
  StarParams star = star_budget(8, 6, 900);
  /// The ingress mission's detector (the forward camera): a 4 x 3 grid of 600. The wall needs
  /// no share kept for a smoother surface in front of it, and the finer budget widens the
  /// opening's width error on photographed walls.
  StarParams ingress_star = star_budget(4, 3, 600);
  SurfParams surf{};
  TrackerParams tracker{};
  MatchParams match{};  ///< reference-to-current matching
  HomographyParams homography{};
  DecompositionParams decomposition{};
  AlignParams align{};
  WaypointParams waypoint{};
  LandingParams landing{};
  IngressParams ingress{};
  MovingTopParams moving_top{};  ///< a moving platform (VISION_PLATFORM)
  double max_reference_baseline_m = 0.3;
  static const ParamSchema<PipelineParams>& schema();
  void validate() const;
};

/// The node's own settings on top of the pipeline.
struct NodeParams {
  PipelineParams pipeline{};
  PoseBufferParams poses{};
  double max_pose_wait_s = 0.2;
  double diag_rate_hz = 2.0;
  int diag_jpeg_quality = 75;
  /// CAMERA messages that may wait undecoded for the vision (Node::on's capacity): 2 s at
  /// 60 fps. More arriving while it is behind are dropped and counted (NODE_STATUS `dropped`,
  /// VISION_TIMING frames_dropped): a bound on memory (~300 kB a 640x480 frame).
  int camera_queue_frames = 120;
  static const ParamSchema<NodeParams>& schema();
  void validate() const;  ///< throws ParamError naming the full key and its value
};

/// Reads the `vision:` section of a vehicle file (absent: the defaults; missing keys keep their
/// defaults; unknown keys are an error), and the gear's footprint from its `autonomy.landing`
/// section (LandingParams::gear_footprint_m; a ParamError naming the key unless finite and > 0).
NodeParams load_node_params(const ParamNode& vehicle_root);
NodeParams load_node_params(const std::string& vehicle_file);

Mission mission_from_string(const std::string& s);  ///< "landing" | "ingress", else ParamError

}  // namespace alight::vision

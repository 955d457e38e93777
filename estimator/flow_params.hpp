#pragma once
// Parameters of the flow odometry (estimator/flow_odometry.hpp): the `flow:` section of the
// `estimator:` section of a vehicle file, keys `estimator.flow.*`. Each parameter is declared
// once, in flow_params.cpp (common/param_schema.hpp), with its unit, constraint and meaning.

#include <cstdint>

#include "common/param_schema.hpp"

namespace alight::estimator {

/// Feature detection and tracking (keys `estimator.flow.track.*`). Pixel sizes are in pixels of
/// the full-resolution image, whatever `downsample` is.
struct FlowTrackParams {
  int downsample = 1;            ///< track on the image halved this many times (pyrDown) [-]
  int max_features = 160;        ///< tracks kept at most [-]
  int min_tracks = 100;          ///< fewer tracks survive a frame: detect new ones [-]
  int grid_cols = 8;             ///< detection spread: at most max_features / cells per cell [-]
  int grid_rows = 6;             ///< rows of that grid [-]
  double min_distance_px = 20;   ///< no two features closer than this [px]
  double quality_level = 0.01;   ///< corner's min eigenvalue relative to the image's best [-]
  double min_quality = 1e-4;     ///< and absolute (OpenCV's min-eigenvalue scale) [-]
  double border_px = 12;         ///< features kept this far from the image edge [px]
  int window_px = 15;            ///< Lucas-Kanade window side at the tracking level [px]
  int pyramid_levels = 3;        ///< Lucas-Kanade pyramid levels above the tracking level [-]
  int lk_iterations = 20;        ///< Lucas-Kanade iterations per level at most [-]
  double lk_epsilon = 0.01;      ///< Lucas-Kanade stops when the update is smaller [px]
  double max_fb_error_px = 0.5;  ///< forward-backward tracking disagreement allowed [px]
  bool predict = true;           ///< start Lucas-Kanade at the motion predicted by R and t/d

  static const ParamSchema<FlowTrackParams>& schema();
  void validate() const;  ///< throws ParamError naming the key and its value
};

/// The robust fit of t/d to the correspondences (keys `estimator.flow.fit.*`).
struct FlowFitParams {
  double inlier_threshold_px = 1.0;      ///< RANSAC: reprojection error of an inlier [px]
  double ransac_confidence = 0.999;      ///< RANSAC: stop when an all-inlier sample is this sure
  int ransac_max_iterations = 200;       ///< RANSAC: minimal samples drawn at most [-]
  double min_sample_separation_px = 30;  ///< a minimal sample's two points at least this apart
  uint64_t seed = 17;                    ///< RANSAC's random generator, reseeded every fit
  double huber_k = 1.345;                ///< Huber threshold in robust standard deviations [-]
  double min_sigma_px = 0.05;            ///< floor of the residual standard deviation [px]
  int max_independent_points = 50;       ///< covariance: information of at most this many points
  int refine_iterations = 10;            ///< Levenberg-Marquardt steps per refinement at most
  int min_inliers = 12;                  ///< fewer inliers: no sample [-]
  double min_inlier_fraction = 0.25;     ///< inliers over correspondences at least [-]
  double max_condition = 1000;           ///< information matrix's eigenvalue ratio at most [-]
  double min_incidence_cos = 0.1;        ///< ray must meet the plane at cos(angle to normal) >=

  static const ParamSchema<FlowFitParams>& schema();
  void validate() const;
};

/// Keys `estimator.flow.*`.
struct FlowFrontParams {
  FlowTrackParams track;
  FlowFitParams fit;
  double max_gap_s = 0.2;  ///< frames further apart make no pair [s]

  static const ParamSchema<FlowFrontParams>& schema();
  void validate() const;  ///< throws ParamError naming the key (below `flow.`) and its value
};

}  // namespace alight::estimator

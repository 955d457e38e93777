#pragma once
// Parameters of the moving platform's top (vision/landing/moving_top.hpp), declared in
// vision/params.cpp with the pipeline's others.

#include "common/param_schema.hpp"

namespace alight::vision {

struct MovingTopParams {
  /// Measure a moving platform on every landing frame (VISION_PLATFORM); VISION_TARGET does not
  /// depend on it.
  bool enabled = true;
  /// The top's expected height above the floor [m]: the depth of a plane that moves on its own
  /// is not observable from two views whose camera stays level (its motion absorbs the
  /// baseline), so the top's points are placed at this height. The error it leaves is the
  /// height error times the tangent of the view angle in position and times the relative
  /// speed over the camera's height in velocity: both vanish as the vehicle comes over the
  /// platform and matches its speed. Autonomy measures the true height over many pairs (the
  /// plane and cameras are published with each measurement).
  double top_height_m = 0.15;
  double top_height_sigma_m = 0.05;  ///< its uncertainty, carried into the covariances [m]
  /// The earlier frame the top's motion is measured against: the newest at least this much
  /// older than the current one [s]. Long enough that the top's displacement stands above the
  /// features' noise, short enough that a turning path is still straight over it.
  double interval_s = 0.25;
  /// No earlier frame within this: nothing measured; the oldest within it measures again a top
  /// whose matches the floor carries over interval_s (one creeping through its turn:
  /// kSlowTopIntervalGain, vision/pipeline.hpp) [s]
  double max_interval_s = 0.6;
  /// A match lies on the floor when the known floor (motion capture's motion) carries it within
  /// this [px]: motion capture's orientation noise moves the image by 1-2 px.
  double floor_tol_px = 3.0;
  /// A match follows the top's motion within this [px] (converted to metres at its depth).
  double threshold_px = 2.5;
  int min_inliers = 12;
  int iterations = 300;  ///< RANSAC draws of two matches (seeded)
  uint64_t seed = 1;
  /// Physical bounds of a platform a vehicle can follow and land on; a motion or a size beyond
  /// them is refused with its own reason.
  double max_speed_mps = 2.0;
  double max_yaw_rate_dps = 45.0;
  double max_scale_change = 0.15;  ///< |s - 1| of the plane's similarity: heave / camera height
  double min_size_m = 0.08;        ///< the features' extent, short side (a top seen whole)
  /// An inlier this close to the current image's border makes the top cut [px]: not a key of
  /// its own but the still landing's vision.landing.edge_margin_px (a top with features this
  /// close to the border is cut), which the pipeline sets when it is made. Closer, a band of the
  /// top bare of features at the border (a print's margin) hides that the top goes on beyond it.
  double edge_margin_px = 40.0;
  double max_size_m = 1.0;  ///< long side
  /// The top's matches that the known floor also carries (within threshold_px): at most this
  /// share (a cluster of floor matches is no top).
  double max_floor_share = 0.25;
  static const ParamSchema<MovingTopParams>& schema();
  void validate() const;
};

}  // namespace alight::vision

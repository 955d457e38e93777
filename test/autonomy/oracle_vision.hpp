#pragma once
// ORACLE VISION: a test fixture, never part of the flight stack, the demo or any launch file.
// It turns simulator ground truth (what SIM_TRUTH carries: vehicle pose, platform / opening
// geometry) into VISION_TARGET-equivalent waypoint measurements with configurable noise and
// outliers, seeded, so that autonomy and control can be tested and Monte-Carlo'd before (and
// independently of) the real vision pipeline.
//
// Model: a measurement is produced at rate_hz when the target centre lies inside the camera's
// field of view within [min_range, max_range]; otherwise a not-found measurement. The waypoint is
// the true centre plus Gaussian noise (sigma_xy laterally, sigma_z vertically: the paper's
// experiments found the vertical component poorest, 4.2); with probability outlier_prob it is
// displaced instead by a uniformly random distance in [outlier_min, outlier_max] in a random
// direction. The reported size is the true size plus noise. `silent` makes it publish nothing
// (vision process dead), `blind` makes every measurement not-found.

#include <cstdint>
#include <optional>
#include <random>

#include "autonomy/types.hpp"
#include "common/geometry.hpp"
#include "common/pose_buffer.hpp"

namespace alight::autonomy::test {

struct OracleTruth {
  PoseSample vehicle;  ///< true pose at the exposure time
  bool has_platform = false;
  Vector3d platform_center_W = Vector3d::Zero();  ///< centre of the top face [m]
  Vector3d platform_size_m = Vector3d::Zero();    ///< length, width, height [m]
  double platform_yaw_rad = 0.0;
  bool has_opening = false;
  Vector3d opening_center_W = Vector3d::Zero();
  Vector2d opening_size_m = Vector2d::Zero();   ///< width, height [m]
  Vector3d wall_normal_W = -Vector3d::UnitX();  ///< towards the approach side
};

struct OracleVisionParams {
  Mission mission = Mission::kLanding;
  double rate_hz = 5.0;  ///< the paper: ~5 fps on STARMAC, ~2 fps on the Pelican
  double sigma_xy_m = 0.01;
  double sigma_z_m = 0.03;
  double size_sigma_m = 0.01;
  double outlier_prob = 0.05;
  double outlier_min_m = 0.15;
  double outlier_max_m = 0.6;
  Matrix3d R_BC = R_BC_downward();
  Vector3d t_B_C = Vector3d(0.05, 0.0, -0.06);
  double half_fov_x_rad = 0.447;  ///< 640 px at f = 666.7 px
  double half_fov_y_rad = 0.346;  ///< 480 px
  double min_range_m = 0.35;      ///< closer than this the target fills the image
  double max_range_m = 4.0;
  uint64_t seed = 1;
};

class OracleVision {
 public:
  explicit OracleVision(const OracleVisionParams& params);

  /// A measurement if one is due at utime (one per 1/rate_hz), else nothing.
  std::optional<TargetMeasurement> update(const OracleTruth& truth, int64_t utime);
  /// Whether the target centre is in view from this pose.
  bool in_view(const OracleTruth& truth) const;

  bool silent = false;  ///< no measurements at all
  bool blind = false;   ///< measurements, all not-found
  int n_outliers() const { return n_outliers_; }
  int n_found() const { return n_found_; }

 private:
  OracleVisionParams params_;
  std::mt19937_64 rng_;
  std::optional<int64_t> next_utime_;
  int n_outliers_ = 0, n_found_ = 0;
};

}  // namespace alight::autonomy::test

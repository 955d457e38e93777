#pragma once
// Parameters of the onboard estimator: the `estimator:` section of a vehicle file.
// Defaults: a BMI088-class MEMS IMU (datasheet noise densities), a TFmini-class rangefinder
// (1 cm + 1 % of the range, 0.1 to 12 m), a BMP388-class barometer (its noise with prop wash, and a
// slowly drifting offset). Each parameter is declared once, in params.cpp.

#include <array>
#include <string>

#include "common/geometry.hpp"
#include "common/param_schema.hpp"
#include "estimator/flow_params.hpp"

namespace alight::estimator {

/// IMU noise model (Sola 2017, 5.4.3: continuous densities, integrated over each interval).
struct ImuNoiseParams {
  double accel_noise_density = 2.0e-3;  ///< white accel noise [m/s^2/sqrt(Hz)] (BMI088 ~190 ug)
  double gyro_noise_density = 2.5e-4;   ///< white gyro noise [rad/s/sqrt(Hz)] (0.014 deg/s/rtHz)
  double accel_bias_rw = 3.0e-4;        ///< accel bias random walk [m/s^3/sqrt(Hz)]
  double gyro_bias_rw = 2.0e-5;         ///< gyro bias random walk [rad/s^2/sqrt(Hz)]
  double max_accel_mps2 = 160.0;        ///< |accel| above: absurd (BMI088 range 24 g = 235) [m/s^2]
  double max_gyro_radps = 35.0;         ///< |gyro| above: absurd (2000 deg/s) [rad/s]

  static const ParamSchema<ImuNoiseParams>& schema();
};

/// Static alignment on the floor and the initial uncertainty.
struct InitParams {
  double duration_s = 1.0;              ///< still this long before the state starts [s]
  double accel_tol_mps2 = 0.5;          ///< each sample's | |accel| - g | below [m/s^2]
  double gyro_tol_radps = 0.05;         ///< each sample's |gyro| below [rad/s]
  Vector3d p_W_B_m = Vector3d::Zero();  ///< body origin at take-off, in world [m]
  double yaw_deg = 0.0;                 ///< heading at take-off (not observable without a compass)
  double sigma_p_m = 0.01;
  double sigma_v_mps = 0.02;
  double sigma_roll_pitch_rad = 0.005;  ///< besides the accel bias's share (correlated with it)
  double sigma_yaw_rad = 0.02;
  double sigma_accel_bias_mps2 = 0.1;  ///< BMI088 offset: +-20 mg at most
  /// After averaging 1 s at rest the error is ~n_g / sqrt(1 s) = 2.5e-4; the rest leaves room for
  /// temperature. Larger values let the (unobservable) heading wander: see README, limitations.
  double sigma_gyro_bias_radps = 0.001;
  double sigma_terrain_m = 0.01;  ///< the floor at take-off is terrain height 0

  static const ParamSchema<InitParams>& schema();
};

/// Rangefinder: where it is, how it sees, and the platform-step logic.
struct RangeParams {
  Vector3d t_B_R_m{0.0, 0.0, -0.05};  ///< rangefinder origin in body [m]
  Vector3d d_B{0.0, 0.0, -1.0};       ///< beam direction in body (normalised when used)
  double min_range_m = 0.1;           ///< readings below are refused (blind zone) [m]
  double max_range_m = 12.0;          ///< readings above are refused [m]
  double sigma_m = 0.01;              ///< noise: sigma_m + sigma_rel * range [m]
  double sigma_rel = 0.01;            ///< [-]
  double max_tilt_deg = 30.0;         ///< beam further from vertical: refused [deg]
  double gate_chi2 = 25.0;            ///< chi-square gate (1 dof; 25 = 5 sigma)
  double terrain_rw = 0.002;          ///< terrain random walk [m/sqrt(s)] (indoors: a flat floor)
  double terrain_gradient = 0.005;    ///< terrain change per metre flown, as noise [-]
  /// Readings implying a terrain this far from the estimate are not fused (while the predicted
  /// range is known better than half of it): a step (a platform's edge) or an outlier [m].
  double step_min_m = 0.05;
  double reset_window_s = 0.15;      ///< out of gate this long (consistently): platform step [s]
  int reset_min_samples = 4;         ///< ... and at least this many samples
  double reset_min_fraction = 0.75;  ///< ... making this share of the window's readings [-]
  double reset_spread_m = 0.08;      ///< ... whose implied terrain heights agree this well
                                     ///< (older half's mean against newer half's) [m]
  double reset_sigma_m = 0.03;       ///< added to the reset terrain's sigma [m]
  double reset_max_sigma_z_m = 0.3;  ///< vehicle height sigma must be below to reset [m]

  static const ParamSchema<RangeParams>& schema();
};

/// Barometer: ISA altitude, white noise, and an offset state that drifts.
struct BaroParams {
  double sigma_m = 0.1;        ///< altitude noise incl. prop wash [m]
  double offset_rw = 0.02;     ///< offset random walk [m/sqrt(s)] (BMP388: ~6 cm per kelvin)
  double gate_chi2 = 25.0;     ///< chi-square gate (1 dof)
  double reset_after_s = 2.0;  ///< refused this long on end: the offset starts over [s]

  static const ParamSchema<BaroParams>& schema();
};

/// Flow front end's measurements and the camera that makes them.
struct FlowParams {
  FlowFrontParams front;  ///< the front end (flow_odometry.hpp): tracking and the fit
  /// The next three are not keys of `estimator.flow`: load_estimator_params takes them from the
  /// vehicle's cameras.downward (common/camera_mount.hpp), the one camera vision also uses.
  std::string mount = "downward";                 ///< R_BC: downward | forward (geometry.hpp)
  std::array<double, 3> rpy_offset_deg{0, 0, 0};  ///< calibrated rotation after the mount [deg]
  Vector3d t_B_C_m{0.0, 0.0, -0.06};              ///< camera centre in body [m]
  int min_inliers = 12;                           ///< fewer homography inliers: refused
  double max_span_s = 0.2;                        ///< utime_to - utime_from above: refused [s]
  double min_height_m = 0.05;  ///< camera height above terrain below: refused [m]
  double max_t_over_d = 5.0;   ///< |t/d| above: absurd [-]
  double cov_scale = 1.0;      ///< the front end's covariance times this [-]
  /// Plus this sigma on each axis, as a velocity: sigma_floor_mps * dt / d of t/d over a sample
  /// of dt seconds taken d metres over the plane [m/s]. The front end's own covariance is its
  /// image noise alone, about a third of its error on the simulator's floor (1.7 mm/s at 1.5 m);
  /// 4.5 mm/s is the error on its worst floor (tiles, p90 6.6 mm/s). A velocity and not a fixed
  /// t/d: what the covariance leaves out (the floor's relief, the lens model, the exposure's
  /// timing) is nearly as large a velocity near the floor as at 1.5 m, a t/d five times as large
  /// at 0.3 m; a fixed t/d made the filter five times too sure of the take-off's first samples,
  /// and one drift of a few cm/s there then failed every later sample's gate.
  double sigma_floor_mps = 0.0045;
  double gate_chi2 = 16.27;  ///< chi-square gate (3 dof; 16.27 = 99.9 %)

  Matrix3d R_BC() const;  ///< camera axes in body
  static const ParamSchema<FlowParams>& schema();
};

/// When the estimate is DEGRADED (hold) or LOST (failsafe descent).
struct HealthParams {
  double flow_timeout_s = 0.5;      ///< no flow fused this long: DEGRADED [s]
  double range_timeout_s = 1.0;     ///< no range fused this long (above min_range_m): DEGRADED [s]
  double baro_timeout_s = 2.0;      ///< no baro fused this long: DEGRADED [s]
  double imu_gap_s = 0.05;          ///< an IMU interval longer than this is a gap [s]
  double imu_gap_recovery_s = 1.0;  ///< DEGRADED this long after a gap [s]
  double imu_lost_s = 0.2;          ///< other sensors this far ahead of the IMU: LOST [s]
  double pos_sigma_degraded_m = 1.0;  ///< horizontal position sigma (largest axis) [m]
  double pos_sigma_lost_m = 3.0;
  double vel_sigma_degraded_mps = 0.3;  ///< velocity sigma (largest axis) [m/s]
  double vel_sigma_lost_mps = 1.0;
  double height_sigma_degraded_m = 0.3;  ///< vertical position sigma [m]
  double height_sigma_lost_m = 1.0;

  static const ParamSchema<HealthParams>& schema();
};

struct EstimatorParams {
  double gravity_mps2 = 9.80665;
  double history_s = 0.5;    ///< delayed measurements older than this are refused [s]
  double max_ahead_s = 1.0;  ///< measurements further ahead of the IMU are refused [s]
  int max_queued = 256;      ///< measurements waiting for the IMU, at most

  ImuNoiseParams imu;
  InitParams init;
  RangeParams range;
  BaroParams baro;
  FlowParams flow;
  HealthParams health;

  static const ParamSchema<EstimatorParams>& schema();
  void validate() const;  ///< throws ParamError naming the dotted key and its value
};

/// Reads the optional `estimator:` section of a vehicle file (absent: the defaults).
EstimatorParams load_estimator_params(const ParamNode& vehicle_root);

}  // namespace alight::estimator

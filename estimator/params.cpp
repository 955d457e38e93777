#include "estimator/params.hpp"

#include <cmath>

#include "common/camera_mount.hpp"

namespace alight::estimator {

const ParamSchema<ImuNoiseParams>& ImuNoiseParams::schema() {
  using P = ImuNoiseParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("accel_noise_density", &P::accel_noise_density, Range::open_closed(0, 1),
          "m/s^2/sqrt(Hz)",
          "accelerometer white noise (BMI088: 190 ug/sqrt(Hz); raise it for a "
          "vibrating airframe)");
    s.add("gyro_noise_density", &P::gyro_noise_density, Range::open_closed(0, 0.1),
          "rad/s/sqrt(Hz)", "gyro white noise (BMI088: 0.014 deg/s/sqrt(Hz))");
    s.add("accel_bias_rw", &P::accel_bias_rw, Range::open_closed(0, 0.1), "m/s^3/sqrt(Hz)",
          "accelerometer bias random walk");
    s.add("gyro_bias_rw", &P::gyro_bias_rw, Range::open_closed(0, 0.01), "rad/s^2/sqrt(Hz)",
          "gyro bias random walk");
    s.add("max_accel_mps2", &P::max_accel_mps2, Range::open(10, 1000), "m/s^2",
          "a larger specific force is absurd: the sample is dropped and counted");
    s.add("max_gyro_radps", &P::max_gyro_radps, Range::open(1, 200), "rad/s",
          "a larger angular rate is absurd: the sample is dropped and counted");
    return s;
  }();
  return schema;
}

const ParamSchema<InitParams>& InitParams::schema() {
  using P = InitParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("duration_s", &P::duration_s, Range::closed(0.1, 10), "s",
          "static alignment: the vehicle rests on the floor this long before the state starts");
    s.add("accel_tol_mps2", &P::accel_tol_mps2, Range::open_closed(0, 5), "m/s^2",
          "still: each sample's |accel| within this of g (otherwise alignment starts over)");
    s.add("gyro_tol_radps", &P::gyro_tol_radps, Range::open_closed(0, 1), "rad/s",
          "still: each sample's |gyro| below this");
    s.add("p_W_B_m", &P::p_W_B_m, Range::closed(-1e4, 1e4), "m",
          "body origin at take-off in world (resting on the floor, terrain height 0)");
    s.add("yaw_deg", &P::yaw_deg, Range::closed(-180, 180), "deg",
          "heading at take-off (no compass: it is not observable, only kept)");
    s.add("sigma_p_m", &P::sigma_p_m, Range::open_closed(0, 10), "m", "initial position sigma");
    s.add("sigma_v_mps", &P::sigma_v_mps, Range::open_closed(0, 10), "m/s",
          "initial velocity sigma");
    s.add(
        "sigma_roll_pitch_rad", &P::sigma_roll_pitch_rad, Range::open_closed(0, 0.5), "rad",
        "initial roll / pitch sigma besides the accelerometer bias's share (sigma_accel_bias / g, "
        "correlated with the bias): mounting, vibration");
    s.add("sigma_yaw_rad", &P::sigma_yaw_rad, Range::open_closed(0, 3.2), "rad",
          "initial yaw sigma");
    s.add("sigma_accel_bias_mps2", &P::sigma_accel_bias_mps2, Range::open_closed(0, 5), "m/s^2",
          "initial accelerometer bias sigma");
    s.add("sigma_gyro_bias_radps", &P::sigma_gyro_bias_radps, Range::open_closed(0, 0.5), "rad/s",
          "gyro bias sigma after averaging the gyro at rest");
    s.add("sigma_terrain_m", &P::sigma_terrain_m, Range::open_closed(0, 10), "m",
          "initial terrain sigma (the take-off floor is height 0)");
    return s;
  }();
  return schema;
}

const ParamSchema<RangeParams>& RangeParams::schema() {
  using P = RangeParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("t_B_R_m", &P::t_B_R_m, Range::closed(-2, 2), "m", "rangefinder origin in body");
    s.add("d_B", &P::d_B, Range::closed(-1, 1), "",
          "beam direction in body (normalised; -z: straight down)")
        .check([](const P& p) { return p.d_B.norm() > 0.5; }, "must have a norm near 1");
    s.add("min_range_m", &P::min_range_m, Range::closed_open(0, 10), "m",
          "shorter readings are refused (the sensor's blind zone)");
    s.add("max_range_m", &P::max_range_m, Range::open_closed(0, 200), "m",
          "longer readings are refused")
        .check([](const P& p) { return p.max_range_m > p.min_range_m; }, "must exceed min_range_m");
    s.add("sigma_m", &P::sigma_m, Range::open_closed(0, 5), "m",
          "noise sigma: sigma_m + sigma_rel * range");
    s.add("sigma_rel", &P::sigma_rel, Range::closed(0, 1), "", "noise proportional to the range");
    s.add("max_tilt_deg", &P::max_tilt_deg, Range::open(0, 80), "deg",
          "beam further than this from vertical: refused");
    s.add("gate_chi2", &P::gate_chi2, Range::gt(0), "",
          "chi-square gate on the normalised innovation (1 dof: 25 = 5 sigma)");
    s.add("terrain_rw", &P::terrain_rw, Range::open_closed(0, 10), "m/sqrt(s)",
          "terrain height random walk");
    s.add("terrain_gradient", &P::terrain_gradient, Range::closed(0, 10), "",
          "terrain change per metre flown horizontally, as process noise (an idea of PX4's ECL)");
    s.add("step_min_m", &P::step_min_m, Range::closed(0, 5), "m",
          "readings implying a terrain this far from the estimate are refused, as a step or an "
          "outlier, while the predicted range's sigma is below half of it (0: the chi-square "
          "gate only)");
    s.add("reset_window_s", &P::reset_window_s, Range::open_closed(0, 5), "s",
          "platform step: readings out of gate, consistently, for this long reset the terrain");
    s.add("reset_min_samples", &P::reset_min_samples, Range::closed(1, 32), "",
          "... and at least this many readings");
    s.add("reset_min_fraction", &P::reset_min_fraction, Range::open_closed(0, 1), "",
          "... making at least this share of the readings in the window (the rest fused: an "
          "edge the beam goes back and forth over is no step)");
    s.add("reset_spread_m", &P::reset_spread_m, Range::gt(0), "m",
          "... whose implied terrain heights agree this well: the mean of the older half and "
          "the mean of the newer half");
    s.add("reset_sigma_m", &P::reset_sigma_m, Range::ge(0), "m",
          "added (in quadrature) to the reset terrain's sigma");
    s.add("reset_max_sigma_z_m", &P::reset_max_sigma_z_m, Range::gt(0), "m",
          "the terrain is reset only while the vehicle height sigma is below this (baro and "
          "IMU keep it): otherwise the readings stay refused");
    return s;
  }();
  return schema;
}

const ParamSchema<BaroParams>& BaroParams::schema() {
  using P = BaroParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("sigma_m", &P::sigma_m, Range::open_closed(0, 10), "m",
          "altitude noise (sensor and prop wash)");
    s.add("offset_rw", &P::offset_rw, Range::open_closed(0, 10), "m/sqrt(s)",
          "random walk of the baro offset (weather, temperature)");
    s.add("gate_chi2", &P::gate_chi2, Range::gt(0), "", "chi-square gate (1 dof: 25 = 5 sigma)");
    s.add("reset_after_s", &P::reset_after_s, Range::open_closed(0, 600), "s",
          "refused by the gate this long on end: the offset starts over from the reading (the "
          "height from range and IMU wins)");
    return s;
  }();
  return schema;
}

Matrix3d FlowParams::R_BC() const {
  constexpr double kDeg = M_PI / 180.0;
  return (mount == "forward" ? R_BC_forward() : R_BC_downward()) *
         rotation_from_rpy(rpy_offset_deg[0] * kDeg, rpy_offset_deg[1] * kDeg,
                           rpy_offset_deg[2] * kDeg);
}

const ParamSchema<FlowParams>& FlowParams::schema() {
  using P = FlowParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.section("front", &P::front, FlowFrontParams::schema(),
              "the front end: feature tracking and the robust fit of t/d");
    s.add("min_inliers", &P::min_inliers, Range::closed(0, 100000), "",
          "fewer homography inliers: refused");
    s.add("max_span_s", &P::max_span_s, Range::open_closed(0, 2), "s",
          "frames further apart are refused");
    s.add("min_height_m", &P::min_height_m, Range::open(0, 10), "m",
          "camera closer to the terrain than this (at the first frame): refused");
    s.add("max_t_over_d", &P::max_t_over_d, Range::open_closed(0, 100), "",
          "a larger translation over height is absurd");
    s.add("cov_scale", &P::cov_scale, Range::open_closed(0, 1000), "",
          "the front end's covariance is scaled by this");
    s.add("sigma_floor_mps", &P::sigma_floor_mps, Range::closed(0, 1), "m/s",
          "sigma added on each axis of t_over_d as a velocity (sigma * dt / height): what the "
          "front end's covariance leaves out");
    s.add("gate_chi2", &P::gate_chi2, Range::gt(0), "", "chi-square gate (3 dof: 16.27 = 99.9 %)");
    return s;
  }();
  return schema;
}

const ParamSchema<HealthParams>& HealthParams::schema() {
  using P = HealthParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("flow_timeout_s", &P::flow_timeout_s, Range::open_closed(0, 60), "s",
          "no flow fused this long: DEGRADED");
    s.add("range_timeout_s", &P::range_timeout_s, Range::open_closed(0, 60), "s",
          "no range fused this long while above the rangefinder's min range: DEGRADED");
    s.add("baro_timeout_s", &P::baro_timeout_s, Range::closed(0, 600), "s",
          "no baro fused this long: DEGRADED (0: no barometer expected)");
    s.add("imu_gap_s", &P::imu_gap_s, Range::open_closed(0, 1), "s",
          "an IMU interval longer than this is a gap (counted)");
    s.add("imu_gap_recovery_s", &P::imu_gap_recovery_s, Range::closed(0, 60), "s",
          "DEGRADED for this long after an IMU gap");
    s.add("imu_lost_s", &P::imu_lost_s, Range::open_closed(0, 10), "s",
          "other sensors' stamps this far ahead of the newest IMU sample: LOST");
    s.add("pos_sigma_degraded_m", &P::pos_sigma_degraded_m, Range::gt(0), "m",
          "horizontal position sigma (largest axis) above: DEGRADED");
    s.add("pos_sigma_lost_m", &P::pos_sigma_lost_m, Range::gt(0), "m",
          "horizontal position sigma above: LOST")
        .check([](const P& p) { return p.pos_sigma_lost_m > p.pos_sigma_degraded_m; },
               "must exceed pos_sigma_degraded_m");
    s.add("vel_sigma_degraded_mps", &P::vel_sigma_degraded_mps, Range::gt(0), "m/s",
          "velocity sigma (largest axis) above: DEGRADED");
    s.add("vel_sigma_lost_mps", &P::vel_sigma_lost_mps, Range::gt(0), "m/s",
          "velocity sigma above: LOST")
        .check([](const P& p) { return p.vel_sigma_lost_mps > p.vel_sigma_degraded_mps; },
               "must exceed vel_sigma_degraded_mps");
    s.add("height_sigma_degraded_m", &P::height_sigma_degraded_m, Range::gt(0), "m",
          "vertical position sigma above: DEGRADED");
    s.add("height_sigma_lost_m", &P::height_sigma_lost_m, Range::gt(0), "m",
          "vertical position sigma above: LOST")
        .check([](const P& p) { return p.height_sigma_lost_m > p.height_sigma_degraded_m; },
               "must exceed height_sigma_degraded_m");
    return s;
  }();
  return schema;
}

const ParamSchema<EstimatorParams>& EstimatorParams::schema() {
  using P = EstimatorParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("gravity_mps2", &P::gravity_mps2, Range::open(9, 10.5), "m/s^2", "local gravity");
    s.add("history_s", &P::history_s, Range::closed(0.02, 5), "s",
          "IMU samples and states kept for delayed measurements; older ones are refused");
    s.add("max_ahead_s", &P::max_ahead_s, Range::open_closed(0, 10), "s",
          "measurements stamped further ahead of the newest IMU sample are refused");
    s.check(
        "health.imu_lost_s", [](const P& p) { return p.health.imu_lost_s < p.max_ahead_s; },
        "must be below max_ahead_s (samples further ahead are refused, so they cannot tell)");
    s.add("max_queued", &P::max_queued, Range::closed(1, 100000), "",
          "measurements waiting for the IMU to reach their time, at most");
    s.section("imu", &P::imu, ImuNoiseParams::schema(), "IMU noise model");
    s.section("init", &P::init, InitParams::schema(), "static alignment and initial sigmas");
    s.section("range", &P::range, RangeParams::schema(), "downward rangefinder");
    s.section("baro", &P::baro, BaroParams::schema(), "barometer");
    s.section("flow", &P::flow, FlowParams::schema(), "flow front end and its camera");
    s.section("health", &P::health, HealthParams::schema(), "OK / DEGRADED / LOST thresholds");
    return s;
  }();
  return schema;
}

void EstimatorParams::validate() const { schema().validate(*this); }

EstimatorParams load_estimator_params(const ParamNode& vehicle_root) {
  EstimatorParams p;
  if (const auto section = vehicle_root.optional_child("estimator"))
    EstimatorParams::schema().read(*section, p);
  // The flow camera is the vehicle's downward camera, declared once under cameras.downward
  // (common/camera_mount.hpp), as vision and the simulator read it.
  if (const auto cameras = vehicle_root.optional_child("cameras")) {
    if (cameras->optional_child("downward")) {
      const CameraMountParams m = load_camera_mount_params(vehicle_root, "downward");
      p.flow.mount = m.mount;
      p.flow.rpy_offset_deg = m.rpy_offset_deg;
      p.flow.t_B_C_m = m.t_B_C_m;
    }
  }
  return p;
}

}  // namespace alight::estimator

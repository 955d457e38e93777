#pragma once
// Synthetic flights for the estimator's tests and benchmarks: a known trajectory (position and
// yaw as functions of time; attitude from the thrust direction, as a quadrotor flies), and the
// IMU, rangefinder, barometer and flow samples it produces, with seeded noise, biases, a
// drifting baro offset, an optional elevated platform and each sensor's delivery delay.

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "estimator/estimator.hpp"

namespace alight::estimator::test {

struct Trajectory {
  std::function<Vector3d(double)> position;  ///< p_W_B(t) [m]
  std::function<double(double)> yaw;         ///< heading(t) [rad]
};

/// At rest on the floor (body origin at rest_z_m) until rest_s, a smooth climb to height_m over
/// climb_s, then hover.
Trajectory hover(double rest_z_m, double height_m, double rest_s = 1.5, double climb_s = 3.0);
/// As hover, then from flight_start_s a figure (Lissajous, 1.5 m amplitude) with a slow yaw
/// oscillation: accelerations and rotations on every axis.
Trajectory figure(double rest_z_m, double height_m, double flight_start_s);
/// As hover, then from flight_start_s a side x side m square at speed_mps (1 s smooth ramps, a
/// pause at each corner), back to the start.
Trajectory square(double rest_z_m, double height_m, double flight_start_s, double side_m,
                  double speed_mps);
/// Duration of square()'s path after flight_start_s.
double square_duration_s(double side_m, double speed_mps);

struct Platform {
  double x0, x1, y0, y1, height_m;
};

struct SensorConfig {
  double imu_rate_hz = 200.0;
  double range_rate_hz = 50.0;
  double baro_rate_hz = 25.0;
  double flow_rate_hz = 30.0;
  double range_delay_s = 0.02;
  double baro_delay_s = 0.03;
  double flow_delay_s = 0.05;
  bool noise = true;  ///< false: perfect sensors, no biases
  bool range = true, baro = true, flow = true;
  double flow_sigma = 0.003;  ///< front end's sigma of t_over_d on each axis [-]
  /// An error of the flow the front end's covariance does not hold (the floor's relief, the lens
  /// model, the exposures' timing), as a velocity of the camera over the floor, world axes: each
  /// sample's displacement is off by it times the sample's interval [m/s].
  Eigen::Vector3d flow_velocity_error_W_mps = Eigen::Vector3d::Zero();
  double baro_offset0_m = 40.0;
  std::optional<Platform> platform;
  /// The flow's plane is the floor even over the platform (a platform small in the camera's
  /// view), not the surface under the camera.
  bool flow_sees_floor = false;
  double start_s = 0.0;  ///< first IMU time (utime 1e9 us + this)
};

enum class Kind { kImu, kRange, kBaro, kFlow };

struct Input {
  int64_t arrival_utime = 0;
  Kind kind = Kind::kImu;
  ImuSample imu;
  RangeSample range;
  BaroSample baro;
  FlowSample flow;
};

struct Truth {
  int64_t utime = 0;
  Vector3d p_W_B, v_W_B;
  Quaterniond q_WB;
};

struct Flight {
  std::vector<Input> inputs;           ///< in arrival order (IMU first on ties)
  std::vector<Truth> truth;            ///< at each IMU sample
  Vector3d accel_bias_B, gyro_bias_B;  ///< the initial true biases
};

constexpr int64_t kStartUtime = 1'000'000'000;

/// The sensor samples of `traj` over [0, duration_s]; noise levels as `params` model them.
Flight simulate(const Trajectory& traj, double duration_s, const SensorConfig& cfg,
                const EstimatorParams& params, uint64_t seed);

/// Gives one input to the estimator.
Outcome feed(Estimator& est, const Input& in);

/// Attitude error in the estimator's convention: q_true = q_est (x) Exp(e), body axes [rad].
Vector3d attitude_error(const Quaterniond& q_est, const Quaterniond& q_true);

}  // namespace alight::estimator::test

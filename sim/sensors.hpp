#pragma once
// Sensor emulation: a VICON-like motion-capture system (sub-millimetre noise, fixed latency,
// dropouts), a strapdown IMU (white noise, a bias drawn per run that then random-walks), a
// single-beam rangefinder cast into the scene, and a barometer in the ICAO standard atmosphere.
// The IMU reports the specific force averaged over each sample interval, as an IMU's decimation
// filter does, so the short contact spike of a touch-down shows in the 200 Hz samples (paper
// 3.4.1: touch-down is detected from the accelerometer). sim/README.md ("Sensors") relates the
// defaults to data sheets.

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "common/pose_buffer.hpp"
#include "sim/params.hpp"
#include "sim/scene.hpp"

namespace alight::sim {

struct MocapSample {
  int64_t seq = 0;
  PoseSample pose;  ///< pose.utime: when it was sampled (published latency_s later)
};

struct ImuSample {
  int64_t utime = 0;
  int64_t seq = 0;
  Vector3d accel_B = Vector3d::Zero();  ///< specific force [m/s^2]
  Vector3d gyro_B = Vector3d::Zero();   ///< [rad/s]
};

/// Whether a rangefinder sample is a measurement; the values are range_t's STATUS_*.
enum class RangeStatus : int8_t { kOk = 0, kOutOfRange = 1, kTooNear = 2, kNoEcho = 3 };

struct RangeSample {
  int64_t utime = 0;
  int64_t seq = 0;
  RangeStatus status = RangeStatus::kOutOfRange;
  double distance_m = 0.0;  ///< along beam_B; in [min_range_m, max_range_m] when kOk, else 0
  double min_range_m = 0.0;
  double max_range_m = 0.0;
  Vector3d t_B_R = Vector3d::Zero();     ///< sensor origin in body [m]
  Vector3d beam_B = -Vector3d::UnitZ();  ///< unit beam direction in body
};

struct BaroSample {
  int64_t utime = 0;
  int64_t seq = 0;
  double pressure_pa = 0.0;    ///< static pressure with the sensor's errors
  double temperature_c = 0.0;  ///< the air's (ISA) temperature at the sensor
};

// The ICAO standard atmosphere's troposphere (ICAO Doc 7488/3, ISO 2533:1975), with the day's
// sea-level pressure and temperature: T = T0 - L h, p = p0 (T / T0)^(g0 / (R L)) with L = 0.0065
// K/m, g0 = 9.80665 m/s^2, R = 287.05287 J/(kg K). Valid up to 11 km (the parameters keep it
// there).
/// Static pressure at `altitude_m` above mean sea level [Pa] (101325 at 0 m, 89874.6 at 1000 m).
double isa_pressure_pa(double altitude_m, double sea_level_pressure_pa = 101325.0,
                       double sea_level_temperature_c = 15.0);
/// The inverse: altitude above mean sea level at which the pressure is `pressure_pa` [m].
double isa_altitude_m(double pressure_pa, double sea_level_pressure_pa = 101325.0,
                      double sea_level_temperature_c = 15.0);
/// Air temperature at `altitude_m` [deg C].
double isa_temperature_c(double altitude_m, double sea_level_temperature_c = 15.0);

class MocapEmulator {
 public:
  MocapEmulator(const MocapParams& params, int64_t start_utime, uint64_t seed);
  /// Called every physics step with the true state at `now`; takes a sample when one is due.
  void update(int64_t now_utime, const PoseSample& truth);
  /// Samples whose latency has elapsed by `now`, oldest first, removed from the queue.
  std::vector<MocapSample> take(int64_t now_utime);
  /// No samples are taken in [from, to).
  void add_dropout(int64_t from_utime, int64_t to_utime);
  int64_t period_us() const { return period_us_; }

 private:
  bool dropped(int64_t utime);
  MocapParams params_;
  int64_t period_us_;
  int64_t next_utime_;
  int64_t seq_ = 0;
  std::mt19937_64 rng_;
  std::vector<std::pair<int64_t, int64_t>> dropouts_;
  std::deque<MocapSample> queue_;
};

class ImuEmulator {
 public:
  ImuEmulator(const ImuParams& params, int64_t start_utime, uint64_t seed);
  /// Called every physics step with the specific force and rate of that step (duration dt_us).
  void update(int64_t now_utime, int64_t dt_us, const Vector3d& specific_force_B,
              const Vector3d& omega_B);
  std::vector<ImuSample> take();
  /// The biases now (they random-walk from sample to sample).
  const Vector3d& accel_bias() const { return accel_bias_; }
  const Vector3d& gyro_bias() const { return gyro_bias_; }

 private:
  ImuParams params_;
  int64_t period_us_;
  int64_t next_utime_;
  int64_t seq_ = 0;
  std::mt19937_64 rng_;
  std::mt19937_64 walk_rng_;  // its own stream: the walk leaves the white noise as it was
  Vector3d accel_bias_, gyro_bias_;
  Vector3d accel_sum_ = Vector3d::Zero(), gyro_sum_ = Vector3d::Zero();
  double sum_s_ = 0.0;
  std::vector<ImuSample> out_;
};

/// A single-beam rangefinder fixed to the body: per sample, one ray from t_B_R along the beam
/// cast into the scene (floor, platform top and sides, walls), the first surface's distance
/// plus Gaussian noise of sigma_m + sigma_frac * distance. A reading (noise included) outside
/// [min_range_m, max_range_m] is reported as such, never as a number; lost returns come in runs
/// (Gilbert's two-state channel, Bell Syst. Tech. J. 39, 1960): a run of mean length L =
/// max(1, dropout_burst_s * rate_hz) samples starts after a good sample with probability
/// dropout_prob / (L (1 - dropout_prob)), so that the long-run fraction lost is dropout_prob.
/// Not modelled: the beam's width (a few degrees: it averages over an edge), the surface's
/// reflectivity and incidence, multiple returns.
class RangefinderEmulator {
 public:
  RangefinderEmulator(const RangefinderParams& params, int64_t start_utime, uint64_t seed);
  /// Called every physics step with the true body pose at `now`; takes a sample when one is due.
  void update(int64_t now_utime, const Isometry3d& X_WB, const Scene& scene);
  /// Samples whose latency has elapsed by `now`, oldest first, removed from the queue.
  std::vector<RangeSample> take(int64_t now_utime);
  int64_t period_us() const { return period_us_; }

 private:
  RangefinderParams params_;
  Vector3d beam_B_;
  int64_t period_us_;
  int64_t next_utime_;
  int64_t seq_ = 0;
  bool losing_ = false;  // in a run of lost returns
  std::mt19937_64 rng_;
  std::deque<RangeSample> queue_;
};

/// A barometer at the body origin: the ISA pressure at ground_altitude_m + z, plus a constant
/// offset drawn per run (offset_sigma_pa), a drift and white noise (sigma_pa). The drift is a
/// first-order Gauss-Markov process started at 0, b' = -b / tau + w, advanced exactly per sample:
/// b <- a b + q sqrt(tau / 2) sqrt(1 - a^2) n with a = exp(-dt / tau), q = drift_pa_per_sqrt_s:
/// a random walk of q sqrt(t) for t << tau, bounded by q sqrt(tau / 2) for ever (the slow
/// changes of a hall's pressure and of the sensor's temperature offset).
class BaroEmulator {
 public:
  BaroEmulator(const BaroParams& params, int64_t start_utime, uint64_t seed);
  /// Called every physics step with the true body position at `now`.
  void update(int64_t now_utime, const Vector3d& p_W_B);
  /// Samples whose latency has elapsed by `now`, oldest first, removed from the queue.
  std::vector<BaroSample> take(int64_t now_utime);
  double offset_pa() const { return offset_pa_; }
  double drift_pa() const { return drift_pa_; }

 private:
  BaroParams params_;
  int64_t period_us_;
  int64_t next_utime_;
  int64_t seq_ = 0;
  std::mt19937_64 rng_;
  double offset_pa_ = 0.0, drift_pa_ = 0.0;
  double drift_decay_ = 1.0, drift_step_pa_ = 0.0;  // per sample
  std::deque<BaroSample> queue_;
};

}  // namespace alight::sim

#pragma once
// Sensor emulation: a VICON-like motion-capture system (sub-millimetre noise, fixed latency,
// dropouts) and a strapdown IMU (white noise plus a constant per-run bias). The IMU reports the
// specific force averaged over each sample interval, as an IMU's decimation filter does, so the
// short contact spike of a touch-down shows in the 200 Hz samples (paper 3.4.1: touch-down is
// detected from the accelerometer).

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "common/pose_buffer.hpp"
#include "sim/params.hpp"

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
  const Vector3d& accel_bias() const { return accel_bias_; }
  const Vector3d& gyro_bias() const { return gyro_bias_; }

 private:
  ImuParams params_;
  int64_t period_us_;
  int64_t next_utime_;
  int64_t seq_ = 0;
  std::mt19937_64 rng_;
  Vector3d accel_bias_, gyro_bias_;
  Vector3d accel_sum_ = Vector3d::Zero(), gyro_sum_ = Vector3d::Zero();
  double sum_s_ = 0.0;
  std::vector<ImuSample> out_;
};

}  // namespace alight::sim

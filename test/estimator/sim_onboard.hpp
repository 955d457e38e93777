#pragma once
// The estimator node's work in process (issue 17): the simulator's IMU, rangefinder, barometer
// and downward camera into an estimator::Onboard built as alight-estimator builds it (the
// vehicle file's `estimator:` section, its downward camera), and out the messages the node
// publishes on every fused IMU sample once aligned: STATE_ESTIMATE and ESTIMATE_POSE. The
// samples go through the same message conversions as on LCM (sim_msgs.hpp, estimator/
// convert.hpp), the frames' pixels as they are. Deterministic: no clock, except the optional CPU
// accounting of the benches (thread CPU time around each call, never read by the estimate).
//
// Used by the in-process closed loop flying on the estimate (test/autonomy/closed_loop.hpp) and
// by bench/estimator/estimator_sim_drift.

#include <alight/pose_t.hpp>
#include <alight/state_estimate_t.hpp>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/pose_buffer.hpp"
#include "estimator/onboard.hpp"
#include "sim/simulator.hpp"

namespace alight::estimator::test {

/// What the node publishes for one fused IMU sample.
struct Published {
  state_estimate_t estimate;  ///< STATE_ESTIMATE
  pose_t pose_msg;            ///< ESTIMATE_POSE
  PoseSample pose;            ///< ESTIMATE_POSE as its readers take it (pose_from_msg)
};

/// CPU time spent in the estimator, per kind of input (thread CPU time, the clock's own cost
/// taken off).
struct OnboardCost {
  int64_t imu_ns = 0, range_ns = 0, baro_ns = 0, frame_ns = 0;
  int64_t n_imu = 0, n_range = 0, n_baro = 0, n_frames = 0;
  int64_t max_imu_ns = 0, max_frame_ns = 0;
  std::vector<int32_t> frame_us;  ///< each frame's [us]
};

class SimOnboard {
 public:
  /// Throws ParamError on a bad vehicle file. `measure_cpu`: keep an OnboardCost.
  explicit SimOnboard(const std::string& vehicle_file, bool measure_cpu = false);

  /// The node's IMU handler: nullopt when nothing is published (not fused, not aligned yet, or
  /// a pose its readers would refuse).
  std::optional<Published> add_imu(const sim::ImuSample& s);
  void add_range(const sim::RangeSample& s);
  void add_baro(const sim::BaroSample& s);
  void add_frame(const sim::CameraFrame& f);

  const Onboard& onboard() const { return *onboard_; }
  State state() const { return onboard_->state(); }
  const OnboardCost& cost() const { return cost_; }

 private:
  int64_t cpu_ns() const;

  std::unique_ptr<Onboard> onboard_;
  bool measure_cpu_;
  int64_t clock_overhead_ns_ = 0;
  OnboardCost cost_;
  int64_t seq_ = 0;
};

}  // namespace alight::estimator::test

#pragma once
// Onboard visual-inertial estimation with metric scale (the paper's future work, 5: fly
// without motion capture). An error-state EKF (Sola 2017; see eskf.hpp) propagated with the IMU
// at its rate and updated by a downward rangefinder, a barometer and the flow front end's
// translation-over-height between consecutive frames (stochastic cloning of the pose at the first
// frame). Pure: the time is the inputs' utime, nothing is read from a clock, a file or the network.
//
// Delayed measurements: every input is kept for params.history_s with a checkpoint of the filter
// after each IMU sample. A measurement is fused at its own stamp, inside the IMU interval that
// contains it, and everything after it is propagated and fused again from the checkpoint before
// it. Inside an interval the events run in a fixed order (time, then range, baro, flow updates,
// then flow clones, then arrival), so the output is a pure function of the inputs: the same
// measurement given late or on time gives the same bits, and a replay of the same inputs too.
//
// Every input is untrusted: non-finite or absurd values, stamps out of order, too old or too far
// ahead are counted per sensor and reason (State::counters) and dropped; nothing throws.

#include <cstddef>
#include <optional>
#include <vector>

#include "estimator/eskf.hpp"
#include "estimator/params.hpp"
#include "estimator/types.hpp"

namespace alight::estimator {

namespace detail {
/// A ring buffer that keeps its storage: the history's checkpoints (about 3 KB each) are
/// overwritten in place, so an IMU sample allocates nothing once the history has filled.
template <class T>
class Ring {
 public:
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T& operator[](size_t i) { return buf_[(head_ + i) % buf_.size()]; }
  const T& operator[](size_t i) const { return buf_[(head_ + i) % buf_.size()]; }
  T& front() { return (*this)[0]; }
  const T& front() const { return (*this)[0]; }
  T& back() { return (*this)[size_ - 1]; }
  const T& back() const { return (*this)[size_ - 1]; }
  void clear() { head_ = size_ = 0; }
  void pop_front() { head_ = (head_ + 1) % buf_.size(), --size_; }
  void truncate(size_t n) { size_ = n < size_ ? n : size_; }
  /// Appends a copy of `v` (which must not live in this ring).
  void push_back(const T& v) { slot() = v; }
  /// Appends a copy of the last element and returns it.
  T& push_copy_of_back() {
    const size_t last = size_ - 1;
    T& out = slot();
    out = (*this)[last];
    return out;
  }

 private:
  T& slot() {
    if (size_ == buf_.size()) {
      std::vector<T> grown(buf_.empty() ? 64 : 2 * buf_.size());
      for (size_t i = 0; i < size_; ++i) grown[i] = std::move((*this)[i]);
      buf_.swap(grown);
      head_ = 0;
    }
    return (*this)[size_++];
  }
  std::vector<T> buf_;
  size_t head_ = 0, size_ = 0;
};
}  // namespace detail

class Estimator {
 public:
  /// Throws ParamError for invalid parameters (the only exception it raises).
  explicit Estimator(const EstimatorParams& params);

  /// Propagates to the sample's time (or, before initialisation, accumulates the static
  /// alignment). kFused, or the reason it was dropped.
  Outcome add_imu(const ImuSample& imu);
  /// kFused or a reason when the IMU already reached the stamp; kQueued when it has not yet (the
  /// final outcome is counted when it is fused).
  Outcome add_range(const RangeSample& range);
  Outcome add_baro(const BaroSample& baro);
  /// Fused at utime_to against a clone of the pose at utime_from.
  Outcome add_flow(const FlowSample& flow);

  /// The estimate at the newest IMU sample, with health and counters.
  State state() const;
  /// The attitude q_WB at a time within the history (for the flow front end's R_C2C1 and n_C1);
  /// nullopt outside it.
  std::optional<Quaterniond> attitude_at(int64_t utime) const;
  bool initialised() const { return !history_.empty(); }
  const EstimatorParams& params() const { return params_; }

 private:
  /// One measurement event in the history: an update, or a flow sample's clone at utime_from.
  struct Event {
    int64_t utime = 0;
    int order = 0;  ///< among equal utimes: range, baro, flow updates, then clones
    int64_t seq = 0;
    Sensor sensor = Sensor::kRange;
    bool clone = false;
    RangeSample range;
    BaroSample baro;
    FlowSample flow;
    Outcome outcome = Outcome::kQueued;
  };
  struct Checkpoint {
    FilterState s;  ///< after everything up to and including s.utime
    ImuSample imu;  ///< the sample whose interval ends at s.utime
  };
  struct Alignment {
    int64_t start_utime = 0, last_utime = 0;
    int n = 0;
    Vector3d accel_sum = Vector3d::Zero(), gyro_sum = Vector3d::Zero();
  };

  Outcome reject(Sensor sensor, Outcome why);
  Outcome add_event(Event update, int64_t earliest_utime);
  void align(const ImuSample& imu);
  void start(const ImuSample& last, const Vector3d& accel_mean, const Vector3d& gyro_mean);
  /// Propagates s through one IMU interval, applying the events inside it in order.
  void run_interval(FilterState& s, const ImuSample& imu);
  /// Restores the checkpoint before `utime` and runs every later interval again.
  void replay_from(int64_t utime);
  void apply(Event& e, FilterState& s);
  Outcome apply_range(const RangeSample& m, FilterState& s);
  Outcome apply_baro(const BaroSample& m, FilterState& s);
  Outcome apply_flow(const FlowSample& m, int64_t key, FilterState& s);
  /// Whether the top's velocity state is known to be other than zero (Estimator::apply_flow).
  bool top_is_moving(const FilterState& s) const;
  /// The horizontal velocity error a flow sample's innovation r (t/d in the first exposure's
  /// camera, noise R, the camera height_m over its plane) implies, in W, with its covariance.
  struct VelocityError {
    int64_t utime = 0;
    Vector2d dv = Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  };
  VelocityError implied_velocity_error(const FilterState& s, const FlowSample& m, const MeasVec& r,
                                       const MeasCov& R, double height_m, int ci) const;
  /// Stage after a flow sample the gate refused (even inflated): the horizontal velocity set to
  /// the flow's (README, "The velocity set to the flow's").
  void reset_velocity_to_flow(FilterState& s, const FlowSample& m, const VelocityError& e) const;
  /// The platform-step condition on the streak; the terrain its readings agree on.
  bool terrain_reset_due(const FilterState& s, double* terrain_m) const;
  void prune();
  void reset_to_alignment();
  /// The terrain under the rangefinder is a top: range.step_min_m or more from the take-off floor.
  bool terrain_raised(const FilterState& s) const;
  bool vertical_ok(const FilterState& s) const;
  int64_t newest_imu_utime() const { return history_.back().s.utime; }

  EstimatorParams params_;
  Vector3d range_d_B_;  ///< unit beam direction
  Matrix3d R_BC_;
  detail::Ring<Checkpoint> history_;  ///< oldest first; empty until initialised
  std::vector<Event> events_;         ///< sorted by (utime, order, seq)
  Alignment alignment_;
  int64_t last_imu_utime_ = 0;      ///< newest accepted IMU stamp (also during alignment)
  int64_t newest_other_utime_ = 0;  ///< newest stamp of any other sensor's plausible sample
  int64_t seq_ = 0;
  Counters counters_;
  std::vector<ImuSample> replay_imu_;  ///< scratch for replay_from
};

}  // namespace alight::estimator

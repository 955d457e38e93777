#include "estimator/estimator.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/geometry.hpp"

namespace alight::estimator {

namespace {
constexpr double kUsPerS = 1e6;
// A barometer reading outside this is not an altitude anyone flies at (about -600 m to 9 km).
constexpr double kMinPressurePa = 30000.0;
constexpr double kMaxPressurePa = 110000.0;
// The median of the chi-square distribution with 3 degrees of freedom: a flow sample's typical
// normalised innovation.
constexpr double kChi2Median3Dof = 2.366;
// The chi-square distribution with 2 degrees of freedom at p = 0.001: two horizontal velocity
// errors that differ by more than their noise allows this seldom are not one error.
constexpr double kChi2P001Dof2 = 13.82;

int64_t to_us(double s) { return static_cast<int64_t>(std::llround(s * kUsPerS)); }

bool event_before(const auto& a, const auto& b) {
  if (a.utime != b.utime) return a.utime < b.utime;
  if (a.order != b.order) return a.order < b.order;
  return a.seq < b.seq;
}

/// The sample's noise with the camera `height_m` (> 0) over the plane it saw: the front end's
/// covariance plus sigma_floor_mps as t/d over the sample's interval (FlowParams::sigma_floor_mps).
MeasCov flow_noise(const FlowSample& m, const FlowParams& p, double height_m) {
  assert(height_m > 0);
  MeasCov R = 0.5 * p.cov_scale * (m.cov + m.cov.transpose());
  const double floor = p.sigma_floor_mps * (m.utime_to - m.utime_from) / kUsPerS / height_m;
  R.diagonal().array() += floor * floor;
  return R;
}

/// The sample with another motion of its (FlowSample::others) in place of its own.
FlowSample with_motion(const FlowSample& m, const FlowMotion& other) {
  FlowSample out = m;
  out.t_over_d_C1 = other.t_over_d_C1;
  out.cov = other.cov;
  out.inliers = other.inliers;
  out.J_rotation = other.J_rotation;
  out.J_normal = other.J_normal;
  out.others.clear();
  return out;
}

/// Whether a sample's own motion passes the checks of add_flow: finite, a plausible size, a
/// covariance that is one, min_inliers behind it; the refusal's outcome otherwise.
std::optional<Outcome> refusal(const FlowSample& m, const FlowParams& p) {
  if (!m.t_over_d_C1.allFinite() || !m.cov.allFinite() || !m.J_rotation.allFinite() ||
      !m.J_normal.allFinite())
    return Outcome::kNonFinite;
  if (m.utime_from <= 0 || m.utime_to <= m.utime_from || m.t_over_d_C1.norm() > p.max_t_over_d)
    return Outcome::kAbsurd;
  // A covariance must be symmetric and, with the floor added (at any height: whether it is
  // one does not depend on it), positive definite.
  const double scale = std::max(1e-12, m.cov.cwiseAbs().maxCoeff());
  if ((m.cov - m.cov.transpose()).cwiseAbs().maxCoeff() > 1e-6 * scale ||
      (m.cov.diagonal().array() < 0).any() ||
      Eigen::LLT<Matrix3d>(Matrix3d(flow_noise(m, p, 1.0))).info() != Eigen::Success)
    return Outcome::kAbsurd;
  if (m.utime_to - m.utime_from > to_us(p.max_span_s)) return Outcome::kGeometry;
  if (m.inliers < p.min_inliers) return Outcome::kTooFewInliers;
  return std::nullopt;
}
}  // namespace

Estimator::Estimator(const EstimatorParams& params) : params_(params) {
  params_.validate();
  range_d_B_ = params_.range.d_B.normalized();
  R_BC_ = params_.flow.R_BC();
}

Outcome Estimator::reject(Sensor sensor, Outcome why) {
  ++counters_.by_outcome[static_cast<int>(sensor)][static_cast<int>(why)];
  return why;
}

// ---- IMU and static alignment

Outcome Estimator::add_imu(const ImuSample& imu) {
  if (!imu.accel_B.allFinite() || !imu.gyro_B.allFinite())
    return reject(Sensor::kImu, Outcome::kNonFinite);
  if (imu.utime <= 0 || imu.accel_B.norm() > params_.imu.max_accel_mps2 ||
      imu.gyro_B.norm() > params_.imu.max_gyro_radps)
    return reject(Sensor::kImu, Outcome::kAbsurd);
  if (last_imu_utime_ != 0 && imu.utime <= last_imu_utime_)
    return reject(Sensor::kImu, Outcome::kOutOfOrder);
  const int64_t dt_us = last_imu_utime_ != 0 ? imu.utime - last_imu_utime_ : 0;
  last_imu_utime_ = imu.utime;
  ++counters_.by_outcome[static_cast<int>(Sensor::kImu)][static_cast<int>(Outcome::kFused)];
  if (dt_us > to_us(params_.health.imu_gap_s)) ++counters_.imu_gaps;

  if (initialised() && dt_us > to_us(params_.max_ahead_s)) {
    // Too long to bridge by holding one sample: the attitude and velocity are unknown. Start
    // over with a static alignment (which waits for the vehicle to be still).
    reset_to_alignment();
  }
  if (!initialised()) {
    align(imu);
    return Outcome::kFused;
  }
  Checkpoint& next = history_.push_copy_of_back();
  next.imu = imu;
  run_interval(next.s, imu);
  prune();
  return Outcome::kFused;
}

void Estimator::align(const ImuSample& imu) {
  const auto& p = params_.init;
  const bool still = std::abs(imu.accel_B.norm() - params_.gravity_mps2) <= p.accel_tol_mps2 &&
                     imu.gyro_B.norm() <= p.gyro_tol_radps;
  const bool gap =
      alignment_.n > 0 && imu.utime - alignment_.last_utime > to_us(params_.health.imu_gap_s);
  if (!still || gap) alignment_ = Alignment{};
  if (!still) return;
  if (alignment_.n == 0) alignment_.start_utime = imu.utime;
  alignment_.accel_sum += imu.accel_B;
  alignment_.gyro_sum += imu.gyro_B;
  ++alignment_.n;
  alignment_.last_utime = imu.utime;
  if (alignment_.last_utime - alignment_.start_utime >= to_us(p.duration_s))
    start(imu, alignment_.accel_sum / alignment_.n, alignment_.gyro_sum / alignment_.n);
}

void Estimator::start(const ImuSample& last, const Vector3d& accel_mean,
                      const Vector3d& gyro_mean) {
  const auto& p = params_.init;
  // At rest the specific force is R_WB^T (0, 0, g): roll and pitch from its direction, yaw and
  // position from the parameters (the take-off point). Earth rate (7e-5 rad/s) is below the
  // gyro's noise over the alignment and is left in the bias.
  const double roll = std::atan2(accel_mean.y(), accel_mean.z());
  const double pitch = std::atan2(-accel_mean.x(), std::hypot(accel_mean.y(), accel_mean.z()));
  const Matrix3d R_WB = rotation_from_rpy(roll, pitch, p.yaw_deg * M_PI / 180.0);

  FilterState s;
  s.utime = last.utime;
  s.x.p_W_B = p.p_W_B_m;
  s.x.q_WB = Quaterniond(R_WB).normalized();
  s.x.gyro_bias_B = gyro_mean;
  s.x.terrain_m = 0.0;
  s.P = Cov::Zero(idx::kCore, idx::kCore);
  s.P.block<3, 3>(idx::kP, idx::kP).diagonal().setConstant(p.sigma_p_m * p.sigma_p_m);
  s.P.block<3, 3>(idx::kV, idx::kV).diagonal().setConstant(p.sigma_v_mps * p.sigma_v_mps);
  // Roll / pitch and yaw sigmas are about world axes; the error state is in body axes.
  const Vector3d att_var_W(p.sigma_roll_pitch_rad * p.sigma_roll_pitch_rad,
                           p.sigma_roll_pitch_rad * p.sigma_roll_pitch_rad,
                           p.sigma_yaw_rad * p.sigma_yaw_rad);
  const Matrix3d P_ba = Matrix3d::Identity() * p.sigma_accel_bias_mps2 * p.sigma_accel_bias_mps2;
  // The levelled attitude absorbs the horizontal accelerometer bias: f = R^T g_W + b gives
  // [g_B]x dtheta = -b_perp, so dtheta = A db with A = [g_B]x / g^2 (g_B = R^T (0, 0, g)). The
  // tilt error and the bias error are one error, and P says so.
  const Vector3d g_B = R_WB.transpose() * Vector3d(0.0, 0.0, params_.gravity_mps2);
  const Matrix3d A = skew(g_B) / (params_.gravity_mps2 * params_.gravity_mps2);
  s.P.block<3, 3>(idx::kTheta, idx::kTheta) =
      R_WB.transpose() * att_var_W.asDiagonal() * R_WB + A * P_ba * A.transpose();
  s.P.block<3, 3>(idx::kTheta, idx::kBa) = A * P_ba;
  s.P.block<3, 3>(idx::kBa, idx::kTheta) = (A * P_ba).transpose();
  s.P.block<3, 3>(idx::kBa, idx::kBa) = P_ba;
  s.P.block<3, 3>(idx::kBg, idx::kBg)
      .diagonal()
      .setConstant(p.sigma_gyro_bias_radps * p.sigma_gyro_bias_radps);
  s.P(idx::kBaro, idx::kBaro) = 1.0;  // replaced by the first baro reading
  s.P(idx::kTerrain, idx::kTerrain) = p.sigma_terrain_m * p.sigma_terrain_m;
  s.P.block<2, 2>(idx::kTopV, idx::kTopV).diagonal().setConstant(kTopMaxSpeedMps * kTopMaxSpeedMps);
  s.last_fused_utime.fill(s.utime);
  s.last_outcome.fill(Outcome::kFused);
  history_.push_back(Checkpoint{s, last});
  alignment_ = Alignment{};
}

void Estimator::reset_to_alignment() {
  // Measurements still waiting never get fused: counted as refused for want of a state.
  for (const Event& e : events_)
    if (!e.clone && e.outcome == Outcome::kQueued) reject(e.sensor, Outcome::kNotInitialised);
  history_.clear();
  events_.clear();
  alignment_ = Alignment{};
}

// ---- Measurements

Outcome Estimator::add_range(const RangeSample& m) {
  if (!std::isfinite(m.range_m)) return reject(Sensor::kRange, Outcome::kNonFinite);
  if (m.utime <= 0) return reject(Sensor::kRange, Outcome::kAbsurd);
  if (!m.valid) return reject(Sensor::kRange, Outcome::kInvalid);
  if (m.range_m < params_.range.min_range_m || m.range_m > params_.range.max_range_m)
    return reject(Sensor::kRange, Outcome::kOutOfRange);
  Event e;
  e.utime = m.utime;
  e.order = 0;
  e.sensor = Sensor::kRange;
  e.range = m;
  return add_event(std::move(e), m.utime);
}

Outcome Estimator::add_baro(const BaroSample& m) {
  if (!std::isfinite(m.pressure_pa)) return reject(Sensor::kBaro, Outcome::kNonFinite);
  if (m.utime <= 0 || m.pressure_pa < kMinPressurePa || m.pressure_pa > kMaxPressurePa)
    return reject(Sensor::kBaro, Outcome::kAbsurd);
  Event e;
  e.utime = m.utime;
  e.order = 1;
  e.sensor = Sensor::kBaro;
  e.baro = m;
  return add_event(std::move(e), m.utime);
}

Outcome Estimator::add_flow(const FlowSample& m) {
  if (const auto why = refusal(m, params_.flow)) return reject(Sensor::kFlow, *why);
  Event e;
  e.utime = m.utime_to;
  e.order = 2;
  e.sensor = Sensor::kFlow;
  e.flow = m;
  // Another motion is checked as the sample's own; one that fails is left out, the sample stays.
  e.flow.others.clear();
  for (const FlowMotion& other : m.others)
    if (!refusal(with_motion(m, other), params_.flow)) e.flow.others.push_back(other);
  return add_event(std::move(e), m.utime_from);
}

Outcome Estimator::add_event(Event update, int64_t earliest_utime) {
  const Sensor sensor = update.sensor;
  if (!initialised()) return reject(sensor, Outcome::kNotInitialised);
  if (earliest_utime <= history_.front().s.utime) return reject(sensor, Outcome::kTooOld);
  const int64_t newest = newest_imu_utime();
  if (update.utime > newest + to_us(params_.max_ahead_s)) return reject(sensor, Outcome::kTooNew);
  // Sensors running ahead of the IMU (within max_ahead_s, so that one absurd stamp cannot make
  // the estimate lost for good) tell that the IMU has stopped.
  newest_other_utime_ = std::max(newest_other_utime_, update.utime);
  const auto waiting = std::count_if(events_.begin(), events_.end(), [newest](const Event& e) {
    return !e.clone && e.utime > newest;
  });
  if (waiting >= params_.max_queued) return reject(sensor, Outcome::kQueueFull);

  // The same stamp twice from one sensor is a repeated message: fusing it would count its
  // information twice.
  const auto same =
      std::equal_range(events_.begin(), events_.end(), update, [](const Event& a, const Event& b) {
        return a.utime != b.utime ? a.utime < b.utime : a.order < b.order;
      });
  if (same.first != same.second) return reject(sensor, Outcome::kDuplicate);

  update.seq = ++seq_;
  update.outcome = Outcome::kQueued;
  const Event key = update;
  auto insert = [this](Event e) {
    events_.insert(
        std::upper_bound(events_.begin(), events_.end(), e,
                         [](const Event& a, const Event& b) { return event_before(a, b); }),
        std::move(e));
  };
  if (sensor == Sensor::kFlow) {
    // The clone of the pose at the first exposure, made when the replay passes utime_from.
    Event clone = update;
    clone.utime = update.flow.utime_from;
    clone.order = 3;
    clone.clone = true;
    insert(std::move(clone));
  }
  insert(std::move(update));
  if (earliest_utime <= newest) replay_from(earliest_utime);
  const auto it =
      std::lower_bound(events_.begin(), events_.end(), key,
                       [](const Event& a, const Event& b) { return event_before(a, b); });
  assert(it != events_.end() && it->seq == key.seq && !it->clone);
  return it->outcome;
}

// ---- History: intervals, replay, pruning

void Estimator::run_interval(FilterState& s, const ImuSample& imu) {
  if (imu.utime - s.utime > to_us(params_.health.imu_gap_s)) s.last_imu_gap_utime = imu.utime;
  const auto first = std::upper_bound(events_.begin(), events_.end(), s.utime,
                                      [](int64_t t, const Event& e) { return t < e.utime; });
  for (auto it = first; it != events_.end() && it->utime <= imu.utime; ++it) {
    if (it->utime > s.utime) {
      propagate(s, imu.accel_B, imu.gyro_B, (it->utime - s.utime) / kUsPerS, params_);
      s.utime = it->utime;
    }
    apply(*it, s);
  }
  if (imu.utime > s.utime) {
    propagate(s, imu.accel_B, imu.gyro_B, (imu.utime - s.utime) / kUsPerS, params_);
    s.utime = imu.utime;
  }
}

void Estimator::replay_from(int64_t utime) {
  size_t k = history_.size() - 1;
  while (k > 0 && history_[k].s.utime >= utime) --k;
  assert(history_[k].s.utime < utime);
  if (k + 1 == history_.size()) return;
  replay_imu_.clear();
  for (size_t j = k + 1; j < history_.size(); ++j) replay_imu_.push_back(history_[j].imu);
  history_.truncate(k + 1);
  for (const ImuSample& imu : replay_imu_) {
    Checkpoint& next = history_.push_copy_of_back();
    next.imu = imu;
    run_interval(next.s, imu);
  }
  ++counters_.replays;
}

void Estimator::prune() {
  const int64_t horizon = newest_imu_utime() - to_us(params_.history_s);
  while (history_.size() > 1 && history_[1].s.utime <= horizon) history_.pop_front();
  // Events at or before the oldest checkpoint are in it for good; their outcomes are final.
  const int64_t oldest = history_.front().s.utime;
  const auto end = std::upper_bound(events_.begin(), events_.end(), oldest,
                                    [](int64_t t, const Event& e) { return t < e.utime; });
  events_.erase(events_.begin(), end);
}

void Estimator::apply(Event& e, FilterState& s) {
  if (e.clone) {
    add_clone(s, e.seq);  // when full, the flow update finds no clone (kNoClone)
    return;
  }
  Outcome o = Outcome::kFused;
  switch (e.sensor) {
    case Sensor::kRange:
      o = apply_range(e.range, s);
      break;
    case Sensor::kBaro:
      o = apply_baro(e.baro, s);
      break;
    case Sensor::kFlow:
      o = apply_flow(e.flow, e.seq, s);
      break;
    default:
      assert(false);
  }
  // A replay fuses an event again: it is counted once, with its latest outcome.
  auto& counts = counters_.by_outcome[static_cast<int>(e.sensor)];
  if (e.outcome != Outcome::kQueued) --counts[static_cast<int>(e.outcome)];
  ++counts[static_cast<int>(o)];
  e.outcome = o;
  s.last_outcome[static_cast<int>(e.sensor)] = o;
  if (o == Outcome::kFused) s.last_fused_utime[static_cast<int>(e.sensor)] = e.utime;
}

// ---- Updates

Outcome Estimator::apply_range(const RangeSample& m, FilterState& s) {
  const auto& p = params_.range;
  const RangeModel model = range_model(s.x, p.t_B_R_m, range_d_B_);
  if (model.cos_tilt < std::cos(p.max_tilt_deg * M_PI / 180.0)) return Outcome::kBeamAngle;
  const double sigma = p.sigma_m + p.sigma_rel * m.range_m;
  MeasVec r(1);
  r[0] = m.range_m - model.range_m;
  MeasJac H = MeasJac::Zero(1, s.dim());
  H.leftCols<idx::kCore>() = model.H;
  MeasCov R(1, 1);
  R(0, 0) = sigma * sigma;
  // The step gate: a platform's top (10-50 cm) is within the chi-square gate of a noisy reading
  // at flight height (1 cm + 1 %, 5 sigma), and fused it would pull the vehicle's height down
  // instead of moving the terrain. So while the predicted range is known to better than
  // step_min_m / 2, a reading implying a terrain step_min_m off is not fused: it witnesses a
  // step. Noise alone puts a reading there rarely (2 sigma at 1.5 m), on both sides alike.
  const double predicted_sigma_m = std::sqrt(
      (model.H * s.P.topLeftCorner<idx::kCore, idx::kCore>() * model.H.transpose())(0, 0));
  const bool step = p.step_min_m > 0 && predicted_sigma_m < 0.5 * p.step_min_m &&
                    std::abs(r[0]) * model.cos_tilt > p.step_min_m;
  const Outcome o = step ? Outcome::kGate : fuse(s, r, H, R, p.gate_chi2);
  if (o != Outcome::kFused && o != Outcome::kGate) return o;
  s.range_streak.add(m.utime, implied_terrain_m(s.x, p.t_B_R_m, range_d_B_, m.range_m),
                     o == Outcome::kGate);
  if (o != Outcome::kGate) return o;

  // Platform step: the readings jump and stay consistent with a new surface while the vehicle's
  // height (IMU, baro) has not moved. The terrain, not the vehicle, is reset to what they imply.
  double terrain_m = 0.0;
  if (!terrain_reset_due(s, &terrain_m) || !vertical_ok(s)) return Outcome::kGate;
  ++s.terrain_resets;
  s.range_streak.clear();
  if (std::abs(terrain_m) < p.step_min_m) {
    // Back over the floor, which defines height 0: the terrain is the floor again, as known as
    // at take-off, and the next readings take the vehicle's height back from it (after a while
    // over a platform, anchored by nothing better than the barometer, it has drifted).
    s.P.row(idx::kTerrain).setZero();
    s.P.col(idx::kTerrain).setZero();
    s.P(idx::kTerrain, idx::kTerrain) = params_.init.sigma_terrain_m * params_.init.sigma_terrain_m;
    s.x.terrain_m = 0.0;
    return Outcome::kFused;
  }
  CoreRow J;
  implied_terrain_m(s.x, p.t_B_R_m, range_d_B_, m.range_m, &J);
  // The new terrain is a function of p_z and the attitude (J has no terrain column): its
  // correlations follow from J, its variance gets the reading's noise and an inflation.
  Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxDim> row =
      J * s.P.topRows(idx::kCore);
  const double meas_sigma = sigma / std::max(model.cos_tilt, 1e-3);
  row[idx::kTerrain] = (J * s.P.topLeftCorner<idx::kCore, idx::kCore>() * J.transpose())(0, 0) +
                       meas_sigma * meas_sigma + p.reset_sigma_m * p.reset_sigma_m;
  s.P.row(idx::kTerrain) = row;
  s.P.col(idx::kTerrain) = row.transpose();
  s.x.terrain_m = terrain_m;
  return Outcome::kFused;
}

bool Estimator::terrain_reset_due(const FilterState& s, double* terrain_m) const {
  // Over the last reset_window_s of readings: enough refused ones, most of the readings, for at
  // least half the window, on one surface: the older and the newer half of the refused readings
  // agree on average (averages, so that the noise of single readings, 2.6 cm at 1.6 m, does not
  // count; a surface that changed, or a wild reading, does). The new terrain is their median.
  const RangeStreak& st = s.range_streak;
  if (st.count == 0) return false;
  const auto& p = params_.range;
  const int newest_slot = (st.head + RangeStreak::kCapacity - 1) % RangeStreak::kCapacity;
  const int64_t newest = st.utime[newest_slot];
  const int64_t window = to_us(p.reset_window_s);
  std::array<double, RangeStreak::kCapacity> h{};  // refused readings' terrain, newest first
  int n = 0, n_refused = 0;
  int64_t first_refused = newest;
  for (int i = 0; i < st.count; ++i) {
    const int slot = (newest_slot - i + RangeStreak::kCapacity) % RangeStreak::kCapacity;
    if (newest - st.utime[slot] > window) break;
    ++n;
    if (!st.refused[slot]) continue;
    h[n_refused++] = st.implied_terrain_m[slot];
    first_refused = st.utime[slot];
  }
  if (n_refused < p.reset_min_samples || n_refused < p.reset_min_fraction * n ||
      newest - first_refused < window / 2)
    return false;
  const int half = n_refused / 2;
  double newer = 0, older = 0;
  for (int i = 0; i < half; ++i) newer += h[i] / half;
  for (int i = n_refused - half; i < n_refused; ++i) older += h[i] / half;
  if (std::abs(newer - older) > p.reset_spread_m) return false;
  std::nth_element(h.begin(), h.begin() + half, h.begin() + n_refused);
  *terrain_m = h[half];
  return true;
}

bool Estimator::terrain_raised(const FilterState& s) const {
  const double step_m = params_.range.step_min_m;
  return step_m > 0 && std::abs(s.x.terrain_m) >= step_m;
}

bool Estimator::vertical_ok(const FilterState& s) const {
  // The vehicle's own height must be trustworthy: small sigma, and the barometer (when there is
  // one) agreeing. The flow is no witness: its scale uses the terrain that is in question.
  return std::sqrt(s.P(idx::kP + 2, idx::kP + 2)) <= params_.range.reset_max_sigma_z_m &&
         s.last_outcome[static_cast<int>(Sensor::kBaro)] != Outcome::kGate;
}

Outcome Estimator::apply_baro(const BaroSample& m, FilterState& s) {
  const auto& p = params_.baro;
  const double altitude_m = isa_altitude_m(m.pressure_pa);
  // A barometer refused for reset_after_s on end (a bad first reading, a door opened, weather)
  // disagrees with the height that range and IMU keep: its offset starts over, as at first.
  const bool stale =
      s.baro_gated_since_utime != 0 && m.utime - s.baro_gated_since_utime >= to_us(p.reset_after_s);
  if (!s.baro_initialised || stale) {
    // The offset starts as the reading minus the height: b = alt - p_z, so its correlations are
    // those of -p_z and its variance that of p_z plus the reading's.
    if (stale) ++s.baro_resets;
    s.baro_gated_since_utime = 0;
    s.x.baro_offset_m = altitude_m - s.x.p_W_B.z();
    Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxDim> row =
        -s.P.row(idx::kP + 2);
    row[idx::kBaro] = s.P(idx::kP + 2, idx::kP + 2) + p.sigma_m * p.sigma_m;
    s.P.row(idx::kBaro) = row;
    s.P.col(idx::kBaro) = row.transpose();
    s.baro_initialised = true;
    return Outcome::kFused;
  }
  MeasVec r(1);
  r[0] = altitude_m - (s.x.p_W_B.z() + s.x.baro_offset_m);
  MeasJac H = MeasJac::Zero(1, s.dim());
  H(0, idx::kP + 2) = 1.0;
  H(0, idx::kBaro) = 1.0;
  MeasCov R(1, 1);
  R(0, 0) = p.sigma_m * p.sigma_m;
  const Outcome o = fuse(s, r, H, R, p.gate_chi2);
  if (o == Outcome::kGate && s.baro_gated_since_utime == 0) s.baro_gated_since_utime = m.utime;
  if (o == Outcome::kFused) s.baro_gated_since_utime = 0;
  return o;
}

// Flow spans two times. Stochastic cloning (preferred over the velocity approximation
// t ~ R_CB R_WB^T v dt): the model above is exact in p and q at both exposures, the lever arm of
// the camera under rotation (t_B_C x omega) and any acceleration inside the interval are
// accounted for, and the cross-covariance between the pose at utime_from and the state now is the
// filter's own, so the update is consistent. The velocity form would treat the mean velocity over
// the interval as the velocity at one end (an error of a dt / 2, 3 % of the displacement at
// 2 m/s^2 and 30 Hz, as large as the flow noise) and drop that correlation. The cost is a 6-dim
// augmentation for one frame interval; the history already visits utime_from on every replay.
Outcome Estimator::apply_flow(const FlowSample& m, int64_t key, FilterState& s) {
  const auto& p = params_.flow;
  const int ci = s.clone_index(key);
  if (ci < 0) return Outcome::kNoClone;
  // The plane a motion is judged against: the terrain's height (a state) standing still, the
  // floor's (height 0), or the terrain's top moving at its velocity state over the interval.
  enum class Plane { kTerrain, kFloor, kMovingTop };
  const double interval_s = static_cast<double>(s.utime - s.clones[ci].utime) / kUsPerS;
  const auto model_over = [&](const FlowSample& f, Plane plane, MeasVec* r, MeasJac* H) {
    Nominal x = s.x;
    if (plane == Plane::kFloor) x.terrain_m = 0.0;
    FlowModel model = flow_model(x, s.clones[ci], R_BC_, p.t_B_C_m,
                                 plane == Plane::kMovingTop ? interval_s : 0.0);
    add_input_sensitivities(model, x, s.clones[ci], R_BC_, f.J_rotation, f.J_normal);
    if (plane == Plane::kFloor) model.H_core.col(idx::kTerrain).setZero();
    *r = f.t_over_d_C1 - model.t_over_d;
    *H = MeasJac::Zero(3, s.dim());
    H->leftCols<idx::kCore>() = model.H_core;
    H->middleCols<kCloneDim>(idx::kCore + kCloneDim * ci) = model.H_clone;
    return model.height_m;
  };
  // Relative to a moving top the flow's vertical is the deck's heave as much as the camera's,
  // which no state models (the rangefinder measures that height): the world's vertical gets the
  // noise of a top's largest speed, and the flow speaks of the horizontal motion only.
  const auto moving_top_noise = [&](const FlowSample& f, double height_m) {
    MeasCov R = flow_noise(f, p, height_m);
    const Vector3d up_C1 = R_BC_.transpose() * (s.clones[ci].q_WB.conjugate() * Vector3d::UnitZ());
    const double sigma = kTopMaxSpeedMps * interval_s / height_m;
    R += sigma * sigma * up_C1 * up_C1.transpose();
    // A deck's roll and pitch turn the top under the camera, which the front end, given the
    // camera's own rotation, reads as a translation of the top's rate times the height.
    const double turn = kTopRateRadps * interval_s;
    R += turn * turn * (Matrix3d::Identity() - up_C1 * up_C1.transpose());
    return R;
  };
  // One motion's update against the plane it fits better, and its NIS; nullopt where the camera
  // is too near the terrain.
  struct Update {
    MeasVec r;
    MeasJac H;
    MeasCov R;
    double nis = 0;
    bool on_floor = false;
    bool on_top = false;  // relative to the moving top
    double height_m = 0;  // the camera's over the plane it is judged against
  };
  const auto update_for = [&](const FlowSample& f) -> std::optional<Update> {
    Update u;
    // A top the flow has shown to move: its motion is the camera's relative to it.
    u.on_top = terrain_raised(s) && s.top_moving;
    const double height_m =
        model_over(f, u.on_top ? Plane::kMovingTop : Plane::kTerrain, &u.r, &u.H);
    if (height_m < p.min_height_m) return std::nullopt;
    u.height_m = height_m;
    u.R = u.on_top ? moving_top_noise(f, height_m) : flow_noise(f, p, height_m);
    // Over a platform the rangefinder's terrain is its top, while the front end's dominant plane
    // stays the floor until the platform fills most of the view (below about 0.5 m over it), and
    // in between its fit may take features of both: the two planes give t/d apart by the
    // platform's height over the camera's (7 % at 1.5 m over paper's platform a, most of the
    // divergence in a descent onto it). Which plane the sample saw is not known, so the
    // difference between the two predictions enters the noise (one sigma: half of it; nothing
    // when hovering, where they agree), and the sample is fused against the plane it fits
    // better, the floor being the take-off floor, height 0 (README, "The platform step").
    MeasVec r_floor;
    MeasJac H_floor;
    double floor_height_m = 0;
    if (terrain_raised(s) &&
        (floor_height_m = model_over(f, Plane::kFloor, &r_floor, &H_floor)) >= p.min_height_m) {
      MeasVec r_still = u.r;
      MeasJac H_still;
      if (u.on_top) model_over(f, Plane::kTerrain, &r_still, &H_still);
      const MeasVec between = r_floor - r_still;  // over the terrain minus over the floor
      MeasCov R_floor = flow_noise(f, p, height_m) + 0.25 * between * between.transpose();
      if (!u.on_top) u.R = R_floor;
      double nis_floor = 0;
      fuse(s, u.r, u.H, u.R, -1.0, &u.nis);  // a negative gate refuses: only the NIS
      fuse(s, r_floor, H_floor, R_floor, -1.0, &nis_floor);
      if (nis_floor < u.nis) {
        u.r = r_floor;
        u.H = H_floor;
        u.R = R_floor;
        u.nis = nis_floor;
        u.on_floor = true;
        u.on_top = false;
        u.height_m = floor_height_m;
      }
    } else if (!m.others.empty()) {
      fuse(s, u.r, u.H, u.R, -1.0, &u.nis);  // for the choice between the motions below
    }
    return u;
  };
  std::optional<Update> u = update_for(m);
  int chosen = -1;  // the sample's own motion, or the index of the other it took
  // Two motions in view (a textured platform moving under the camera over a sparse floor): the
  // one the prediction explains better is the floor's. Taking the larger, the platform's, the
  // estimate would follow the platform: a vehicle holding over it moves with it while its
  // estimate stands still.
  for (size_t k = 0; k < m.others.size(); ++k) {
    const std::optional<Update> b = update_for(with_motion(m, m.others[k]));
    if (b && (!u || b->nis < u->nis)) {
      u = b;
      chosen = static_cast<int>(k);
    }
  }
  Outcome o = Outcome::kGeometry;
  bool inflated = false;
  if (u) {
    if (u->on_floor) ++s.flow_on_floor;
    const MeasVec& r = u->r;
    const MeasJac& H = u->H;
    const MeasCov& R = u->R;
    double nis = 0;
    o = fuse(s, r, H, R, p.gate_chi2, &nis);
    // A run of samples the gate refuses says the model and the flow disagree by more than either
    // knows: a plane the model does not have (a top in the camera's view while the rangefinder
    // sees the floor, whose features outnumber a sparse floor's), not an outlier. Left to the IMU
    // the estimate drifts until the flow can never pass again and the health goes DEGRADED. Past
    // half the flow timeout of refusals on end (a refusal after as long a silence starts a run,
    // so a lone outlier never passes) the sample is fused with its noise scaled so that its
    // innovation is a typical one (covariance matching; Mehra 1972): the estimate follows the flow
    // loosely, its covariance shrinks only as far as the inflated noise allows, and a flow that
    // even so does not pass (the state's own uncertainty dominating) still times out to DEGRADED.
    const int64_t run_us = to_us(0.5 * params_.health.flow_timeout_s);
    if (o == Outcome::kGate) {
      if (s.flow_gated_since_utime == 0 || m.utime_to - s.flow_gated_last_utime > run_us)
        s.flow_gated_since_utime = m.utime_to;
      s.flow_gated_last_utime = m.utime_to;
    }
    if (o == Outcome::kGate && std::isfinite(nis) &&
        m.utime_to - s.flow_gated_since_utime >= run_us) {
      o = fuse(s, r, H, R * (nis / kChi2Median3Dof), p.gate_chi2);
      inflated = o == Outcome::kFused;
      if (inflated) ++s.flow_inflated;
    }
    if (o == Outcome::kFused) {
      s.flow_gated_since_utime = 0;
      s.flow_refused_utime = 0;
      if (chosen >= 0) ++s.flow_second;
      if (u->on_top) ++s.flow_top;
    }
    if (o == Outcome::kGate && m.others.empty())
      reset_velocity_to_flow(s, m, implied_velocity_error(s, m, r, u->R, u->height_m, ci));
  }
  // Two motions in view with the rangefinder on a top, the one fused as it is judged the floor's
  // or the moving top's: the other is the other plane's. The top's measures the top's velocity
  // (the camera's own motion known from the floor's); the floor's keeps the vehicle's velocity
  // on the still world while the top's explains the sample better.
  if (o == Outcome::kFused && !inflated && (u->on_floor || u->on_top) && !m.others.empty()) {
    const FlowSample rest = chosen < 0 ? with_motion(m, m.others.front()) : m;
    const Plane plane = u->on_floor ? Plane::kMovingTop : Plane::kFloor;
    MeasVec r;
    MeasJac H;
    const double height_m = model_over(rest, plane, &r, &H);
    const MeasCov R = plane == Plane::kMovingTop ? moving_top_noise(rest, height_m)
                                                 : flow_noise(rest, p, height_m);
    if (height_m >= p.min_height_m && fuse(s, r, H, R, p.gate_chi2) == Outcome::kFused) {
      if (plane == Plane::kMovingTop) ++s.flow_top;
      s.top_moving = top_is_moving(s);
    }
  }
  remove_clone(s, ci);
  return o;
}

bool Estimator::top_is_moving(const FilterState& s) const {
  // Moving: its speed is three sigmas clear of zero and of the flow's own noise floor, the
  // speed below which the top's motion and the floor's cannot be told apart anyway.
  const Vector2d v = s.x.top_v_W;
  const double speed = v.norm();
  if (speed == 0.0) return false;
  const Vector2d along = v / speed;
  const double sigma = std::sqrt(along.dot(s.P.block<2, 2>(idx::kTopV, idx::kTopV) * along));
  return speed > 3.0 * std::max(sigma, params_.flow.sigma_floor_mps);
}

Estimator::VelocityError Estimator::implied_velocity_error(const FilterState& s,
                                                           const FlowSample& m, const MeasVec& r,
                                                           const MeasCov& R, double height_m,
                                                           int ci) const {
  // r is t/d in the first exposure's camera frame: times d, the displacement the estimate lacks
  // over the interval; over the interval, the velocity it lacks (the IMU's acceleration inside
  // the interval is the filter's own, in both the prediction and the truth).
  const double dt_s = static_cast<double>(m.utime_to - m.utime_from) / kUsPerS;
  const Matrix3d A = s.clones[ci].q_WB.toRotationMatrix() * R_BC_ * (height_m / dt_s);
  const Vector3d dv_W = A * r;
  const Matrix3d cov_W = A * R * A.transpose();
  VelocityError e;
  e.utime = m.utime_to;
  e.dv = dv_W.head<2>();
  e.cov = cov_W.topLeftCorner<2, 2>();
  return e;
}

// A refused sample that even its inflated noise did not pass says the state's covariance is the
// wrong one: the filter is sure of a velocity the floor's motion contradicts, and on the IMU alone
// no later sample would pass. As EKF2 resets its velocity to the flow, its only horizontal aid,
// after the flow's timeout, the horizontal velocity becomes the flow's; only where the flow is
// the one to believe (no flow fused for the timeout, over the floor, the height trustworthy) and
// two samples in a row agree on the error (a lone bad sample never resets). The velocity's
// correlations go and its variance is the sample's; the position is kept (no step for the pose's
// consumers beyond the change over the flow's delay as the state is run forward).
void Estimator::reset_velocity_to_flow(FilterState& s, const FlowSample& m,
                                       const VelocityError& e) const {
  const int64_t timeout_us = to_us(params_.health.flow_timeout_s);
  const bool consecutive = s.flow_refused_utime != 0 && m.utime_from <= s.flow_refused_utime &&
                           e.utime - s.flow_refused_utime <= timeout_us;
  const Vector2d diff = e.dv - s.flow_refused_dv;
  const Eigen::Matrix2d both = e.cov + s.flow_refused_cov;
  const bool agree = consecutive && diff.dot(both.ldlt().solve(diff)) <= kChi2P001Dof2;
  s.flow_refused_utime = e.utime;
  s.flow_refused_dv = e.dv;
  s.flow_refused_cov = e.cov;
  const bool timed_out = e.utime - s.last_fused_utime[static_cast<int>(Sensor::kFlow)] > timeout_us;
  if (!(timed_out && agree && !terrain_raised(s) && vertical_ok(s))) return;
  s.x.v_W_B.head<2>() += e.dv;
  for (int i = idx::kV; i < idx::kV + 2; ++i) {
    s.P.row(i).setZero();
    s.P.col(i).setZero();
  }
  s.P.block<2, 2>(idx::kV, idx::kV) = e.cov;
  s.flow_refused_utime = 0;
  ++s.flow_velocity_resets;
}

// ---- Output

std::optional<Quaterniond> Estimator::attitude_at(int64_t utime) const {
  if (!initialised() || utime < history_.front().s.utime || utime > newest_imu_utime())
    return std::nullopt;
  size_t k = history_.size() - 1;
  while (k > 0 && history_[k].s.utime > utime) --k;
  const FilterState& s = history_[k].s;
  if (s.utime == utime) return s.x.q_WB;
  // Inside the next interval: its sample's rate, as the propagation integrates it.
  const ImuSample& next = history_[k + 1].imu;
  return (s.x.q_WB * quat_exp((next.gyro_B - s.x.gyro_bias_B) * ((utime - s.utime) / kUsPerS)))
      .normalized();
}

State Estimator::state() const {
  State out;
  out.counters = counters_;
  if (!initialised()) {
    out.health = Health::kLost;
    out.health_reasons = kNotInitialised;
    return out;
  }
  const FilterState& s = history_.back().s;
  out.utime = s.utime;
  out.initialised = true;
  out.p_W_B = s.x.p_W_B;
  out.v_W_B = s.x.v_W_B;
  out.q_WB = s.x.q_WB;
  out.accel_bias_B = s.x.accel_bias_B;
  out.gyro_bias_B = s.x.gyro_bias_B;
  out.baro_offset_m = s.x.baro_offset_m;
  out.terrain_height_m = s.x.terrain_m;
  out.top_velocity_W = s.x.top_v_W;
  out.top_moving = s.top_moving;
  out.cov = s.P.topLeftCorner<idx::kCore, idx::kCore>();
  out.counters.terrain_resets = s.terrain_resets;
  out.counters.flow_on_floor = s.flow_on_floor;
  out.counters.flow_inflated = s.flow_inflated;
  out.counters.flow_second = s.flow_second;
  out.counters.flow_top = s.flow_top;
  out.counters.baro_resets = s.baro_resets;
  out.counters.flow_velocity_resets = s.flow_velocity_resets;

  const auto& h = params_.health;
  uint32_t reasons = kReasonNone;
  Health health = Health::kOk;
  auto flag = [&](uint32_t why, Health level) {
    reasons |= why;
    health = std::max(health, level);
  };
  auto age_s = [&](Sensor sensor) {
    return (s.utime - s.last_fused_utime[static_cast<int>(sensor)]) / kUsPerS;
  };
  if (age_s(Sensor::kFlow) > h.flow_timeout_s) flag(kNoFlow, Health::kDegraded);
  // Below the rangefinder's blind zone (resting on the floor) no reading is expected; nor where
  // the estimate cannot tell, within two sigma of its height, that it is above it (resting, the
  // flow's noise as a velocity is large a few centimetres over the floor: sigma_floor_mps).
  const RangeModel range = range_model(s.x, params_.range.t_B_R_m, range_d_B_);
  const double range_var =
      (range.H * s.P.topLeftCorner<idx::kCore, idx::kCore>() * range.H.transpose())(0, 0);
  if (range.range_m - 2.0 * std::sqrt(std::max(0.0, range_var)) > params_.range.min_range_m &&
      age_s(Sensor::kRange) > h.range_timeout_s)
    flag(kNoRange, Health::kDegraded);
  if (h.baro_timeout_s > 0 && age_s(Sensor::kBaro) > h.baro_timeout_s)
    flag(kNoBaro, Health::kDegraded);
  if (s.last_imu_gap_utime != 0 &&
      (s.utime - s.last_imu_gap_utime) / kUsPerS < h.imu_gap_recovery_s)
    flag(kImuGap, Health::kDegraded);
  if ((newest_other_utime_ - s.utime) / kUsPerS > h.imu_lost_s) flag(kImuStopped, Health::kLost);

  const Eigen::VectorXd sd = out.cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  const double pos_sd = std::max(sd[idx::kP], sd[idx::kP + 1]);
  const double vel_sd = sd.segment<3>(idx::kV).maxCoeff();
  const double height_sd = sd[idx::kP + 2];
  if (pos_sd > h.pos_sigma_lost_m)
    flag(kPositionUncertain, Health::kLost);
  else if (pos_sd > h.pos_sigma_degraded_m)
    flag(kPositionUncertain, Health::kDegraded);
  if (vel_sd > h.vel_sigma_lost_mps)
    flag(kVelocityUncertain, Health::kLost);
  else if (vel_sd > h.vel_sigma_degraded_mps)
    flag(kVelocityUncertain, Health::kDegraded);
  if (height_sd > h.height_sigma_lost_m)
    flag(kHeightUncertain, Health::kLost);
  else if (height_sd > h.height_sigma_degraded_m)
    flag(kHeightUncertain, Health::kDegraded);
  out.health = health;
  out.health_reasons = reasons;
  return out;
}

}  // namespace alight::estimator

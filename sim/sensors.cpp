#include "sim/sensors.hpp"

#include <algorithm>
#include <cmath>

namespace alight::sim {

namespace {
Vector3d gauss3(std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double a = n(rng), b = n(rng), c = n(rng);
  return sigma * Vector3d(a, b, c);
}
int64_t period_of(double rate_hz) { return std::llround(1e6 / rate_hz); }

// A second stream from one seed (splitmix64's finaliser), so a new draw never shifts the
// stream an older one reads.
uint64_t side_stream(uint64_t seed) {
  uint64_t z = seed + 0x632BE59BD9B4E019ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// ICAO standard atmosphere, troposphere.
constexpr double kLapseKpm = 0.0065;
constexpr double kG0 = 9.80665;
constexpr double kRAir = 287.05287;
constexpr double kExponent = kG0 / (kRAir * kLapseKpm);  // 5.25588
constexpr double kKelvin = 273.15;
}  // namespace

double isa_pressure_pa(double altitude_m, double p0_pa, double t0_c) {
  const double t0 = t0_c + kKelvin;
  return p0_pa * std::pow((t0 - kLapseKpm * altitude_m) / t0, kExponent);
}

double isa_altitude_m(double pressure_pa, double p0_pa, double t0_c) {
  const double t0 = t0_c + kKelvin;
  return t0 / kLapseKpm * (1.0 - std::pow(pressure_pa / p0_pa, 1.0 / kExponent));
}

double isa_temperature_c(double altitude_m, double t0_c) { return t0_c - kLapseKpm * altitude_m; }

MocapEmulator::MocapEmulator(const MocapParams& params, int64_t start_utime, uint64_t seed)
    : params_(params), period_us_(period_of(params.rate_hz)), next_utime_(start_utime), rng_(seed) {
  for (const auto& d : params.dropouts_s)
    add_dropout(start_utime + std::llround(d[0] * 1e6), start_utime + std::llround(d[1] * 1e6));
}

void MocapEmulator::add_dropout(int64_t from_utime, int64_t to_utime) {
  dropouts_.emplace_back(from_utime, to_utime);
}

bool MocapEmulator::dropped(int64_t utime) {
  for (const auto& [a, b] : dropouts_)
    if (utime >= a && utime < b) return true;
  if (params_.dropout_probability <= 0) return false;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  return u(rng_) < params_.dropout_probability;
}

void MocapEmulator::update(int64_t now_utime, const PoseSample& truth) {
  while (now_utime >= next_utime_) {
    const int64_t t = next_utime_;
    next_utime_ += period_us_;
    // The noise is drawn for every sample, dropped or not, so a dropout leaves the other samples
    // of the run unchanged.
    const Vector3d dp = gauss3(rng_, params_.pos_sigma_m);
    const Vector3d dr = gauss3(rng_, params_.rot_sigma_rad);
    const Vector3d dv = gauss3(rng_, params_.vel_sigma_mps);
    const Vector3d dw = gauss3(rng_, params_.rate_sigma_radps);
    ++seq_;
    if (dropped(t)) continue;
    MocapSample m;
    m.seq = seq_;
    m.pose = truth;
    m.pose.utime = t;
    m.pose.p_W_B += dp;
    const double a = dr.norm();
    if (a > 0) m.pose.q_WB = (truth.q_WB * Quaterniond(Eigen::AngleAxisd(a, dr / a))).normalized();
    m.pose.v_W_B += dv;
    m.pose.omega_B += dw;
    queue_.push_back(m);
  }
}

std::vector<MocapSample> MocapEmulator::take(int64_t now_utime) {
  std::vector<MocapSample> out;
  const int64_t latency_us = std::llround(params_.latency_s * 1e6);
  while (!queue_.empty() && queue_.front().pose.utime + latency_us <= now_utime) {
    out.push_back(queue_.front());
    queue_.pop_front();
  }
  return out;
}

ImuEmulator::ImuEmulator(const ImuParams& params, int64_t start_utime, uint64_t seed)
    : params_(params),
      period_us_(period_of(params.rate_hz)),
      next_utime_(start_utime + period_us_),
      rng_(seed),
      walk_rng_(side_stream(seed)) {
  accel_bias_ = gauss3(rng_, params.accel_bias_sigma_mps2);
  gyro_bias_ = gauss3(rng_, params.gyro_bias_sigma_radps);
}

void ImuEmulator::update(int64_t now_utime, int64_t dt_us, const Vector3d& f_B,
                         const Vector3d& w_B) {
  const double dt = dt_us * 1e-6;
  accel_sum_ += f_B * dt;
  gyro_sum_ += w_B * dt;
  sum_s_ += dt;
  if (now_utime < next_utime_) return;
  const double sqrt_dt = std::sqrt(period_us_ * 1e-6);
  accel_bias_ += gauss3(walk_rng_, params_.accel_bias_walk_mps2_per_sqrt_s * sqrt_dt);
  gyro_bias_ += gauss3(walk_rng_, params_.gyro_bias_walk_radps_per_sqrt_s * sqrt_dt);
  ImuSample s;
  s.utime = next_utime_;
  s.seq = ++seq_;
  s.accel_B = accel_sum_ / sum_s_ + accel_bias_ + gauss3(rng_, params_.accel_sigma_mps2);
  s.gyro_B = gyro_sum_ / sum_s_ + gyro_bias_ + gauss3(rng_, params_.gyro_sigma_radps);
  out_.push_back(s);
  accel_sum_.setZero();
  gyro_sum_.setZero();
  sum_s_ = 0.0;
  next_utime_ += period_us_;
}

std::vector<ImuSample> ImuEmulator::take() {
  std::vector<ImuSample> out;
  out.swap(out_);
  return out;
}

RangefinderEmulator::RangefinderEmulator(const RangefinderParams& params, int64_t start_utime,
                                         uint64_t seed)
    : params_(params),
      beam_B_(params.direction_B.normalized()),
      period_us_(period_of(params.rate_hz)),
      next_utime_(start_utime + period_us_),
      rng_(seed) {}

void RangefinderEmulator::update(int64_t now_utime, const Isometry3d& X_WB, const Scene& scene) {
  const RangefinderParams& P = params_;
  const double run = std::max(1.0, P.dropout_burst_s * P.rate_hz);  // mean run length [samples]
  const double start_run = P.dropout_prob / (run * (1.0 - P.dropout_prob));
  while (now_utime >= next_utime_) {
    RangeSample s;
    s.utime = next_utime_;
    s.seq = ++seq_;
    s.min_range_m = P.min_range_m;
    s.max_range_m = P.max_range_m;
    s.t_B_R = P.offset_B_m;
    s.beam_B = beam_B_;
    next_utime_ += period_us_;
    // Both draws for every sample, whatever its outcome, so one sample's outcome never shifts
    // the noise of the others.
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double noise = n(rng_);
    const double draw = u(rng_);
    losing_ = losing_ ? draw < 1.0 - 1.0 / run : draw < start_run;

    const Vector3d origin_W = X_WB * P.offset_B_m;
    const Vector3d beam_W = X_WB.linear() * beam_B_;
    // Far enough that noise cannot bring a surface beyond it back into range.
    const auto hit = scene.cast_ray(origin_W, beam_W, 2.0 * P.max_range_m + 1.0);
    if (hit) {
      const double measured =
          hit->distance_m + (P.sigma_m + P.sigma_frac * hit->distance_m) * noise;
      if (measured > P.max_range_m)
        s.status = RangeStatus::kOutOfRange;
      else if (measured < P.min_range_m)
        s.status = RangeStatus::kTooNear;
      else if (losing_)
        s.status = RangeStatus::kNoEcho;
      else {
        s.status = RangeStatus::kOk;
        s.distance_m = measured;
      }
    }
    queue_.push_back(s);
  }
}

std::vector<RangeSample> RangefinderEmulator::take(int64_t now_utime) {
  std::vector<RangeSample> out;
  const int64_t latency_us = std::llround(params_.latency_s * 1e6);
  while (!queue_.empty() && queue_.front().utime + latency_us <= now_utime) {
    out.push_back(queue_.front());
    queue_.pop_front();
  }
  return out;
}

BaroEmulator::BaroEmulator(const BaroParams& params, int64_t start_utime, uint64_t seed)
    : params_(params),
      period_us_(period_of(params.rate_hz)),
      next_utime_(start_utime + period_us_),
      rng_(seed) {
  std::normal_distribution<double> n(0.0, 1.0);
  offset_pa_ = params.offset_sigma_pa * n(rng_);
  const double dt = period_us_ * 1e-6, tau = params.drift_tau_s;
  drift_decay_ = std::exp(-dt / tau);
  // sqrt(1 - a^2) through expm1: 1 - a^2 is tiny for a long correlation time.
  drift_step_pa_ = params.drift_pa_per_sqrt_s * std::sqrt(0.5 * tau * -std::expm1(-2.0 * dt / tau));
}

void BaroEmulator::update(int64_t now_utime, const Vector3d& p_W_B) {
  const BaroParams& P = params_;
  while (now_utime >= next_utime_) {
    std::normal_distribution<double> n(0.0, 1.0);
    const double w = n(rng_), v = n(rng_);
    drift_pa_ = drift_decay_ * drift_pa_ + drift_step_pa_ * w;
    const double altitude_m = P.ground_altitude_m + p_W_B.z();
    BaroSample s;
    s.utime = next_utime_;
    s.seq = ++seq_;
    s.pressure_pa =
        isa_pressure_pa(altitude_m, P.sea_level_pressure_pa, P.sea_level_temperature_c) +
        offset_pa_ + drift_pa_ + P.sigma_pa * v;
    s.temperature_c = isa_temperature_c(altitude_m, P.sea_level_temperature_c);
    queue_.push_back(s);
    next_utime_ += period_us_;
  }
}

std::vector<BaroSample> BaroEmulator::take(int64_t now_utime) {
  std::vector<BaroSample> out;
  const int64_t latency_us = std::llround(params_.latency_s * 1e6);
  while (!queue_.empty() && queue_.front().utime + latency_us <= now_utime) {
    out.push_back(queue_.front());
    queue_.pop_front();
  }
  return out;
}

}  // namespace alight::sim

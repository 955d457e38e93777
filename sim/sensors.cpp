#include "sim/sensors.hpp"

#include <cmath>

namespace alight::sim {

namespace {
Vector3d gauss3(std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double a = n(rng), b = n(rng), c = n(rng);
  return sigma * Vector3d(a, b, c);
}
int64_t period_of(double rate_hz) { return std::llround(1e6 / rate_hz); }
}  // namespace

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
      rng_(seed) {
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

}  // namespace alight::sim

#include "sim/camera_effects.hpp"

#include <algorithm>
#include <cmath>

namespace alight::sim {

Vibration::Vibration(const VibrationParams& params, uint64_t seed) : params_(params) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2 * M_PI);
  for (auto& h : angle_phase_)
    for (double& p : h) p = phase(rng);
  for (auto& h : linear_phase_)
    for (double& p : h) p = phase(rng);
}

Vector3d Vibration::angle(double t) const {
  Vector3d a = Vector3d::Zero();
  if (!params_.enabled) return a;
  for (int k = 1; k <= params_.harmonics; ++k) {
    const double w = 2 * M_PI * params_.base_hz * k, amp = params_.angle_rad / k;
    for (int i = 0; i < 3; ++i) a[i] += amp * std::sin(w * t + angle_phase_[k - 1][i]);
  }
  return a;
}

Vector3d Vibration::offset(double t) const {
  Vector3d d = Vector3d::Zero();
  if (!params_.enabled) return d;
  for (int k = 1; k <= params_.harmonics; ++k) {
    const double w = 2 * M_PI * params_.base_hz * k, amp = params_.linear_m / k;
    for (int i = 0; i < 3; ++i) d[i] += amp * std::sin(w * t + linear_phase_[k - 1][i]);
  }
  return d;
}

Vector3d Vibration::velocity(double t) const {
  Vector3d v = Vector3d::Zero();
  if (!params_.enabled) return v;
  for (int k = 1; k <= params_.harmonics; ++k) {
    const double w = 2 * M_PI * params_.base_hz * k, amp = params_.linear_m / k;
    for (int i = 0; i < 3; ++i) v[i] += amp * w * std::cos(w * t + linear_phase_[k - 1][i]);
  }
  return v;
}

Isometry3d Vibration::jitter(double t) const {
  const Vector3d a = angle(t);
  const double n = a.norm();
  const Matrix3d R =
      n > 0 ? Eigen::AngleAxisd(n, a / n).toRotationMatrix() : Matrix3d::Identity().eval();
  return make_transform(R, offset(t));
}

Vector3d Vibration::mean_rate(double t0, double t1) const {
  return (angle(t1) - angle(t0)) / (t1 - t0);
}

Vector3d Vibration::mean_accel(double t0, double t1) const {
  return (velocity(t1) - velocity(t0)) / (t1 - t0);
}

ExposureSteps::ExposureSteps(const CameraEffects& e, double frame_rate_hz)
    : max_ev_(e.ae_max_ev),
      p_step_(std::min(1.0, e.ae_rate_hz / frame_rate_hz)),
      lag_(std::max(1, e.ae_lag_frames)) {}

void ExposureSteps::start(double ev) {
  step_ev_ = ev;
  since_ = 0;
  forced_ = true;
}

double ExposureSteps::next_ev(std::mt19937_64& rng) {
  // Both draws on every frame, so the stream's use does not depend on the outcome.
  const double u = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  const double ev = std::uniform_real_distribution<double>(-max_ev_, max_ev_)(rng);
  if (!forced_ && u < p_step_) {
    step_ev_ = ev;
    since_ = 0;
  }
  forced_ = false;
  const double out = since_ < lag_ ? step_ev_ * (1.0 - static_cast<double>(since_) / lag_) : 0.0;
  if (since_ < lag_) ++since_;
  return out;
}

cv::Mat vignetting_map(const CameraModel& m, double corner_ratio) {
  cv::Mat map(m.height, m.width, CV_32F);
  const double dx = std::max(m.cx + 0.5, m.width - 0.5 - m.cx);
  const double dy = std::max(m.cy + 0.5, m.height - 0.5 - m.cy);
  const double r2_corner = dx * dx + dy * dy;
  // cos^4 of a pinhole: 1 / (1 + tan^2)^2; k scales tan^2 so the corner gets corner_ratio.
  const double k = 1.0 / std::sqrt(corner_ratio) - 1.0;
  for (int v = 0; v < m.height; ++v) {
    float* row = map.ptr<float>(v);
    for (int u = 0; u < m.width; ++u) {
      const double rho2 = ((u - m.cx) * (u - m.cx) + (v - m.cy) * (v - m.cy)) / r2_corner;
      const double f = 1.0 + k * rho2;
      row[u] = static_cast<float>(1.0 / (f * f));
    }
  }
  return map;
}

DriverDraw draw_driver(const CameraEffects& e, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  DriverDraw d;
  const double a = u(rng), b = u(rng), n = g(rng);
  d.dropped = a < e.drop_prob;
  d.duplicated = !d.dropped && b < e.dup_prob;
  d.stamp_error_s = e.stamp_jitter_s * n;
  return d;
}

}  // namespace alight::sim

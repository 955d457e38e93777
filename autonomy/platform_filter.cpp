// The moving platform's constant-velocity filter and the deck's heave fit (platform_filter.hpp).
#include "autonomy/platform_filter.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace alight::autonomy {
namespace {

// The platform's axes repeat every quarter turn: its yaw is kept in (-pi/4, pi/4] and every
// innovation wrapped there (a top seen in part can swap its long and short sides).
double wrap_quarter(double a) {
  a = std::remainder(a, M_PI / 2);
  if (a <= -M_PI / 4) a += M_PI / 2;
  return a;
}

bool finite(const PlatformMeasurement& m) {
  return m.p_W.allFinite() && m.v_W.allFinite() && m.cov_p_W.allFinite() && m.cov_v_W.allFinite() &&
         std::isfinite(m.yaw_rad) && std::isfinite(m.yaw_rate_rps) && std::isfinite(m.var_yaw) &&
         std::isfinite(m.var_yaw_rate) && m.var_yaw >= 0 && m.var_yaw_rate >= 0;
}

// Continuous white-acceleration process noise of a constant-velocity pair over dt.
Matrix2d cv_noise(double psd, double dt) {
  Matrix2d Q;
  Q << dt * dt * dt / 3, dt * dt / 2, dt * dt / 2, dt;
  return psd * Q;
}

}  // namespace

const ParamSchema<PlatformFilterParams>& PlatformFilterParams::schema() {
  using P = PlatformFilterParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("accel_psd", &P::accel_psd, Range::gt(0), "m^2/s^3",
          "white acceleration driving the platform's constant-velocity model (a cart's turns)");
    s.add("yaw_accel_psd", &P::yaw_accel_psd, Range::gt(0), "rad^2/s^3",
          "white angular acceleration driving its yaw rate");
    s.add("gate_chi2", &P::gate_chi2, Range::gt(0), "",
          "a measurement's position and velocity innovation beyond this (4 dof) is refused");
    s.add("max_consecutive_rejections", &P::max_consecutive_rejections, Range::ge(1), "",
          "refused in a row: the filter starts over from the next measurement");
    s.add("stale_s", &P::stale_s, Range::gt(0), "s",
          "no measurement for this long: the filter starts over");
    s.add("min_sigma_m", &P::min_sigma_m, Range::gt(0), "m",
          "floor on a measurement's position sigma");
    s.add("min_sigma_mps", &P::min_sigma_mps, Range::gt(0), "m/s",
          "floor on a measurement's velocity sigma");
    s.add("course_tau_s", &P::course_tau_s, Range::gt(0), "s",
          "the course's turn rate (a cart round a bend) smoothed over this; the prediction "
          "turns the velocity at it");
    s.add("heave_window_s", &P::heave_window_s, Range::gt(0), "s",
          "the vertical velocities the heave is fitted to");
    s.add("heave_min_hz", &P::heave_min_hz, Range::gt(0), "Hz", "lowest heave frequency fitted");
    s.add("heave_max_hz", &P::heave_max_hz, Range::gt(0), "Hz", "highest heave frequency fitted")
        .check([](const P& p) { return p.heave_max_hz > p.heave_min_hz; },
               "must exceed heave_min_hz");
    return s;
  }();
  return schema;
}

void PlatformFilterParams::validate() const { schema().validate(*this); }

double HeaveModel::vz(int64_t utime) const {
  if (!(w_rps > 0)) return 0.0;
  const double t = double(utime - t0_utime) * 1e-6;
  return a * std::sin(w_rps * t) + b * std::cos(w_rps * t) + c;
}

double HeaveModel::z(int64_t utime) const {
  if (!(w_rps > 0)) return 0.0;
  const double t = double(utime - t0_utime) * 1e-6;
  return (-a * std::cos(w_rps * t) + b * std::sin(w_rps * t)) / w_rps;
}

HeaveModel fit_heave(const std::deque<std::pair<int64_t, double>>& vz, double min_hz,
                     double max_hz) {
  HeaveModel best;
  if (vz.size() < 8) return best;
  const int64_t t0 = vz.front().first;
  const double span_s = double(vz.back().first - t0) * 1e-6;
  // A sine is told from a drift only over most of a period.
  const double lo_hz = std::max(min_hz, 0.6 / std::max(span_s, 1e-3));
  if (!(lo_hz < max_hz)) return best;
  double best_sse = INFINITY;
  constexpr int kGrid = 60;
  for (int k = 0; k <= kGrid; ++k) {
    const double f = lo_hz * std::pow(max_hz / lo_hz, double(k) / kGrid);
    const double w = 2 * M_PI * f;
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    for (const auto& [t_us, v] : vz) {
      const double t = double(t_us - t0) * 1e-6;
      const Eigen::Vector3d row(std::sin(w * t), std::cos(w * t), 1.0);
      A += row * row.transpose();
      y += row * v;
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
    if (ldlt.info() != Eigen::Success) continue;
    const Eigen::Vector3d sol = ldlt.solve(y);
    if (!sol.allFinite()) continue;
    double sse = 0;
    for (const auto& [t_us, v] : vz) {
      const double t = double(t_us - t0) * 1e-6;
      const double r = v - (sol(0) * std::sin(w * t) + sol(1) * std::cos(w * t) + sol(2));
      sse += r * r;
    }
    if (sse < best_sse) {
      best_sse = sse;
      best.w_rps = w, best.a = sol(0), best.b = sol(1), best.c = sol(2), best.t0_utime = t0;
    }
  }
  best.rms_mps = std::sqrt(best_sse / double(vz.size()));
  return best;
}

PlatformFilter::PlatformFilter(const PlatformFilterParams& params) : params_(params) {
  params_.validate();
}

void PlatformFilter::reset() {
  t_utime_ = 0;
  course_rate_ = 0;
  consecutive_rejections_ = 0;
  top_z_sum_ = 0;
  n_z_ = 0;
  vz_.clear();
  heave_ = HeaveModel{};
}

PlatformFilter::Prediction PlatformFilter::predict(int64_t utime) const {
  Prediction p;
  const double dt = std::max(0.0, double(utime - t_utime_) * 1e-6);
  // The path's turn (a cart round a bend): the velocity turned at course_rate_ over dt.
  const double w = course_rate_, a = w * dt;
  const Vector2d v = x_.tail<2>(), v_perp(-v.y(), v.x());
  if (std::abs(a) > 1e-6) {
    p.p_W = x_.head<2>() + (std::sin(a) * v + (1 - std::cos(a)) * v_perp) / w;
    p.v_W = std::cos(a) * v + std::sin(a) * v_perp;
  } else {
    p.p_W = x_.head<2>() + dt * v;
    p.v_W = v;
  }
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F.topRightCorner<2, 2>() = dt * Matrix2d::Identity();
  Eigen::Matrix4d Pp = F * P_ * F.transpose();
  const Matrix2d q = cv_noise(params_.accel_psd, dt);
  for (int i = 0; i < 2; ++i) {
    Pp(i, i) += q(0, 0), Pp(i, i + 2) += q(0, 1), Pp(i + 2, i) += q(1, 0),
        Pp(i + 2, i + 2) += q(1, 1);
  }
  p.cov_p = Pp.topLeftCorner<2, 2>();
  p.cov_v = Pp.bottomRightCorner<2, 2>();
  p.yaw_rad = wrap_quarter(yaw_(0) + dt * yaw_(1));
  p.yaw_rate_rps = yaw_(1);
  p.var_yaw = P_yaw_(0, 0) + 2 * dt * P_yaw_(0, 1) + dt * dt * P_yaw_(1, 1) +
              cv_noise(params_.yaw_accel_psd, dt)(0, 0);
  p.top_z_m = n_z_ > 0 ? top_z_sum_ / n_z_ : 0.0;
  return p;
}

bool PlatformFilter::update(const PlatformMeasurement& m) {
  if (!finite(m) || m.utime <= 0 || m.ref_utime >= m.utime) return false;
  if (initialised() && m.utime <= t_utime_) return false;
  if (initialised() && double(m.utime - t_utime_) * 1e-6 > params_.stale_s) reset();
  // The measurement's covariances, floored: vision's residuals can be optimistic.
  Eigen::Matrix4d R = Eigen::Matrix4d::Zero();
  R.topLeftCorner<2, 2>() = m.cov_p_W.topLeftCorner<2, 2>() +
                            params_.min_sigma_m * params_.min_sigma_m * Matrix2d::Identity();
  R.bottomRightCorner<2, 2>() = m.cov_v_W.topLeftCorner<2, 2>() + params_.min_sigma_mps *
                                                                      params_.min_sigma_mps *
                                                                      Matrix2d::Identity();
  const Eigen::Vector4d z(m.p_W.x(), m.p_W.y(), m.v_W.x(), m.v_W.y());
  if (!initialised()) {
    x_ = z;
    P_ = R;
    yaw_ = Vector2d(wrap_quarter(m.yaw_rad), m.yaw_rate_rps);
    P_yaw_ = Vector2d(m.var_yaw + 1e-4, m.var_yaw_rate + 1e-4).asDiagonal();
  } else {
    const double dt = double(m.utime - t_utime_) * 1e-6;
    Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
    F.topRightCorner<2, 2>() = dt * Matrix2d::Identity();
    Eigen::Matrix4d Pp = F * P_ * F.transpose();
    const Matrix2d q = cv_noise(params_.accel_psd, dt);
    for (int i = 0; i < 2; ++i) {
      Pp(i, i) += q(0, 0), Pp(i, i + 2) += q(0, 1), Pp(i + 2, i) += q(1, 0),
          Pp(i + 2, i + 2) += q(1, 1);
    }
    const Prediction ahead = predict(m.utime);
    Eigen::Vector4d xp;
    xp << ahead.p_W, ahead.v_W;
    const Eigen::Vector4d innov = z - xp;
    const Eigen::Matrix4d S = Pp + R;
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(S);
    const double d2 = innov.dot(ldlt.solve(innov));
    if (!(d2 <= params_.gate_chi2)) {
      ++n_rejected_;
      if (++consecutive_rejections_ < params_.max_consecutive_rejections) return false;
      // The platform is not where it was believed: start over from this measurement.
      reset();
      return update(m);
    }
    const Eigen::Matrix4d K = Pp * ldlt.solve(Eigen::Matrix4d::Identity());
    x_ = xp + K * innov;
    // The course's turn rate, smoothed over about course_tau_s (from the filtered velocity's
    // direction, only while it is fast enough to have one).
    const Vector2d v0 = xp.tail<2>(), v1 = x_.tail<2>();
    if (v0.norm() > 0.2 && v1.norm() > 0.2 && dt > 0) {
      const double rate = std::atan2(v0.x() * v1.y() - v0.y() * v1.x(), v0.dot(v1)) / dt;
      const double k = std::min(1.0, dt / params_.course_tau_s);
      course_rate_ += k * (rate - course_rate_);
    }
    P_ = (Eigen::Matrix4d::Identity() - K) * Pp;
    P_ = 0.5 * (P_ + P_.transpose()).eval();
    // Yaw and its rate: the same filter in one dimension pair.
    Matrix2d Fy;
    Fy << 1, dt, 0, 1;
    const Vector2d yp(yaw_(0) + dt * yaw_(1), yaw_(1));
    const Matrix2d Py = Fy * P_yaw_ * Fy.transpose() + cv_noise(params_.yaw_accel_psd, dt);
    const Vector2d iy(wrap_quarter(m.yaw_rad - yp(0)), m.yaw_rate_rps - yp(1));
    Matrix2d Sy = Py;
    Sy(0, 0) += m.var_yaw + 1e-6;
    Sy(1, 1) += m.var_yaw_rate + 1e-6;
    const Matrix2d Ky = Py * Sy.inverse();
    yaw_ = yp + Ky * iy;
    yaw_(0) = wrap_quarter(yaw_(0));
    P_yaw_ = (Matrix2d::Identity() - Ky) * Py;
  }
  t_utime_ = m.utime;
  consecutive_rejections_ = 0;
  ++n_updates_;
  top_z_sum_ += m.p_W.z();
  ++n_z_;
  // The heave: each vertical velocity is the mean over its interval, so at the interval's middle.
  vz_.emplace_back((m.utime + m.ref_utime) / 2, m.v_W.z());
  while (!vz_.empty() &&
         double(vz_.back().first - vz_.front().first) * 1e-6 > params_.heave_window_s)
    vz_.pop_front();
  heave_ = fit_heave(vz_, params_.heave_min_hz, params_.heave_max_hz);
  return true;
}

}  // namespace alight::autonomy

#include "oracle_vision.hpp"

#include <cmath>

namespace alight::autonomy::test {

OracleVision::OracleVision(const OracleVisionParams& params) : params_(params), rng_(params.seed) {}

bool OracleVision::in_view(const OracleTruth& truth) const {
  const bool landing = params_.mission == Mission::kLanding;
  if (landing ? !truth.has_platform : !truth.has_opening) return false;
  const Vector3d target = landing ? truth.platform_center_W : truth.opening_center_W;
  const Isometry3d X_WC =
      camera_in_world(truth.vehicle.X_WB(), make_transform(params_.R_BC, params_.t_B_C));
  const Vector3d p_C = X_WC.inverse() * target;
  if (p_C.z() < params_.min_range_m || p_C.norm() > params_.max_range_m) return false;
  return std::abs(p_C.x() / p_C.z()) < std::tan(params_.half_fov_x_rad) &&
         std::abs(p_C.y() / p_C.z()) < std::tan(params_.half_fov_y_rad);
}

std::optional<TargetMeasurement> OracleVision::update(const OracleTruth& truth, int64_t utime) {
  const int64_t period = static_cast<int64_t>(1e6 / params_.rate_hz);
  if (!next_utime_) next_utime_ = utime;
  if (utime < *next_utime_) return std::nullopt;
  *next_utime_ += period;
  if (*next_utime_ <= utime) next_utime_ = utime + period;
  if (silent) return std::nullopt;

  TargetMeasurement m;
  m.utime = utime;
  m.mission = params_.mission;
  if (blind || !in_view(truth)) return m;
  m.found = true;
  ++n_found_;
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const bool landing = params_.mission == Mission::kLanding;
  const Vector3d center = landing ? truth.platform_center_W : truth.opening_center_W;
  Vector3d noise(params_.sigma_xy_m * n01(rng_), params_.sigma_xy_m * n01(rng_),
                 params_.sigma_z_m * n01(rng_));
  if (!landing) {
    // For a wall the "lateral" plane is the wall's; the depth along the normal is the poorest.
    const Vector3d n = truth.wall_normal_W.normalized();
    const Vector3d t = Vector3d::UnitZ().cross(n).normalized();
    noise = t * params_.sigma_xy_m * n01(rng_) +
            Vector3d::UnitZ() * params_.sigma_xy_m * n01(rng_) + n * params_.sigma_z_m * n01(rng_);
  }
  if (u01(rng_) < params_.outlier_prob) {
    Vector3d dir(n01(rng_), n01(rng_), n01(rng_));
    dir.normalize();
    const double r =
        params_.outlier_min_m + (params_.outlier_max_m - params_.outlier_min_m) * u01(rng_);
    noise = dir * r;
    ++n_outliers_;
  }
  m.p_W_target = center + noise;
  if (landing) {
    m.n_W = Vector3d::UnitZ();
    const double a = truth.platform_size_m.x(), b = truth.platform_size_m.y();
    m.size_m = Vector2d(std::max(a, b) + params_.size_sigma_m * n01(rng_),
                        std::min(a, b) + params_.size_sigma_m * n01(rng_));
    // The long axis (size x lies along the platform's yaw), in (-pi/2, pi/2] as vision gives it.
    double yaw = truth.platform_yaw_rad + (a >= b ? 0.0 : M_PI / 2);
    yaw = wrap_angle(yaw);
    if (yaw <= -M_PI / 2) yaw += M_PI;
    if (yaw > M_PI / 2) yaw -= M_PI;
    m.yaw_rad = yaw;
  } else {
    m.n_W = truth.wall_normal_W.normalized();
    m.size_m = truth.opening_size_m +
               Vector2d(params_.size_sigma_m * n01(rng_), params_.size_sigma_m * n01(rng_));
  }
  return m;
}

}  // namespace alight::autonomy::test

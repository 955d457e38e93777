#include "synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "common/geometry.hpp"

namespace alight::estimator::test {

namespace {

double smoothstep5(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
}

Vector3d climb(double t, double rest_z_m, double height_m, double rest_s, double climb_s) {
  return Vector3d(0.0, 0.0, rest_z_m + (height_m - rest_z_m) * smoothstep5((t - rest_s) / climb_s));
}

/// Distance along a leg of length L at time tau: 1 s smooth ramps (cubic velocity), cruise.
double leg_distance(double tau, double L, double V) {
  constexpr double Ta = 1.0;
  const double Tc = (L - V * Ta) / V;
  if (tau <= 0) return 0.0;
  if (tau < Ta) {
    const double u = tau / Ta;
    return V * Ta * (u * u * u - 0.5 * u * u * u * u);
  }
  if (tau < Ta + Tc) return 0.5 * V * Ta + V * (tau - Ta);
  if (tau < 2 * Ta + Tc) {
    const double w = (2 * Ta + Tc - tau) / Ta;
    return L - V * Ta * (w * w * w - 0.5 * w * w * w * w);
  }
  return L;
}

double leg_duration(double L, double V) { return 2.0 + (L - V) / V + 1.0; }

struct Kin {
  Vector3d p, v, a;
  Matrix3d R;
};

Kin kinematics(const Trajectory& traj, double t, double g) {
  constexpr double h = 1e-3;
  Kin k;
  const Vector3d p0 = traj.position(t - h), p1 = traj.position(t), p2 = traj.position(t + h);
  k.p = p1;
  k.v = (p2 - p0) / (2 * h);
  k.a = (p2 - 2 * p1 + p0) / (h * h);
  // A quadrotor's body z is its thrust direction; the heading sets the rest (flatness).
  const Vector3d b3 = (k.a + Vector3d(0, 0, g)).normalized();
  const double yaw = traj.yaw(t);
  const Vector3d xc(std::cos(yaw), std::sin(yaw), 0.0);
  const Vector3d b2 = b3.cross(xc).normalized();
  const Vector3d b1 = b2.cross(b3);
  k.R.col(0) = b1;
  k.R.col(1) = b2;
  k.R.col(2) = b3;
  return k;
}

Vector3d log_so3(const Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

double terrain_at(const std::optional<Platform>& pl, double x, double y) {
  if (pl && x >= pl->x0 && x <= pl->x1 && y >= pl->y0 && y <= pl->y1) return pl->height_m;
  return 0.0;
}

int64_t utime_of(double t_s) { return kStartUtime + static_cast<int64_t>(std::llround(t_s * 1e6)); }

}  // namespace

Trajectory hover(double rest_z_m, double height_m, double rest_s, double climb_s) {
  return {[=](double t) { return climb(t, rest_z_m, height_m, rest_s, climb_s); },
          [](double) { return 0.0; }};
}

Trajectory figure(double rest_z_m, double height_m, double flight_start_s) {
  auto env = [=](double t) { return smoothstep5((t - flight_start_s) / 2.0); };
  return {[=](double t) {
            const double tau = std::max(0.0, t - flight_start_s);
            const double e = env(t);
            return Vector3d(climb(t, rest_z_m, height_m, 1.5, 3.0) +
                            e * Vector3d(1.5 * std::sin(0.5 * tau), 1.0 * std::sin(0.8 * tau),
                                         0.3 * std::sin(0.4 * tau)));
          },
          [=](double t) {
            const double tau = std::max(0.0, t - flight_start_s);
            return env(t) * 0.5 * std::sin(0.3 * tau);
          }};
}

double square_duration_s(double side_m, double speed_mps) {
  return 4.0 * leg_duration(side_m, speed_mps);
}

Trajectory square(double rest_z_m, double height_m, double flight_start_s, double side_m,
                  double speed_mps) {
  return {[=](double t) {
            Vector3d p = climb(t, rest_z_m, height_m, 1.5, 3.0);
            const double T = leg_duration(side_m, speed_mps);
            const Vector3d dirs[4] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
            double tau = t - flight_start_s;
            for (int i = 0; i < 4 && tau > 0; ++i, tau -= T)
              p += dirs[i] * leg_distance(std::min(tau, T), side_m, speed_mps);
            return p;
          },
          [](double) { return 0.0; }};
}

Flight simulate(const Trajectory& traj, double duration_s, const SensorConfig& cfg,
                const EstimatorParams& params, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0.0, 1.0);
  auto randn3 = [&] { return Vector3d(N(rng), N(rng), N(rng)); };
  const double g = params.gravity_mps2;
  const bool noisy = cfg.noise;
  Flight f;
  f.accel_bias_B =
      noisy ? Vector3d(randn3() * params.init.sigma_accel_bias_mps2) : Vector3d::Zero();
  f.gyro_bias_B = noisy ? Vector3d(randn3() * 0.005) : Vector3d::Zero();

  // IMU: the mean specific force and the exact rotation increment over each interval.
  {
    const double dt = 1.0 / cfg.imu_rate_hz;
    Vector3d ba = f.accel_bias_B, bg = f.gyro_bias_B;
    const int n = static_cast<int>(std::floor(duration_s * cfg.imu_rate_hz));
    for (int k = 0; k <= n; ++k) {
      const double t1 = cfg.start_s + k * dt, t0 = t1 - dt;
      const Kin k0 = kinematics(traj, t0, g), k1 = kinematics(traj, t1, g);
      Vector3d f_mean = Vector3d::Zero();
      constexpr int kSub = 4;
      for (int j = 0; j < kSub; ++j) {
        const Kin ks = kinematics(traj, t0 + (j + 0.5) * dt / kSub, g);
        f_mean += ks.R.transpose() * (ks.a + Vector3d(0, 0, g)) / kSub;
      }
      Input in;
      in.kind = Kind::kImu;
      in.imu.utime = in.arrival_utime = utime_of(t1);
      in.imu.accel_B = f_mean + ba;
      in.imu.gyro_B = log_so3(k0.R.transpose() * k1.R) / dt + bg;
      if (noisy) {
        in.imu.accel_B += randn3() * params.imu.accel_noise_density / std::sqrt(dt);
        in.imu.gyro_B += randn3() * params.imu.gyro_noise_density / std::sqrt(dt);
        ba += randn3() * params.imu.accel_bias_rw * std::sqrt(dt);
        bg += randn3() * params.imu.gyro_bias_rw * std::sqrt(dt);
      }
      f.inputs.push_back(in);
      f.truth.push_back({in.imu.utime, k1.p, k1.v, Quaterniond(k1.R).normalized()});
    }
  }

  if (cfg.range) {
    const auto& rp = params.range;
    const Vector3d d_B = rp.d_B.normalized();
    for (double t = cfg.start_s + 0.0013; t <= cfg.start_s + duration_s;
         t += 1.0 / cfg.range_rate_hz) {
      const Kin k = kinematics(traj, t, g);
      const Vector3d p_R = k.p + k.R * rp.t_B_R_m;
      const Vector3d d_W = k.R * d_B;
      double lambda = p_R.z() / -d_W.z();
      const Vector3d hit = p_R + lambda * d_W;
      const double h = terrain_at(cfg.platform, hit.x(), hit.y());
      if (h != 0.0) lambda = (p_R.z() - h) / -d_W.z();
      Input in;
      in.kind = Kind::kRange;
      in.range.utime = utime_of(t);
      in.range.range_m = lambda + (noisy ? N(rng) * (rp.sigma_m + rp.sigma_rel * lambda) : 0.0);
      in.range.valid = lambda >= rp.min_range_m && lambda <= rp.max_range_m;
      in.arrival_utime = in.range.utime + static_cast<int64_t>(cfg.range_delay_s * 1e6);
      f.inputs.push_back(in);
    }
  }

  if (cfg.baro) {
    const auto& bp = params.baro;
    const double dt = 1.0 / cfg.baro_rate_hz;
    double offset = cfg.baro_offset0_m;
    for (double t = cfg.start_s + 0.0027; t <= cfg.start_s + duration_s; t += dt) {
      const Kin k = kinematics(traj, t, g);
      Input in;
      in.kind = Kind::kBaro;
      in.baro.utime = utime_of(t);
      in.baro.pressure_pa = isa_pressure_pa(k.p.z() + offset + (noisy ? N(rng) * bp.sigma_m : 0.0));
      in.arrival_utime = in.baro.utime + static_cast<int64_t>(cfg.baro_delay_s * 1e6);
      f.inputs.push_back(in);
      if (noisy) offset += N(rng) * bp.offset_rw * std::sqrt(dt);
    }
  }

  if (cfg.flow) {
    const auto& fp = params.flow;
    const Matrix3d R_BC = fp.R_BC();
    const double dt = 1.0 / cfg.flow_rate_hz;
    double t0 = cfg.start_s + 0.0021;
    for (double t1 = t0 + dt; t1 <= cfg.start_s + duration_s; t0 = t1, t1 += dt) {
      const Kin k0 = kinematics(traj, t0, g), k1 = kinematics(traj, t1, g);
      const Vector3d p_C1 = k0.p + k0.R * fp.t_B_C_m, p_C2 = k1.p + k1.R * fp.t_B_C_m;
      const double d1 =
          p_C1.z() - (cfg.flow_sees_floor ? 0.0 : terrain_at(cfg.platform, p_C1.x(), p_C1.y()));
      Input in;
      in.kind = Kind::kFlow;
      in.flow.utime_from = utime_of(t0);
      in.flow.utime_to = utime_of(t1);
      in.flow.t_over_d_C1 = R_BC.transpose() * k0.R.transpose() *
                            (p_C2 - p_C1 + cfg.flow_velocity_error_W_mps * dt) / d1;
      if (noisy) {  // the noise the filter assumes (FlowParams::sigma_floor_mps)
        const double floor = fp.sigma_floor_mps * dt / d1;
        in.flow.t_over_d_C1 +=
            std::sqrt(fp.cov_scale * cfg.flow_sigma * cfg.flow_sigma + floor * floor) * randn3();
      }
      in.flow.cov = cfg.flow_sigma * cfg.flow_sigma * Matrix3d::Identity();
      in.flow.inliers = 100;
      in.arrival_utime = in.flow.utime_to + static_cast<int64_t>(cfg.flow_delay_s * 1e6);
      f.inputs.push_back(in);
    }
  }

  std::stable_sort(f.inputs.begin(), f.inputs.end(), [](const Input& a, const Input& b) {
    if (a.arrival_utime != b.arrival_utime) return a.arrival_utime < b.arrival_utime;
    return static_cast<int>(a.kind) < static_cast<int>(b.kind);
  });
  return f;
}

Outcome feed(Estimator& est, const Input& in) {
  switch (in.kind) {
    case Kind::kImu:
      return est.add_imu(in.imu);
    case Kind::kRange:
      return est.add_range(in.range);
    case Kind::kBaro:
      return est.add_baro(in.baro);
    case Kind::kFlow:
      return est.add_flow(in.flow);
  }
  return Outcome::kAbsurd;
}

Vector3d attitude_error(const Quaterniond& q_est, const Quaterniond& q_true) {
  Quaterniond dq = q_est.conjugate() * q_true;
  if (dq.w() < 0) dq.coeffs() = -dq.coeffs();
  const Eigen::AngleAxisd aa(dq);
  return aa.angle() * aa.axis();
}

}  // namespace alight::estimator::test

#include "sim/platform_motion.hpp"

#include <cmath>
#include <random>

namespace alight::sim {

namespace {
constexpr double kDeg = M_PI / 180.0;

// Arc of radius r turning by `sign` (+1 left) from (0, 0) heading along x, after length u.
PlatformMotion::PathPoint arc(double r, double u, double sign) {
  const double phi = u / r;
  PlatformMotion::PathPoint p;
  p.offset = Vector2d(r * std::sin(phi), sign * r * (1.0 - std::cos(phi)));
  p.heading_rad = sign * phi;
  p.curvature = sign / r;
  return p;
}
// A straight of length L entered and left at v_in, at most v_max between, speeding up and
// slowing at a: the distance and speed `tau` seconds after entering it (0 <= tau < duration()).
struct Straight {
  double v_in, v_peak, a, t_ramp, t_cruise;
  Straight(double L, double v_in_, double v_max, double a_) : v_in(v_in_), a(a_) {
    const double ramp = (v_max * v_max - v_in * v_in) / (2.0 * a);
    v_peak = 2.0 * ramp <= L ? v_max : std::sqrt(v_in * v_in + a * L);
    t_ramp = (v_peak - v_in) / a;
    t_cruise = 2.0 * ramp <= L ? (L - 2.0 * ramp) / v_max : 0.0;
  }
  double duration() const { return 2.0 * t_ramp + t_cruise; }
  PlatformMotion::Travel at(double tau) const {
    const double up = (v_peak * v_peak - v_in * v_in) / (2.0 * a);
    if (tau < t_ramp) return {v_in * tau + 0.5 * a * tau * tau, v_in + a * tau};
    if (tau < t_ramp + t_cruise) return {up + v_peak * (tau - t_ramp), v_peak};
    const double d = tau - t_ramp - t_cruise;
    return {up + v_peak * t_cruise + v_peak * d - 0.5 * a * d * d, v_peak - a * d};
  }
};
}  // namespace

double PlatformMotion::Sine::value(double t) const {
  return amplitude * std::sin(2.0 * M_PI * frequency_hz * t + phase_rad);
}

double PlatformMotion::Sine::rate(double t) const {
  const double w = 2.0 * M_PI * frequency_hz;
  return amplitude * w * std::cos(w * t + phase_rad);
}

PlatformMotion::PlatformMotion(const PlatformMotionParams& params, const Vector3d& top0_W,
                               double yaw0_rad, uint64_t seed)
    : params_(params), top0_W_(top0_W), yaw0_rad_(yaw0_rad) {
  const PlatformMotionParams& p = params_;
  heave_ = {p.heave_amplitude_m, p.heave_frequency_hz, p.heave_phase_deg * kDeg};
  roll_ = {p.roll_amplitude_deg * kDeg, p.roll_frequency_hz, p.roll_phase_deg * kDeg};
  pitch_ = {p.pitch_amplitude_deg * kDeg, p.pitch_frequency_hz, p.pitch_phase_deg * kDeg};
  // Each motion draws its components from the same stream in a fixed order (heave, roll, pitch),
  // whether or not its bound is 0, so changing one bound leaves the others' draws as they were.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> band(p.sea_band_hz.x(), p.sea_band_hz.y());
  std::uniform_real_distribution<double> turn(0.0, 2.0 * M_PI);
  const double bounds[3] = {p.sea_heave_m, p.sea_roll_deg * kDeg, p.sea_pitch_deg * kDeg};
  for (int m = 0; m < 3; ++m) {
    for (int k = 0; k < p.sea_components; ++k) {
      const double f = band(rng), phase = turn(rng);
      if (bounds[m] > 0) sea_[m].push_back({bounds[m] / p.sea_components, f, phase});
    }
  }
}

PlatformMotion::PathPoint PlatformMotion::path_point(const PlatformMotionParams& p, double s) {
  PathPoint out;
  if (p.path == "none") return out;
  const double r = p.path_radius_m;
  if (p.path == "circle") return arc(r, std::fmod(s, 2.0 * M_PI * r), 1.0);
  if (p.path == "figure_eight") {
    // Two circles touching at the start, both tangent to the start direction there: a full left
    // circle, then a full right one; the heading is continuous, the curvature changes sign.
    const double lobe = 2.0 * M_PI * r;
    const double u = std::fmod(s, 2.0 * lobe);
    return u < lobe ? arc(r, u, 1.0) : arc(r, u - lobe, -1.0);
  }
  // line: a stadium, straight out, half a turn left, straight back, half a turn left.
  const double L = p.path_length_m, half = M_PI * r;
  const double u = std::fmod(s, 2.0 * L + 2.0 * half);
  if (u < L) {
    out.offset = Vector2d(u, 0.0);
  } else if (u < L + half) {
    out = arc(r, u - L, 1.0);
    out.offset.x() += L;
  } else if (u < 2.0 * L + half) {
    out.offset = Vector2d(L - (u - L - half), 2.0 * r);
    out.heading_rad = M_PI;
  } else {
    const PathPoint a = arc(r, u - 2.0 * L - half, 1.0);
    out.offset = Vector2d(-a.offset.x(), 2.0 * r - a.offset.y());
    out.heading_rad = M_PI + a.heading_rad;
    out.curvature = a.curvature;
  }
  return out;
}

PlatformMotion::Travel PlatformMotion::travel(const PlatformMotionParams& p, double t) {
  if (p.path == "none" || p.speed_mps <= 0) return {};
  const double v_turn = p.turn_speed_mps();
  // Only the stadium has straights to speed up on; the other paths are turns throughout.
  if (p.path != "line" || v_turn >= p.speed_mps) return {v_turn * t, v_turn};
  const double L = p.path_length_m, half = M_PI * p.path_radius_m;
  const Straight straight(L, v_turn, p.speed_mps, PlatformMotionParams::kTurnAccelMps2);
  const double t_straight = straight.duration(), t_half = half / v_turn;
  const double period = 2.0 * (t_straight + t_half);
  const double laps = std::floor(t / period);
  double tau = t - laps * period;
  double s = laps * (2.0 * L + 2.0 * half);
  for (int leg = 0; leg < 2; ++leg) {  // out and back: a straight, then half a turn
    if (tau < t_straight) {
      const Travel in = straight.at(tau);
      return {s + in.s_m, in.speed_mps};
    }
    tau -= t_straight;
    s += L;
    if (tau < t_half || leg == 1) return {s + v_turn * std::min(tau, t_half), v_turn};
    tau -= t_half;
    s += half;
  }
  return {s, v_turn};  // not reached: the second leg's turn returns
}

PlatformPose PlatformMotion::at(double t) const {
  const PlatformMotionParams& p = params_;
  const Travel along = travel(p, t);
  const double speed = along.speed_mps;
  const PathPoint pp = path_point(p, along.s_m);
  const double h = p.path_heading_deg * kDeg;
  const Eigen::Matrix2d R_h = Eigen::Rotation2Dd(h).toRotationMatrix();

  double heave = heave_.value(t), heave_rate = heave_.rate(t);
  double roll = roll_.value(t), roll_rate = roll_.rate(t);
  double pitch = pitch_.value(t), pitch_rate = pitch_.rate(t);
  for (const Sine& c : sea_[0]) heave += c.value(t), heave_rate += c.rate(t);
  for (const Sine& c : sea_[1]) roll += c.value(t), roll_rate += c.rate(t);
  for (const Sine& c : sea_[2]) pitch += c.value(t), pitch_rate += c.rate(t);

  double yaw = yaw0_rad_ + p.yaw_rate_dps * kDeg * t;
  double yaw_rate = p.yaw_rate_dps * kDeg;
  if (p.heading_follows_path) {
    yaw += pp.heading_rad;
    yaw_rate += pp.curvature * speed;
  }

  PlatformPose out;
  const Vector2d xy = top0_W_.head<2>() + R_h * pp.offset + p.velocity_mps * t;
  out.top_center_W = Vector3d(xy.x(), xy.y(), top0_W_.z() + heave);
  const Vector2d v_path =
      speed * (R_h * Vector2d(std::cos(pp.heading_rad), std::sin(pp.heading_rad)));
  out.v_W = Vector3d(v_path.x() + p.velocity_mps.x(), v_path.y() + p.velocity_mps.y(), heave_rate);
  out.roll_rad = roll;
  out.pitch_rad = pitch;
  out.yaw_rad = wrap_angle(yaw);
  out.R_WO = rotation_from_rpy(roll, pitch, yaw);
  // Z-Y-X rates to the angular velocity: yaw about world z, pitch about the once-turned y, roll
  // about the body x.
  const Matrix3d Rz = rotation_from_rpy(0, 0, yaw), Rzy = rotation_from_rpy(0, pitch, yaw);
  out.omega_W = yaw_rate * Vector3d::UnitZ() + pitch_rate * Rz.col(1) + roll_rate * Rzy.col(0);
  return out;
}

}  // namespace alight::sim

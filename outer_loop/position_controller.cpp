#include "outer_loop/position_controller.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace alight::outer_loop {

const char* mode_name(Mode mode) {
  switch (mode) {
    case Mode::kNormal: return "NORMAL";
    case Mode::kHoldLevel: return "HOLD_LEVEL";
    case Mode::kFailsafeDescent: return "FAILSAFE_DESCENT";
    case Mode::kHoldPosition: return "HOLD_POSITION";
    case Mode::kSetpointLostDescent: return "SETPOINT_LOST_DESCENT";
    case Mode::kDisarmed: return "DISARMED";
  }
  return "?";
}

namespace {
constexpr double kDegToRad = M_PI / 180.0;

double age_s(const std::optional<int64_t>& utime, int64_t now_utime) {
  if (!utime) return std::numeric_limits<double>::infinity();
  return static_cast<double>(now_utime - *utime) * 1e-6;
}

// Caps the norm of v at limit (anti-windup of a vector integrator).
void clamp_norm(Eigen::Ref<Eigen::VectorXd> v, double limit) {
  const double n = v.norm();
  if (n > limit && n > 0.0) v *= limit / n;
}
}  // namespace

PositionController::PositionController(const OuterLoopParams& params) : params_(params) {
  params_.validate();
}

double PositionController::hover_thrust_N() const {
  // The altitude integrator has learnt the difference between nominal and true hover thrust.
  return params_.mass_kg * (params_.gravity_mps2 + integral_mps2_.z());
}

AttitudeCommand PositionController::level(double thrust_N) const {
  AttitudeCommand c;
  c.thrust_N = std::clamp(thrust_N, params_.thrust_min_N, params_.thrust_max_N);
  c.armed = true;
  return c;
}

AttitudeCommand PositionController::disarmed(const char* reason) {
  integral_mps2_.setZero();
  holding_ = false;
  pose_lost_since_.reset();
  setpoint_lost_since_.reset();
  still_since_.reset();
  AttitudeCommand c;
  c.armed = false;
  c.mode = Mode::kDisarmed;
  c.reason = reason;
  return c;
}

AttitudeCommand PositionController::track(const Vector3d& p_sp, const Vector3d& v_sp,
                                          double yaw_sp, const PoseSample& pose, double dt_s,
                                          bool integrate) {
  const auto& P = params_;
  const Vector3d e_p = p_sp - pose.p_W_B;
  const Vector3d e_v = v_sp - pose.v_W_B;

  // Conditional integration: near the setpoint, or while not moving (a steady offset, e.g. a
  // wrong mass, larger than the zone), so that flying a large step does not wind it up.
  const bool still = pose.v_W_B.norm() < P.i_still_mps;
  if (integrate && (still || e_p.head<2>().norm() < P.i_zone_m)) {
    integral_mps2_.head<2>() += P.ki_xy_per_s3 * e_p.head<2>() * dt_s;
    clamp_norm(integral_mps2_.head<2>(), P.i_limit_xy_mps2);
  }
  if (integrate && (still || std::abs(e_p.z()) < P.i_zone_m)) {
    integral_mps2_.z() = std::clamp(integral_mps2_.z() + P.ki_z_per_s3 * e_p.z() * dt_s,
                                    -P.i_limit_z_mps2, P.i_limit_z_mps2);
  }

  Vector2d a_xy = P.kp_xy_per_s2 * e_p.head<2>() + P.kd_xy_per_s * e_v.head<2>() +
                  integral_mps2_.head<2>();
  const double a_z = std::clamp(P.kp_z_per_s2 * e_p.z() + P.kd_z_per_s * e_v.z() +
                                    integral_mps2_.z(),
                                -P.max_accel_z_mps2, P.max_accel_z_mps2);
  const double f_z = P.gravity_mps2 + a_z;  // > 0 since max_accel_z < g
  const double max_tilt_rad = P.max_tilt_deg * kDegToRad;
  const double a_xy_max = f_z * std::tan(max_tilt_rad);
  if (a_xy.norm() > a_xy_max) a_xy *= a_xy_max / a_xy.norm();

  // Desired specific force in the heading frame (world rotated by the current yaw).
  const double yaw = yaw_of(pose.q_WB.toRotationMatrix());
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double f_x = c * a_xy.x() + s * a_xy.y();
  const double f_y = -s * a_xy.x() + c * a_xy.y();
  // Body z of Rz(yaw) Ry(pitch) Rx(roll) in the heading frame is
  // [cos(roll) sin(pitch), -sin(roll), cos(roll) cos(pitch)]: align it with f.
  AttitudeCommand cmd;
  cmd.pitch_rad = std::clamp(std::atan2(f_x, f_z), -max_tilt_rad, max_tilt_rad);
  cmd.roll_rad = std::clamp(std::atan2(-f_y, std::hypot(f_x, f_z)), -max_tilt_rad, max_tilt_rad);
  const double f_norm = std::sqrt(f_x * f_x + f_y * f_y + f_z * f_z);
  cmd.thrust_N = std::clamp(P.mass_kg * f_norm, P.thrust_min_N, P.thrust_max_N);
  const double max_rate = P.max_yaw_rate_dps * kDegToRad;
  cmd.yaw_rate_radps =
      std::clamp(P.yaw_kp_per_s * wrap_angle(yaw_sp - yaw), -max_rate, max_rate);
  cmd.armed = true;
  cmd.mode = Mode::kNormal;
  return cmd;
}

AttitudeCommand PositionController::update(const std::optional<PositionSetpoint>& setpoint,
                                           const std::optional<PoseSample>& pose,
                                           int64_t now_utime) {
  const auto& P = params_;
  double dt_s = 0.0;
  if (last_utime_) {
    dt_s = std::clamp(static_cast<double>(now_utime - *last_utime_) * 1e-6, 0.0, P.max_dt_s);
  }
  last_utime_ = std::max(now_utime, last_utime_.value_or(now_utime));

  const auto finish = [&](AttitudeCommand c) {
    c.utime = now_utime;
    return c;
  };

  if (!setpoint) return finish(disarmed("no setpoint received yet"));
  if (!setpoint->motors_on) {
    disarm_latched_ = false;  // autonomy acknowledged: the next motors-on may arm again
    return finish(disarmed("setpoint: motors off"));
  }
  if (disarm_latched_) {
    return finish(disarmed("failsafe disarmed; waiting for autonomy to send motors off"));
  }
  if (!pose) return finish(disarmed("no pose received yet: refusing to arm"));

  const double pose_age_s = age_s(pose->utime, now_utime);
  const double sp_age_s = age_s(setpoint->utime, now_utime);

  if (pose_age_s > P.pose_lost_s) {
    if (!pose_lost_since_) pose_lost_since_ = now_utime;
    const double t_s = age_s(*pose_lost_since_, now_utime);
    if (t_s > P.failsafe_disarm_after_s) {
      disarm_latched_ = true;
      return finish(disarmed("pose lost: failsafe descent timed out, disarmed"));
    }
    // Accelerate down at a_fs until the descent speed is reached, then hold that speed against
    // the expected drag. Without a velocity measurement this is open loop: a drag smaller than
    // drag_per_s lets it speed up slowly, a larger one slows it.
    const double accel_time_s = P.failsafe_descent_mps / P.failsafe_descent_accel_mps2;
    const double a_z = t_s < accel_time_s ? -P.failsafe_descent_accel_mps2
                                          : -P.drag_per_s * P.failsafe_descent_mps;
    auto c = level(P.mass_kg * (P.gravity_mps2 + integral_mps2_.z() + a_z));
    c.mode = Mode::kFailsafeDescent;
    c.reason = "pose lost: open-loop slow descent";
    return finish(c);
  }
  pose_lost_since_.reset();
  if (pose_age_s > P.pose_stale_s) {
    auto c = level(hover_thrust_N());
    c.mode = Mode::kHoldLevel;
    c.reason = "pose stale: level, hover thrust";
    return finish(c);
  }

  if (setpoint->idle) {
    integral_mps2_.setZero();
    holding_ = false;
    auto c = level(P.thrust_min_N);
    c.mode = Mode::kNormal;
    c.reason = "idle on the ground";
    return finish(c);
  }

  if (sp_age_s <= P.setpoint_stale_s) {
    holding_ = false;
    setpoint_lost_since_.reset();
    still_since_.reset();
    auto c = track(setpoint->p_W, setpoint->v_W, setpoint->yaw_rad, *pose, dt_s, true);
    c.reason = "tracking";
    return finish(c);
  }

  if (!holding_) {
    holding_ = true;
    hold_p_W_ = pose->p_W_B;
    hold_yaw_rad_ = yaw_of(pose->q_WB.toRotationMatrix());
  }
  if (sp_age_s <= P.setpoint_lost_s) {
    auto c = track(hold_p_W_, Vector3d::Zero(), hold_yaw_rad_, *pose, dt_s, false);
    c.mode = Mode::kHoldPosition;
    c.reason = "setpoint stale: holding position";
    return finish(c);
  }

  if (!setpoint_lost_since_) {
    setpoint_lost_since_ = now_utime;
    lost_descent_z0_m_ = pose->p_W_B.z();
  }
  const double t_s = age_s(*setpoint_lost_since_, now_utime);
  const Vector3d v_sp(0, 0, -P.setpoint_lost_descent_mps);
  Vector3d p_sp = hold_p_W_;
  p_sp.z() = lost_descent_z0_m_ - P.setpoint_lost_descent_mps * t_s;
  // On the ground: commanded well below the vehicle, yet it does not move down.
  const bool blocked = p_sp.z() < pose->p_W_B.z() - 0.2 && std::abs(pose->v_W_B.z()) < 0.05;
  if (!blocked) {
    still_since_.reset();
  } else if (!still_since_) {
    still_since_ = now_utime;
  } else if (age_s(*still_since_, now_utime) > P.landed_still_s) {
    disarm_latched_ = true;
    return finish(disarmed("setpoint lost: descended to the ground, disarmed"));
  }
  auto c = track(p_sp, v_sp, hold_yaw_rad_, *pose, dt_s, false);
  c.mode = Mode::kSetpointLostDescent;
  c.reason = "setpoint lost: slow descent";
  return finish(c);
}

}  // namespace alight::outer_loop

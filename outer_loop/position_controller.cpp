#include "outer_loop/position_controller.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace alight::outer_loop {

const char* mode_name(Mode mode) {
  switch (mode) {
    case Mode::kNormal:
      return "NORMAL";
    case Mode::kHoldLevel:
      return "HOLD_LEVEL";
    case Mode::kFailsafeDescent:
      return "FAILSAFE_DESCENT";
    case Mode::kHoldPosition:
      return "HOLD_POSITION";
    case Mode::kSetpointLostDescent:
      return "SETPOINT_LOST_DESCENT";
    case Mode::kDisarmed:
      return "DISARMED";
    case Mode::kFailsafeLand:
      return "FAILSAFE_LAND";
  }
  return "?";
}

namespace {
constexpr double kDegToRad = M_PI / 180.0;
/// Risen this far above the height it rested at since arming, the vehicle flies: well above
/// motion capture's noise (sub-millimetre) and a landing gear's settling, well below a take-off's
/// first second.
constexpr double kLiftOffM = 0.05;
/// Moving vertically faster than this, the vehicle is not held by the ground either (motion
/// capture's velocity noise is millimetres per second).
constexpr double kAirborneSpeedMps = 0.1;

double age_s(const std::optional<int64_t>& utime, int64_t now_utime) {
  if (!utime) return std::numeric_limits<double>::infinity();
  return static_cast<double>(now_utime - *utime) * 1e-6;
}

// Caps the norm of v at limit (anti-windup of a vector integrator).
void clamp_norm(Eigen::Ref<Eigen::VectorXd> v, double limit) {
  const double n = v.norm();
  if (n > limit && n > 0.0) v *= limit / n;
}

bool all_finite(const PositionSetpoint& sp) {
  return sp.p_W.allFinite() && sp.v_W.allFinite() && sp.a_W.allFinite() &&
         std::isfinite(sp.yaw_rad) && std::isfinite(sp.yaw_rate_radps);
}

bool all_finite(const PoseSample& pose) {
  return pose.p_W_B.allFinite() && pose.v_W_B.allFinite() && pose.q_WB.coeffs().allFinite() &&
         pose.omega_B.allFinite() && std::abs(pose.q_WB.norm() - 1.0) <= 0.01;
}

bool all_finite(const AttitudeCommand& c) {
  return std::isfinite(c.roll_rad) && std::isfinite(c.pitch_rad) &&
         std::isfinite(c.yaw_rate_radps) && std::isfinite(c.thrust_N);
}
}  // namespace

PositionController::PositionController(const OuterLoopParams& params,
                                       const PersistentState& restored)
    : params_(params),
      disarm_latched_(restored.disarm_latched),
      armed_(restored.armed),
      lifted_off_(restored.armed) {
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
  landing_since_.reset();
  land_since_.reset();
  landed_ = false;
  last_demand_z_mps2_ = 0.0;
  pose_lost_since_.reset();
  setpoint_lost_since_.reset();
  still_since_.reset();
  failsafe_reason_ = nullptr;
  failsafe_since_.reset();
  AttitudeCommand c;
  c.armed = false;
  c.mode = Mode::kDisarmed;
  c.reason = reason;
  return c;
}

double fence_stopping_speed(double distance_m, double brake_mps2, double lag_s) {
  if (!(distance_m > 0.0)) return 0.0;
  return brake_mps2 * (-lag_s + std::sqrt(lag_s * lag_s + 2.0 * distance_m / brake_mps2));
}

AttitudeCommand PositionController::track(const Vector3d& p_sp, const Vector3d& v_sp,
                                          const Vector3d& a_sp, double yaw_sp,
                                          const PoseSample& pose, double dt_s, bool integrate,
                                          bool precise, double yaw_rate_ff_radps) {
  const auto& P = params_;
  const double kp_xy = precise ? P.precise_kp_xy_per_s2 : P.kp_xy_per_s2;
  const double kd_xy = precise ? P.precise_kd_xy_per_s : P.kd_xy_per_s;
  const double ki_xy = precise ? P.precise_ki_xy_per_s3 : P.ki_xy_per_s3;
  // Speed limits: at steady state the loop flies v = kp e / kd, so capping the error caps the
  // speed it asks for relative to the setpoint; the setpoint's own velocity (a moving
  // platform's, fed forward) has a bound of its own, what the vehicle follows.
  Vector3d e_p = p_sp - pose.p_W_B;
  clamp_norm(e_p.head<2>(), P.max_speed_xy_mps * kd_xy / kp_xy);
  const double e_z_max = P.max_speed_z_mps * P.kd_z_per_s / P.kp_z_per_s2;
  e_p.z() = std::clamp(e_p.z(), -e_z_max, e_z_max);
  Vector3d v_ff = v_sp;
  clamp_norm(v_ff.head<2>(), P.max_feedforward_xy_mps);
  v_ff.z() = std::clamp(v_ff.z(), -P.max_speed_z_mps, P.max_speed_z_mps);
  // Towards a wall of the fence, the velocity the loop asks for (v_ff + kp e / kd: it demands
  // kd (that - v)) is one it stops from before the wall's inset, and beyond the inset one that
  // brings it back as the position loop would; on such an axis it asks for exactly that, with no
  // position error and no feed-forward acceleration.
  Vector3d a_ff = a_sp;
  const double brake_mps2 =
      kFenceBrakeShare * P.gravity_mps2 * std::tan(P.max_tilt_deg * kDegToRad);
  for (int i = 0; i < 2; ++i) {
    const double v_ask = v_ff[i] + kp_xy / kd_xy * e_p[i];
    const double to_wall_m = v_ask > 0 ? P.geofence_max_W_m[i] - kFenceInsetM - pose.p_W_B[i]
                                       : pose.p_W_B[i] - (P.geofence_min_W_m[i] + kFenceInsetM);
    const double v_max = to_wall_m > 0 ? fence_stopping_speed(to_wall_m, brake_mps2, 1.0 / kd_xy)
                                       : kp_xy / kd_xy * to_wall_m;
    if (std::abs(v_ask) > v_max) {
      v_ff[i] = v_ask > 0 ? v_max : -v_max;
      e_p[i] = 0.0;
      a_ff[i] = 0.0;
    }
  }
  const Vector3d e_v = v_ff - pose.v_W_B;

  // Conditional integration: near the setpoint, or while not moving (a steady offset, e.g. a
  // wrong mass, larger than the zone), so that flying a large step does not wind it up.
  const bool still = pose.v_W_B.norm() < P.i_still_mps;
  integrate = integrate && lifted_off_;
  if (integrate && (still || e_p.head<2>().norm() < P.i_zone_m)) {
    integral_mps2_.head<2>() += ki_xy * e_p.head<2>() * dt_s;
    clamp_norm(integral_mps2_.head<2>(), P.i_limit_xy_mps2);
  }
  if (integrate && (still || std::abs(e_p.z()) < P.i_zone_m)) {
    integral_mps2_.z() = std::clamp(integral_mps2_.z() + P.ki_z_per_s3 * e_p.z() * dt_s,
                                    -P.i_limit_z_mps2, P.i_limit_z_mps2);
  }

  // A moving setpoint's own acceleration (a platform's turn) fed forward: without it a PD loop
  // lags a turning setpoint by a / kp, and the integrator cannot learn a disturbance that turns
  // with it.
  Vector2d a_xy =
      kp_xy * e_p.head<2>() + kd_xy * e_v.head<2>() + integral_mps2_.head<2>() + a_ff.head<2>();
  last_demand_z_mps2_ = P.kp_z_per_s2 * e_p.z() + P.kd_z_per_s * e_v.z() + a_ff.z();
  const double a_z =
      std::clamp(last_demand_z_mps2_ + integral_mps2_.z(), -P.max_accel_z_mps2, P.max_accel_z_mps2);
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
  // The feed-forward of a turning heading: without it a P loop trails a ramp by rate / kp.
  cmd.yaw_rate_radps = std::clamp(P.yaw_kp_per_s * wrap_angle(yaw_sp - yaw) + yaw_rate_ff_radps,
                                  -max_rate, max_rate);
  cmd.armed = true;
  cmd.mode = Mode::kNormal;
  return cmd;
}

AttitudeCommand PositionController::update(const std::optional<PositionSetpoint>& setpoint_in,
                                           const std::optional<PoseSample>& pose_in,
                                           int64_t now_utime) {
  const auto& P = params_;
  double dt_s = 0.0;
  if (last_utime_) {
    dt_s = std::clamp(static_cast<double>(now_utime - *last_utime_) * 1e-6, 0.0, P.max_dt_s);
  }
  last_utime_ = now_utime;

  // A non-finite input is replaced by the last finite one (which then ages like a lost input).
  if (setpoint_in && all_finite(*setpoint_in)) last_good_setpoint_ = *setpoint_in;
  if (pose_in && all_finite(*pose_in)) last_good_pose_ = *pose_in;
  const std::optional<PositionSetpoint> setpoint =
      setpoint_in ? last_good_setpoint_ : std::optional<PositionSetpoint>{};
  const std::optional<PoseSample> pose = pose_in ? last_good_pose_ : std::optional<PoseSample>{};

  if (!started_ && setpoint && pose && age_s(pose->utime, now_utime) <= P.pose_stale_s &&
      age_s(setpoint->utime, now_utime) <= P.setpoint_stale_s) {
    started_ = true;
  }

  detect_lift_off(pose, now_utime);
  AttitudeCommand c = step(setpoint, pose, now_utime, dt_s);
  if (!integral_mps2_.allFinite()) integral_mps2_.setZero();
  if (c.armed && !all_finite(c)) {
    c = level(P.mass_kg * P.gravity_mps2);
    c.mode = Mode::kHoldLevel;
    c.reason = "non-finite command refused: level, hover thrust";
  }
  c.utime = now_utime;
  // Before the start nothing is published, so nothing was commanded: a restored "armed" stands.
  if (started_) armed_ = c.armed;
  return c;
}

void PositionController::detect_landing(const PoseSample& pose, int64_t now_utime) {
  const auto& P = params_;
  // The position loop pushes down, yet the vehicle does not move down: the ground holds it up.
  const bool held_up = armed_ && last_demand_z_mps2_ < -P.land_accel_mps2 &&
                       std::abs(pose.v_W_B.z()) < P.land_vz_mps;
  if (!held_up) {
    land_since_.reset();
    landed_ = false;
    return;
  }
  if (!land_since_) land_since_ = now_utime;
  landed_ = age_s(*land_since_, now_utime) >= P.land_detect_s;
}

void PositionController::detect_lift_off(const std::optional<PoseSample>& pose, int64_t now_utime) {
  if (!armed_) {  // the previous command: a disarmed vehicle rests wherever it is
    rest_z_m_.reset();
    lifted_off_ = false;
    return;
  }
  if (lifted_off_ || !pose || age_s(pose->utime, now_utime) > params_.pose_stale_s) return;
  const double z = pose->p_W_B.z();
  rest_z_m_ = rest_z_m_ ? std::min(*rest_z_m_, z) : z;
  lifted_off_ = z > *rest_z_m_ + kLiftOffM || std::abs(pose->v_W_B.z()) > kAirborneSpeedMps;
}

AttitudeCommand PositionController::land(const PoseSample& pose, int64_t now_utime, double dt_s) {
  const auto& P = params_;
  if (!landing_since_) {
    landing_since_ = now_utime;
    landing_p_W_ = pose.p_W_B;
    landing_yaw_rad_ = yaw_of(pose.q_WB.toRotationMatrix());
    // Autonomy's motors-off comes at the touch-down of its final descent, while the pose still
    // shows the descent (motion capture's velocity lags the impact). Braking to a slower descent
    // there lifts the vehicle off the top it has just touched, and it lands again elsewhere. So
    // the descent goes on at the speed autonomy last commanded (bounded); a motors-off in a hover
    // descends slowly.
    const double commanded_mps = last_motors_on_ ? -last_motors_on_->v_W.z() : 0.0;
    landing_descent_mps_ =
        std::clamp(commanded_mps, P.setpoint_lost_descent_mps,
                   std::max(P.setpoint_lost_descent_mps, P.land_max_descent_mps));
    // A touch-down on a moving platform: the vehicle goes on with the horizontal velocity autonomy
    // last fed forward (the platform's), or it is held to a world point while the top moves on
    // under it and drags it across the top until the land detector levels it.
    landing_v_xy_ = last_motors_on_ ? Vector2d(last_motors_on_->v_W.head<2>()) : Vector2d::Zero();
    clamp_norm(landing_v_xy_, P.max_feedforward_xy_mps);
    // Autonomy was leading a descent: its motors-off is an arrival (at the impact, or once it saw
    // the vehicle stopped on the ground).
    landing_arrived_ = commanded_mps > P.land_vz_mps;
    // Its altitude setpoint led the vehicle down, so the thrust was below hover at the impact:
    // taking the pose's altitude instead would raise the thrust as the gear meets the top. The
    // lead kept is bounded by the one that already saturates the vertical demand.
    if (last_motors_on_) {
      const double lead_max_m = P.max_accel_z_mps2 / P.kp_z_per_s2;
      landing_p_W_.z() =
          std::clamp(last_motors_on_->p_W.z(), pose.p_W_B.z() - lead_max_m, pose.p_W_B.z());
    }
  }
  landing_arrived_ = landing_arrived_ || pose.v_W_B.z() < -P.land_vz_mps;
  const double t_s = std::max(0.0, age_s(*landing_since_, now_utime));
  Vector3d p_sp = landing_p_W_;
  p_sp.head<2>() += landing_v_xy_ * t_s;
  p_sp.z() -= landing_descent_mps_ * t_s;
  const Vector3d v_sp(landing_v_xy_.x(), landing_v_xy_.y(), -landing_descent_mps_);
  auto c = track(p_sp, v_sp, Vector3d::Zero(), landing_yaw_rad_, pose, dt_s, false);
  if (land_since_) {
    // Ground contact (PX4 stops horizontal control there too): the gear's friction holds the
    // vehicle where it stands, and tilting against it only drags it across the top.
    c.roll_rad = 0.0;
    c.pitch_rad = 0.0;
    // Arrived there descending: the gear carries the vehicle (maybe landed), so the thrust goes
    // and the friction of its full weight holds it. A landing that began in a hover is first
    // held up by nothing but its own start (the demand leads, the vehicle has not moved yet).
    if (P.land_contact_cut && landing_arrived_) c.thrust_N = P.thrust_min_N;
  }
  c.mode = Mode::kSetpointLostDescent;
  c.reason = "motors off without KILL, not judged on the ground yet: landing";
  return c;
}

Vector3d PositionController::inside_fence(const Vector3d& p_W) const {
  const Vector3d inset = Vector3d::Constant(kFenceInsetM);
  return p_W.cwiseMax(params_.geofence_min_W_m + inset).cwiseMin(params_.geofence_max_W_m - inset);
}

bool PositionController::outside_fence(const Vector3d& p_W) const {
  return (p_W.array() < params_.geofence_min_W_m.array()).any() ||
         (p_W.array() > params_.geofence_max_W_m.array()).any();
}

void PositionController::trigger_failsafe(const char* reason) {
  if (!armed_ || failsafe_reason_) return;
  failsafe_reason_ = reason;
  failsafe_since_.reset();  // set at the next step, with its pose
}

AttitudeCommand PositionController::descend_to_ground(const Vector3d& from_W, double yaw_rad,
                                                      int64_t since, const PoseSample& pose,
                                                      int64_t now_utime, double dt_s, Mode mode,
                                                      const char* reason,
                                                      const char* landed_reason) {
  const auto& P = params_;
  const double t_s = age_s(since, now_utime);
  const Vector3d v_sp(0, 0, -P.setpoint_lost_descent_mps);
  Vector3d p_sp = from_W;
  p_sp.z() = from_W.z() - P.setpoint_lost_descent_mps * t_s;
  // On the ground: commanded well below the vehicle, yet it does not move down.
  const bool blocked = p_sp.z() < pose.p_W_B.z() - 0.2 && std::abs(pose.v_W_B.z()) < 0.05;
  if (!blocked) {
    still_since_.reset();
  } else if (!still_since_) {
    still_since_ = now_utime;
  } else if (age_s(*still_since_, now_utime) > P.landed_still_s) {
    disarm_latched_ = true;
    return disarmed(landed_reason);
  }
  auto c = track(p_sp, v_sp, Vector3d::Zero(), yaw_rad, pose, dt_s, false);
  c.mode = mode;
  c.reason = reason;
  return c;
}

AttitudeCommand PositionController::failsafe_land(const PoseSample& pose, int64_t now_utime,
                                                  double dt_s) {
  const auto& P = params_;
  if (!failsafe_since_) {
    failsafe_since_ = now_utime;
    failsafe_p_W_ = inside_fence(pose.p_W_B);
    failsafe_yaw_rad_ = yaw_of(pose.q_WB.toRotationMatrix());
    still_since_.reset();
  }
  if (age_s(*failsafe_since_, now_utime) <= P.failsafe_hold_s) {
    auto c = track(failsafe_p_W_, Vector3d::Zero(), Vector3d::Zero(), failsafe_yaw_rad_, pose, dt_s,
                   false);
    c.mode = Mode::kFailsafeLand;
    c.reason = failsafe_reason_;
    return c;
  }
  const int64_t descent_since = *failsafe_since_ + static_cast<int64_t>(P.failsafe_hold_s * 1e6);
  return descend_to_ground(failsafe_p_W_, failsafe_yaw_rad_, descent_since, pose, now_utime, dt_s,
                           Mode::kFailsafeLand, failsafe_reason_, "failsafe: landed, disarmed");
}

AttitudeCommand PositionController::step(const std::optional<PositionSetpoint>& setpoint,
                                         const std::optional<PoseSample>& pose, int64_t now_utime,
                                         double dt_s) {
  const auto& P = params_;
  if (pose && age_s(pose->utime, now_utime) <= P.pose_stale_s) {
    detect_landing(*pose, now_utime);
  } else {
    land_since_.reset();
    landed_ = false;
  }

  if (!setpoint) return disarmed("no setpoint received yet");
  if (setpoint->kill) {
    disarm_latched_ = false;  // a KILL is also the acknowledgement of a failsafe disarm
    return disarmed("setpoint: KILL");
  }
  // Without pose the land detector is blind and the outer loop is descending blind itself: then
  // autonomy's touch-down (from the IMU) is the only land detector left, and its motors-off is
  // honoured.
  const bool pose_lost = !pose || age_s(pose->utime, now_utime) > P.pose_lost_s;
  const bool motors_off_refused = !setpoint->motors_on && armed_ && !landed_ && !pose_lost;
  if (!setpoint->motors_on && !motors_off_refused) {
    disarm_latched_ = false;  // autonomy acknowledged: the next motors-on may arm again
    return disarmed(armed_ ? "setpoint: motors off, landed" : "setpoint: motors off");
  }
  if (setpoint->motors_on) {
    landing_since_.reset();
    last_motors_on_ = *setpoint;
  }
  if (disarm_latched_) {
    return disarmed("failsafe disarmed; waiting for autonomy to send motors off");
  }
  if (!pose) return disarmed("no pose received yet: refusing to arm");

  const double pose_age_s = age_s(pose->utime, now_utime);
  const double sp_age_s = age_s(setpoint->utime, now_utime);

  if (pose_age_s > P.pose_lost_s) {
    if (!pose_lost_since_) pose_lost_since_ = now_utime;
    const double t_s = age_s(*pose_lost_since_, now_utime);
    if (t_s > P.failsafe_disarm_after_s) {
      disarm_latched_ = true;
      return disarmed("pose lost: failsafe descent timed out, disarmed");
    }
    // Accelerate down at a_fs until the descent speed is reached, then hold that speed against
    // the expected drag. Without a velocity measurement this is open loop: a drag smaller than
    // drag_per_s lets it speed up slowly, a larger one slows it.
    const double accel_time_s = P.failsafe_descent_mps / P.failsafe_descent_accel_mps2;
    last_demand_z_mps2_ = 0.0;
    const double a_z = t_s < accel_time_s ? -P.failsafe_descent_accel_mps2
                                          : -P.drag_per_s * P.failsafe_descent_mps;
    auto c = level(P.mass_kg * (P.gravity_mps2 + integral_mps2_.z() + a_z));
    c.mode = Mode::kFailsafeDescent;
    c.reason = "pose lost: open-loop slow descent";
    return c;
  }
  pose_lost_since_.reset();
  if (pose_age_s > P.pose_stale_s) {
    last_demand_z_mps2_ = 0.0;
    auto c = level(hover_thrust_N());
    c.mode = Mode::kHoldLevel;
    c.reason = "pose stale: level, hover thrust";
    return c;
  }

  if (armed_ && outside_fence(pose->p_W_B))
    trigger_failsafe("left the geofence: holding, then landing");
  if (failsafe_reason_) return failsafe_land(*pose, now_utime, dt_s);

  if (motors_off_refused) return land(*pose, now_utime, dt_s);

  if (setpoint->idle) {
    integral_mps2_.setZero();
    last_demand_z_mps2_ = 0.0;
    landed_ = true;  // autonomy keeps it on the ground at idle
    holding_ = false;
    auto c = level(P.thrust_min_N);
    c.mode = Mode::kNormal;
    c.reason = "idle on the ground";
    return c;
  }

  if (sp_age_s <= P.setpoint_stale_s) {
    holding_ = false;
    setpoint_lost_since_.reset();
    still_since_.reset();
    auto c = track(inside_fence(setpoint->p_W), setpoint->v_W, setpoint->a_W, setpoint->yaw_rad,
                   *pose, dt_s, true, setpoint->precise, setpoint->yaw_rate_radps);
    c.reason = setpoint->precise ? "tracking (precise)" : "tracking";
    return c;
  }

  if (!holding_) {
    holding_ = true;
    hold_p_W_ = inside_fence(pose->p_W_B);
    hold_yaw_rad_ = yaw_of(pose->q_WB.toRotationMatrix());
  }
  if (sp_age_s <= P.setpoint_lost_s) {
    auto c =
        track(hold_p_W_, Vector3d::Zero(), Vector3d::Zero(), hold_yaw_rad_, *pose, dt_s, false);
    c.mode = Mode::kHoldPosition;
    c.reason = "setpoint stale: holding position";
    return c;
  }

  if (!setpoint_lost_since_) {
    setpoint_lost_since_ = now_utime;
    lost_descent_z0_m_ = pose->p_W_B.z();
  }
  Vector3d from = hold_p_W_;
  from.z() = lost_descent_z0_m_;
  return descend_to_ground(from, hold_yaw_rad_, *setpoint_lost_since_, *pose, now_utime, dt_s,
                           Mode::kSetpointLostDescent, "setpoint lost: slow descent",
                           "setpoint lost: descended to the ground, disarmed");
}

}  // namespace alight::outer_loop

#pragma once
// Outer-loop linear position controller (paper 3.4 and 4.1: "a linear controller stably regulates
// the vehicle's lateral position towards a designated setpoint. Vehicle yaw angle is maintained
// constant, and altitude is also regulated with a linear controller based on state measurements
// from the motion capture system").
//
// Lateral PD(+I) on position and velocity, plus the setpoint's feed-forward acceleration, gives a
// desired horizontal acceleration; with the gravity feed-forward and the altitude PD(+I) this is a
// desired specific-force vector f, whose direction is the commanded body z axis (roll / pitch,
// Z-Y-X Euler in the heading frame) and whose magnitude times the mass is the collective thrust.
// This is the small-angle-free form of the classic near-hover quadrotor linearisation (e.g.
// Hoffmann et al., "Quadrotor helicopter flight dynamics and control", AIAA GNC 2007, the STARMAC
// controller).
//
// The integrators learn only once the vehicle flies: risen kLiftOffM above where it rested when
// armed, or moving vertically (the ground holds it still): an autopilot that takes seconds from
// arming to lift-off (ArduCopter's spool-up in GUIDED_NOGPS) otherwise winds them up against the
// ground and the take-off overshoots.
//
// Stale inputs are explicit modes (never flying on old data): pose older than pose_stale_s →
// level attitude with hover thrust; older than pose_lost_s → open-loop slow descent and disarm;
// setpoint older than setpoint_stale_s → hold the position where it went stale; older than
// setpoint_lost_s → slow descent on the pose, disarm once on the ground.
//
// Disarming in the air (PX4's rule: a disarm request in flight is refused unless forced): a
// motors-off setpoint is honoured at once only with kill (the operator's KILL), or when the
// vehicle is not armed, or when the land detector judges it on the ground (the position loop
// asks for a clear downward acceleration and the vehicle does not move vertically, for
// land_detect_s), or during the blind pose-lost descent (where autonomy's IMU touch-down is the
// only land detector left). Otherwise the outer loop lands from where it is, at the descent
// speed autonomy last commanded (a motors-off in a hover descends slowly), level once in ground
// contact, disarming once the land detector says it is down.
//
// The autopilot's own limits, whatever the setpoints say (PX4 and ArduPilot keep them in the
// autopilot): setpoints are kept kFenceInsetM inside the geofence; a far setpoint is approached at
// no more than max_speed_*_mps (the position error is capped at the one that asks for that speed
// at steady state, v = kp e / kd); towards a wall of the fence the horizontal speed asked for is
// one the vehicle stops from before that wall's inset (fence_stopping_speed: ArduPilot's fence
// avoidance, PX4's predicted breach), so a setpoint that runs fast into the fence (a moving
// platform's follow) is not overshot beyond it; leaving the fence starts the landing failsafe
// (hold failsafe_hold_s where it is, then descend and disarm on the ground).
//
// Defence in depth: the node refuses non-finite input, but update() also never lets one
// through: a non-finite setpoint or pose is replaced by the last finite one, a non-finite
// integrator is reset, and a non-finite command becomes level hover thrust.

#include <cstdint>
#include <optional>

#include "common/pose_buffer.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/setpoint.hpp"

namespace alight::outer_loop {

/// The share of the tilt-limited horizontal acceleration (g tan(max_tilt_deg)) the loop counts on
/// to stop before a wall of the fence: the PD loop does not brake at the tilt limit from the
/// first instant, and the rest is left for the wind.
inline constexpr double kFenceBrakeShare = 0.5;

/// The fastest speed towards a wall `distance_m` away that a velocity loop of time constant
/// `lag_s` braking at `brake_mps2` stops from short of it: v lag + v^2 / (2 brake) = distance;
/// 0 at or beyond the wall [m/s].
double fence_stopping_speed(double distance_m, double brake_mps2, double lag_s);

/// What must survive a restart of the outer loop (the node keeps it in its state file).
struct PersistentState {
  bool disarm_latched = false;  ///< a failsafe disarmed: stays off until a motors-off setpoint
  bool armed = false;           ///< the last command was armed (flying, as far as we know)
};

class PositionController {
 public:
  /// `restored`: the state a previous run of the outer loop left (default: on the ground).
  explicit PositionController(const OuterLoopParams& params, const PersistentState& restored = {});

  /// One control step at `now_utime` (the newest input time; never the wall clock) with the
  /// newest setpoint and pose received so far (nullopt: none yet). Ages are now - utime.
  AttitudeCommand update(const std::optional<PositionSetpoint>& setpoint,
                         const std::optional<PoseSample>& pose, int64_t now_utime);

  /// True once one update saw a setpoint and a pose both fresh: before that a (re)started outer
  /// loop publishes nothing (it knows nothing that would justify a command).
  bool started() const { return started_; }
  /// Land detector's verdict at the last update.
  bool landed() const { return landed_; }
  /// Starts the failsafe that holds failsafe_hold_s where the vehicle is, then lands and disarms
  /// (latched until disarmed). `reason` is static text. Ignored while disarmed or already in it.
  void trigger_failsafe(const char* reason);
  /// Why the landing failsafe is active (nullptr: it is not).
  const char* failsafe_reason() const { return failsafe_reason_; }
  PersistentState persistent_state() const { return {disarm_latched_, armed_}; }

  /// Integral terms [m/s^2] (for tests and logs).
  const Vector3d& integral() const { return integral_mps2_; }
  const OuterLoopParams& params() const { return params_; }

 private:
  AttitudeCommand track(const Vector3d& p_sp, const Vector3d& v_sp, const Vector3d& a_sp,
                        double yaw_sp, const PoseSample& pose, double dt_s, bool integrate,
                        bool precise = false, double yaw_rate_ff_radps = 0.0);
  AttitudeCommand level(double thrust_N) const;
  AttitudeCommand disarmed(const char* reason);
  double hover_thrust_N() const;
  AttitudeCommand step(const std::optional<PositionSetpoint>& setpoint,
                       const std::optional<PoseSample>& pose, int64_t now_utime, double dt_s);
  AttitudeCommand land(const PoseSample& pose, int64_t now_utime, double dt_s);
  AttitudeCommand failsafe_land(const PoseSample& pose, int64_t now_utime, double dt_s);
  // Descends from `from_W` at setpoint_lost_descent_mps since `since`; disarms (latched) once
  // the ground stops it. `mode` and `reason` name what is landing.
  AttitudeCommand descend_to_ground(const Vector3d& from_W, double yaw_rad, int64_t since,
                                    const PoseSample& pose, int64_t now_utime, double dt_s,
                                    Mode mode, const char* reason, const char* landed_reason);
  Vector3d inside_fence(const Vector3d& p_W) const;
  bool outside_fence(const Vector3d& p_W) const;
  void detect_landing(const PoseSample& pose, int64_t now_utime);
  void detect_lift_off(const std::optional<PoseSample>& pose, int64_t now_utime);

  OuterLoopParams params_;
  std::optional<int64_t> last_utime_;
  Vector3d integral_mps2_ = Vector3d::Zero();

  bool disarm_latched_ = false;  // failsafe disarm: stays until autonomy sends motors off
  bool armed_ = false;           // the last command's armed
  bool started_ = false;
  bool landed_ = false;
  // Since the last arming: the lowest height seen, and whether the vehicle has risen off it. The
  // integrators learn only in the air: on the ground the support, not a thrust error, cancels the
  // position error.
  std::optional<double> rest_z_m_;
  bool lifted_off_ = false;
  std::optional<int64_t> land_since_;
  double last_demand_z_mps2_ = 0.0;  // PD part of the last vertical demand (land detector)
  std::optional<PositionSetpoint> last_good_setpoint_;
  std::optional<PoseSample> last_good_pose_;
  std::optional<PositionSetpoint> last_motors_on_;  // newest motors-on setpoint
  std::optional<int64_t> landing_since_;            // refused motors-off: landing since
  Vector3d landing_p_W_ = Vector3d::Zero();
  double landing_yaw_rad_ = 0.0;
  double landing_descent_mps_ = 0.0;
  Vector2d landing_v_xy_ = Vector2d::Zero();  // the last feed-forward: a moving top's velocity
  bool landing_arrived_ = false;  // led down or seen descending: a contact now is the ground
  std::optional<int64_t> pose_lost_since_;
  std::optional<int64_t> setpoint_lost_since_;
  std::optional<int64_t> still_since_;
  bool holding_ = false;
  Vector3d hold_p_W_ = Vector3d::Zero();
  double hold_yaw_rad_ = 0.0;
  double lost_descent_z0_m_ = 0.0;
  const char* failsafe_reason_ = nullptr;  // the landing failsafe, latched until disarmed
  std::optional<int64_t> failsafe_since_;
  Vector3d failsafe_p_W_ = Vector3d::Zero();
  double failsafe_yaw_rad_ = 0.0;
};

}  // namespace alight::outer_loop

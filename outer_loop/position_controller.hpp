#pragma once
// Outer-loop linear position controller (paper 3.4 and 4.1: "a linear controller stably regulates
// the vehicle's lateral position towards a designated setpoint. Vehicle yaw angle is maintained
// constant, and altitude is also regulated with a linear controller based on state measurements
// from the motion capture system").
//
// Lateral PD(+I) on position and velocity gives a desired horizontal acceleration; with the
// gravity feed-forward and the altitude PD(+I) this is a desired specific-force vector f, whose
// direction is the commanded body z axis (roll / pitch, Z-Y-X Euler in the heading frame) and
// whose magnitude times the mass is the collective thrust. This is the small-angle-free form of
// the classic near-hover quadrotor linearisation (e.g. Hoffmann et al., "Quadrotor helicopter
// flight dynamics and control", AIAA GNC 2007, the STARMAC controller).
//
// Stale inputs are explicit modes (never flying on old data): pose older than pose_stale_s →
// level attitude with hover thrust; older than pose_lost_s → open-loop slow descent and disarm;
// setpoint older than setpoint_stale_s → hold the position where it went stale; older than
// setpoint_lost_s → slow descent on the pose, disarm once on the ground.

#include <cstdint>
#include <optional>

#include "common/pose_buffer.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/setpoint.hpp"

namespace alight::outer_loop {

class PositionController {
 public:
  explicit PositionController(const OuterLoopParams& params);

  /// One control step at `now_utime` (the newest input time; never the wall clock) with the
  /// newest setpoint and pose received so far (nullopt: none yet). Ages are now - utime.
  AttitudeCommand update(const std::optional<PositionSetpoint>& setpoint,
                         const std::optional<PoseSample>& pose, int64_t now_utime);

  /// Integral terms [m/s^2] (for tests and logs).
  const Vector3d& integral() const { return integral_mps2_; }
  const OuterLoopParams& params() const { return params_; }

 private:
  AttitudeCommand track(const Vector3d& p_sp, const Vector3d& v_sp, double yaw_sp,
                        const PoseSample& pose, double dt_s, bool integrate);
  AttitudeCommand level(double thrust_N) const;
  AttitudeCommand disarmed(const char* reason);
  double hover_thrust_N() const;

  OuterLoopParams params_;
  std::optional<int64_t> last_utime_;
  Vector3d integral_mps2_ = Vector3d::Zero();

  bool disarm_latched_ = false;   // failsafe disarm: stays until autonomy sends motors off
  std::optional<int64_t> pose_lost_since_;
  std::optional<int64_t> setpoint_lost_since_;
  std::optional<int64_t> still_since_;
  bool holding_ = false;
  Vector3d hold_p_W_ = Vector3d::Zero();
  double hold_yaw_rad_ = 0.0;
  double lost_descent_z0_m_ = 0.0;
};

}  // namespace alight::outer_loop

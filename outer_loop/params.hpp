#pragma once
// Parameters of the outer-loop position controller (paper 3.4 and 4.1): the `outer_loop:` section
// of a vehicle file. Gains are per unit mass (accelerations), so the same numbers mean the same
// closed-loop bandwidth on both vehicles; mass_kg turns them into thrust.

#include <string>

#include "common/params.hpp"

namespace alight::outer_loop {

struct OuterLoopParams {
  double mass_kg = 1.0;        ///< controller's nominal vehicle mass (hover thrust = m g) [kg]
  double gravity_mps2 = 9.81;  ///< [m/s^2]

  // Lateral (x, y) PD + optional I on position, turned into roll / pitch.
  double kp_xy_per_s2 = 4.0;     ///< position gain: commanded accel per metre of error [1/s^2]
  double kd_xy_per_s = 3.2;      ///< velocity gain: commanded accel per m/s of error [1/s]
  double ki_xy_per_s3 = 1.0;     ///< integral gain [1/s^3]; 0 disables the integrator
  double i_limit_xy_mps2 = 1.0;  ///< anti-windup: largest integral contribution [m/s^2]

  // Altitude PD + I with gravity feed-forward.
  double kp_z_per_s2 = 6.0;     ///< [1/s^2]
  double kd_z_per_s = 4.0;      ///< [1/s]
  double ki_z_per_s3 = 3.0;     ///< [1/s^3]; 0 disables
  double i_limit_z_mps2 = 2.0;  ///< anti-windup: largest integral contribution [m/s^2]

  double max_tilt_deg = 20.0;     ///< largest commanded roll / pitch (and tilt of the thrust) [deg]
  double thrust_min_N = 0.5;      ///< smallest collective thrust while armed [N]
  double thrust_max_N = 20.0;     ///< largest collective thrust [N]
  double max_accel_z_mps2 = 4.0;  ///< largest commanded vertical acceleration magnitude [m/s^2]

  double yaw_kp_per_s = 1.5;       ///< yaw rate per radian of heading error [1/s]
  double max_yaw_rate_dps = 45.0;  ///< [deg/s]

  // Stale inputs (never fly on old data). Ages are measured against the newest input time.
  double pose_stale_s = 0.3;          ///< pose older than this: level attitude, hover thrust [s]
  double pose_lost_s = 1.0;           ///< pose older than this: open-loop slow descent [s]
  double failsafe_descent_mps = 0.4;  ///< open-loop descent speed without pose [m/s]
  double failsafe_descent_accel_mps2 = 1.0;  ///< how hard that descent is started [m/s^2]
  double drag_per_s = 0.2;                ///< linear drag over mass [1/s]: without pose the descent
                                          ///< speed is held open loop by thrust = m (g - drag v)
  double failsafe_disarm_after_s = 20.0;  ///< without pose, disarm this long into the descent
                                          ///< (the flying area is lower than 8 m) [s]
  double setpoint_stale_s = 0.5;  ///< setpoint older than this: hold where it went stale [s]
  double setpoint_lost_s = 3.0;   ///< setpoint older than this: slow descent on mocap [s]
  double setpoint_lost_descent_mps = 0.3;  ///< descent speed with pose but no setpoint [m/s]
  double landed_still_s = 1.0;  ///< with no setpoint: disarm after this long not descending
                                ///< although commanded to (on the ground) [s]

  // Land detector (like PX4's): a motors-off setpoint without KILL is honoured only on the ground.
  double land_detect_s = 0.5;    ///< on the ground once this long with the demand below [s]
  double land_vz_mps = 0.1;      ///< ... no faster vertically than this [m/s]
  double land_accel_mps2 = 0.5;  ///< ... and the position loop asking for at least this much
                                 ///< downward acceleration (the ground holds it up) [m/s^2]

  double i_zone_m = 0.3;     ///< integrate only while the error is smaller (no windup
                             ///< during large steps) [m]
  double i_still_mps = 0.1;  ///< ... or while slower than this (steady offsets) [m/s]
  double max_dt_s = 0.05;    ///< larger input gaps are integrated as this step [s]

  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Reads the `outer_loop:` section of a vehicle file (and only it; finish() on it).
OuterLoopParams load_params(const std::string& vehicle_file);
/// Same, from a parsed file's root node.
OuterLoopParams load_params(const ParamNode& vehicle_root);

}  // namespace alight::outer_loop

#pragma once
// Parameters of the outer-loop position controller (paper 3.4 and 4.1): the `outer_loop:` section
// of a vehicle file. Gains are per unit mass (accelerations), so the same numbers mean the same
// closed-loop bandwidth on both vehicles; mass_kg turns them into thrust.

#include <string>

#include "common/geometry.hpp"
#include "common/param_schema.hpp"
#include "common/site.hpp"

namespace alight::outer_loop {

/// Setpoints are kept this far inside the geofence: a step flown at the speed limit overshoots
/// by less, so a tracked setpoint never breaches the fence [m].
inline constexpr double kFenceInsetM = 0.2;

struct OuterLoopParams {
  double mass_kg = 1.0;
  double gravity_mps2 = 9.81;

  // Lateral (x, y) PD + optional I on position, turned into roll / pitch.
  double kp_xy_per_s2 = 4.0;
  double kd_xy_per_s = 3.2;
  double ki_xy_per_s3 = 1.0;
  double i_limit_xy_mps2 = 1.0;
  // The same for setpoints marked precise (position_setpoint_t.MODE_PRECISE).
  double precise_kp_xy_per_s2 = 9.0;
  double precise_kd_xy_per_s = 4.8;
  double precise_ki_xy_per_s3 = 3.0;

  // Altitude PD + I with gravity feed-forward.
  double kp_z_per_s2 = 6.0;
  double kd_z_per_s = 4.0;
  double ki_z_per_s3 = 3.0;
  double i_limit_z_mps2 = 2.0;

  double max_tilt_deg = 20.0;
  double thrust_min_N = 0.5;
  double thrust_max_N = 20.0;
  double max_accel_z_mps2 = 4.0;

  double yaw_kp_per_s = 1.5;
  double max_yaw_rate_dps = 45.0;

  // Stale inputs (never fly on old data). Ages are measured against the newest input time.
  double pose_stale_s = 0.3;
  double pose_lost_s = 1.0;
  double failsafe_descent_mps = 0.4;
  double failsafe_descent_accel_mps2 = 1.0;
  double drag_per_s = 0.2;
  double failsafe_disarm_after_s = 20.0;
  double setpoint_stale_s = 0.5;
  double setpoint_lost_s = 3.0;
  double setpoint_lost_descent_mps = 0.3;
  double landed_still_s = 1.0;

  // Land detector (like PX4's): a motors-off setpoint without KILL is honoured only on the ground.
  double land_detect_s = 0.5;
  double land_vz_mps = 0.1;
  double land_accel_mps2 = 0.5;
  double land_max_descent_mps = 1.0;
  bool land_contact_cut = false;

  // The autopilot's own limits, whatever the setpoints say (PX4's GF_* and MPC_*_VEL_MAX).
  // No default flying area: every vehicle file states its own (the schema requires it).
  Vector3d geofence_min_W_m = Vector3d::Constant(-1e3);
  Vector3d geofence_max_W_m = Vector3d::Constant(1e3);
  double max_speed_xy_mps = 1.0;
  /// A setpoint's own horizontal velocity (a moving platform's, fed forward) is followed up to
  /// this, the far setpoint's approach at max_speed_xy_mps coming on top of it [m/s].
  double max_feedforward_xy_mps = 2.0;
  double max_speed_z_mps = 1.0;
  double failsafe_hold_s = 2.0;

  double i_zone_m = 0.3;
  double i_still_mps = 0.1;
  double max_dt_s = 0.05;

  /// Key, constraint, unit and meaning of every field above (their defaults are the
  /// initialisers); reading, validation and `alight-params --dump` all come from it.
  static const ParamSchema<OuterLoopParams>& schema();
  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Reads the `outer_loop:` section of a vehicle file (and only it; finish() on it).
OuterLoopParams load_params(const std::string& vehicle_file);
/// Same, from a parsed file's root node.
OuterLoopParams load_params(const ParamNode& vehicle_root);

/// Narrows the geofence to the site's walls and ceiling (common/site.hpp): the room flown in,
/// its setpoints kept kFenceInsetM inside as ever. Throws ParamError naming `site_file` when the
/// vehicle's geofence and the site leave 2 x kFenceInsetM or less on an axis.
void fit_to_site(OuterLoopParams& p, const SiteArea& site, const std::string& site_file);

}  // namespace alight::outer_loop

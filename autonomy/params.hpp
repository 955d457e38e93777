#pragma once
// Parameters of the autonomy loop (paper 3.4): the `autonomy:` section of a vehicle file. The
// defaults are the initialisers below; key, constraint, unit and meaning of each field (with the
// paper's symbol where it has one) are declared once in params.cpp (common/param_schema.hpp), and
// `alight-params --defaults vehicle` prints them.

#include <cstdint>
#include <optional>
#include <string>

#include "autonomy/moving_landing.hpp"
#include "common/camera_model.hpp"
#include "common/geometry.hpp"
#include "common/param_schema.hpp"
#include "common/site.hpp"

namespace alight::autonomy {

struct TakeoffParams {
  double height_m = 1.2;
  double climb_rate_mps = 0.5;
  double reached_tol_m = 0.08;
  static const ParamSchema<TakeoffParams>& schema();
  void validate() const;
};

/// The flying area: every setpoint is clamped into this box.
struct GeofenceParams {
  Vector3d min_W_m = Vector3d(-3, -3, 0);
  Vector3d max_W_m = Vector3d(3, 3, 2.5);
  static const ParamSchema<GeofenceParams>& schema();
  void validate() const;
};

/// Detection phase (3.4.1 "Platform Detection", 4.3): predefined search paths.
struct DetectionParams {
  double speed_mps = 0.3;
  Vector2d landing_area_min_W_m = Vector2d(-1, -1);
  Vector2d landing_area_max_W_m = Vector2d(1, 1);
  double lane_spacing_m = 0.6;
  double landing_height_m = 1.2;
  Vector3d ingress_start_W_m = Vector3d(1.5, -1.2, 1.2);
  Vector3d ingress_end_W_m = Vector3d(1.5, 1.2, 1.2);
  double ingress_yaw_deg = 0.0;
  int max_retries = 2;
  static const ParamSchema<DetectionParams>& schema();
  void validate() const;
};

/// Refinement phase (3.4.1 "Refinement of Estimate", eqs. 7-9).
struct RefinementParams {
  int n_min = 10;            // eq. 7
  double eps_horz_m = 0.01;  // eq. 8
  double eps_vert_m = 0.02;  // eq. 9
  double cutoff_m = 0.2;
  double prior_sigma_m = 0.1;
  double vantage_sigma_floor_m = 0.08;
  double vantage_reach_tol_m = 0.08;
  double vantage_dwell_s = 0.8;
  double vantage_timeout_s = 6.0;
  bool one_waypoint_per_vantage = true;
  double gate_chi2 = 16.27;
  int gate_min_n = 4;
  double gate_floor_sigma_m = 0.03;
  int max_consecutive_rejections = 6;
  double lost_timeout_s = 3.0;
  double max_time_s = 60.0;
  double ingress_standoff_m = 1.5;
  static const ParamSchema<RefinementParams>& schema();
  void validate() const;
};

/// Approach phase, landing (3.4.1 "Descent and Landing").
struct LandingParams {
  double descent_rate_mps = 0.25;  // v_des
  double radial_tol_m = 0.04;      // bound on e_r(t)
  double final_height_m = 0.25;
  double final_descent_rate_mps = 1.0;
  double final_depth_m = 0.3;
  double gear_height_m = 0.1;
  double gear_footprint_m = 0.15;
  double fit_margin_m = 0.02;
  double touchdown_accel_mps2 = 4.0;
  double touchdown_still_s = 0.5;
  double lost_timeout_s = 3.0;
  double lost_check_height_m = 0.6;
  double align_yaw_tol_deg = 3.0;
  double final_hold_speed_mps = 0.0;      // 0: the final descent is never held
  double final_hold_speed_max_mps = 0.0;  // 0: the bound never grows
  double final_hold_radial_m = 0.01;
  double final_hold_settle_s = 0.2;
  double final_hold_timeout_s = 10.0;
  double final_pause_radial_m = 0.0;  // 0: the final descent never pauses
  double final_pause_min_height_m = 0.1;
  bool precise_final = false;
  bool aim_gear = false;
  static const ParamSchema<LandingParams>& schema();
  void validate() const;
};

/// Approach phase, ingress (3.4.2: the paper did not fly it).
struct IngressParams {
  double standoff_m = 1.2;
  double speed_mps = 0.3;
  double lateral_tol_m = 0.05;
  double vertical_tol_m = 0.05;
  double pass_distance_m = 1.0;
  double align_tol_m = 0.04;
  double align_speed_mps = 0.08;
  double align_settle_s = 1.0;
  double vehicle_span_m = 0.45;
  double vehicle_height_m = 0.2;
  double clearance_m = 0.05;
  double lost_timeout_s = 0.0;
  static const ParamSchema<IngressParams>& schema();
  void validate() const;
};

/// Lost motion capture, silent vision, and the onboard estimate's health.
struct FailsafeParams {
  double pose_stale_s = 0.3;
  double pose_lost_s = 1.0;
  double descent_mps = 0.3;
  double pose_recovered_s = 0.5;
  double vision_silent_s = 5.0;
  double abort_height_m = 1.5;
  double max_nudge_m = 0.5;
  double estimate_silent_s = 0.5;
  bool require_estimate = false;
  static const ParamSchema<FailsafeParams>& schema();
  void validate() const;
};

/// Restart semantics, the PX4 way: an autonomy that starts while the vehicle flies
/// holds where it is, motors on, and waits for the operator; it never takes off again.
struct RestartParams {
  double airborne_height_m = 0.15;
  double airborne_speed_mps = 0.3;
  double state_max_age_s = 60.0;
  static const ParamSchema<RestartParams>& schema();
  void validate() const;
};

/// The downward camera's view as refinement uses it to look at a top its views cut (derived from
/// the vehicle file's cameras.downward and its camera_info when it declares one; not a
/// parameter): the tangents of the half angles inside which the vision calls a top whole.
struct DownwardView {
  double tan_long = 0.0;             ///< along the image's long axis
  double tan_short = 0.0;            ///< along its short axis
  double long_axis_yaw_B_rad = 0.0;  ///< the image's long axis in the body's x-y plane [rad]
  double offset_m = 0.0;  ///< the camera's centre from the body's origin, horizontally [m]
};

/// The view of a camera model and mounting, less the vision's border margin (a top with a
/// feature this close to the border is cut: vision.landing.edge_margin_px's default) [px].
inline constexpr double kViewBorderPx = 40.0;
DownwardView downward_view(const CameraModel& camera, const Matrix3d& R_BC);

struct AutonomyParams {
  uint64_t seed = 1;
  bool accept_unsigned_commands = false;
  std::string operator_key_file;  ///< resolved against the vehicle file's folder when read
  double command_max_age_s = 2.0;
  std::string vehicle_id = "alight";
  double status_period_s = 0.1;
  double hover_tol_m = 0.1;
  TakeoffParams takeoff;
  GeofenceParams geofence;
  DetectionParams detection;
  RefinementParams refinement;
  LandingParams landing;
  IngressParams ingress;
  FailsafeParams failsafe;
  RestartParams restart;
  MovingLandingParams moving_platform;
  /// Without one, refinement looks from the search height as it found the top.
  std::optional<DownwardView> downward_view;
  static const ParamSchema<AutonomyParams>& schema();
  void validate() const;  ///< throws ParamError naming the full key and its value
};

/// Reads the `autonomy:` section of a vehicle file (finish() on it).
AutonomyParams load_params(const std::string& vehicle_file);
AutonomyParams load_params(const ParamNode& vehicle_root);

/// The autonomy's setpoints stay this far inside a site's walls and ceiling: as far as the
/// outer loop keeps its own setpoints inside its fence (outer_loop::kFenceInsetM), whose box is
/// the site's walls themselves [m].
inline constexpr double kSiteWallClearanceM = 0.2;

/// Narrows `p.geofence` to the site (common/site.hpp) kSiteWallClearanceM inside its walls and
/// ceiling: every setpoint, a moving platform's predicted follow too, stays in the room flown
/// in. Throws ParamError naming `site_file` when the vehicle's geofence and the site leave less
/// than the geofence's 0.5 m on an axis, or no room above takeoff.height_m.
void fit_to_site(AutonomyParams& p, const SiteArea& site, const std::string& site_file);

}  // namespace alight::autonomy

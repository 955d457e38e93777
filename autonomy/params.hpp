#pragma once
// Parameters of the autonomy loop (paper 3.4): the `autonomy:` section of a vehicle file. Every
// threshold carries its unit and, where the paper has one, the paper's symbol.

#include <cstdint>
#include <string>

#include "common/geometry.hpp"
#include "common/params.hpp"

namespace alight::autonomy {

struct TakeoffParams {
  double height_m = 1.2;        ///< hover height after take-off, world z [m]
  double climb_rate_mps = 0.5;  ///< setpoint ramp while climbing [m/s]
  double reached_tol_m = 0.08;  ///< position error that counts as arrived [m]
  void validate() const;
};

/// The flying area: every setpoint is clamped into this box.
struct GeofenceParams {
  Vector3d min_W_m = Vector3d(-3, -3, 0);  ///< [m]; min z is the floor (LAND_HERE lands on it)
  Vector3d max_W_m = Vector3d(3, 3, 2.5);  ///< [m]
  void validate() const;
};

/// Detection phase (3.4.1 "Platform Detection", 4.3): predefined search paths.
struct DetectionParams {
  double speed_mps = 0.3;                            ///< along the search path [m/s]
  Vector2d landing_area_min_W_m = Vector2d(-1, -1);  ///< lawnmower over this rectangle [m]
  Vector2d landing_area_max_W_m = Vector2d(1, 1);
  double lane_spacing_m = 0.6;    ///< lawnmower lanes (along x) this far apart in y [m]
  double landing_height_m = 1.2;  ///< search height, world z [m]
  Vector3d ingress_start_W_m = Vector3d(1.5, -1.2, 1.2);  ///< pass along the wall: from [m]
  Vector3d ingress_end_W_m = Vector3d(1.5, 1.2, 1.2);     ///< to [m]
  double ingress_yaw_deg = 0.0;  ///< heading during the pass (camera at the wall) [deg]
  int max_retries = 2;           ///< detections retried after a lost target [-]
  void validate() const;
};

/// Refinement phase (3.4.1 "Refinement of Estimate", eqs. 7-9).
struct RefinementParams {
  int n_min = 10;            ///< eq. 7: n >= n_min
  double eps_horz_m = 0.01;  ///< eq. 8: horizontal change of the mean [m]
  double eps_vert_m = 0.02;  ///< eq. 9: vertical change of the mean [m]
  double cutoff_m = 0.2;  ///< vantage draws farther than this from the mean are redrawn; keeps the
                          ///< target in view (a 43 cm platform at 1.1 m range: within ~0.2 m) [m]
  double prior_sigma_m = 0.1;           ///< Sigma of the vantage draws before 2 waypoints exist [m]
  double vantage_sigma_floor_m = 0.08;  ///< added to Sigma of the draws so vantages keep apart [m]
  double vantage_reach_tol_m = 0.08;    ///< at a vantage point when this close [m]
  double vantage_dwell_s = 0.8;         ///< stay this long at a vantage point [s]
  double vantage_timeout_s = 6.0;       ///< draw the next vantage after this long anyway [s]
  /// One waypoint per vantage: the component-wise median of the frames seen while dwelling there
  /// (none while flying between vantages). Successive frames from one place share the reference
  /// image and the features, so their errors are not independent: counted one by one, eqs. 7-9
  /// would be met after n_min frames from a single point (in flight: 0.8 s, 43 cm off). [-]
  bool one_waypoint_per_vantage = true;
  double gate_chi2 = 16.27;          ///< Mahalanobis gate d^2 (chi^2, 3 dof, p = 0.001) [-]
  int gate_min_n = 4;                ///< the gate is active from this many waypoints on [-]
  double gate_floor_sigma_m = 0.03;  ///< isotropic sigma added to the sample covariance [m]
  int max_consecutive_rejections =
      6;                            ///< then the estimate is restarted (seeded by an outlier) [-]
  double lost_timeout_s = 3.0;      ///< no target seen this long: target lost [s]
  double max_time_s = 60.0;         ///< no convergence in this time: hold and report [s]
  double ingress_standoff_m = 1.5;  ///< ingress vantages lie this far in front of the wall [m]
  void validate() const;
};

/// Approach phase, landing (3.4.1 "Descent and Landing").
struct LandingParams {
  double descent_rate_mps = 0.25;       ///< v_des: x3(t+1) = x3(t) - v_des dt [m/s]
  double radial_tol_m = 0.04;           ///< descend only while e_r(t) is within this [m]
  double final_height_m = 0.25;         ///< gear this high above the estimate: final descent [m]
  double final_descent_rate_mps = 1.0;  ///< the "rapid" decrease of the setpoint [m/s]
  double final_depth_m = 0.3;           ///< final setpoint this far below the platform top [m]
  double gear_height_m = 0.1;           ///< body origin above the gear feet [m]
  double gear_footprint_m = 0.15;       ///< side of the landing gear (paper 4.1: approx. 15 cm) [m]
  double fit_margin_m = 0.02;  ///< refuse a platform whose short side < footprint + 2 margin [m]
  double touchdown_accel_mps2 = 4.0;  ///< impact: specific force above g by this much [m/s^2]
  double touchdown_still_s = 0.5;     ///< or: not descending this long although commanded [s]
  double lost_timeout_s = 3.0;        ///< target unseen this long during approach: lost [s]
  double lost_check_height_m = 0.6;   ///< ... checked only while the gear is higher above it [m]
  /// The square gear is turned to the platform's edges (its yaw from vision, modulo 90 deg) and
  /// descends only within this yaw error [deg]; 0: no turn. A corner of a 15 cm gear turned 25
  /// deg on a 21.6 cm wide ream lands within mm of the edge (Monte Carlo landing_c: 3 of 20
  /// tipped off it after touch-down).
  double align_yaw_tol_deg = 3.0;
  void validate() const;
};

/// Approach phase, ingress (3.4.2: the paper did not fly it).
struct IngressParams {
  double standoff_m = 1.2;        ///< align on the normal this far in front of the opening [m]
  double speed_mps = 0.3;         ///< along the normal through the opening [m/s]
  double lateral_tol_m = 0.05;    ///< advance only while the lateral error is within [m]
  double vertical_tol_m = 0.05;   ///< ... and the vertical error [m]
  double pass_distance_m = 1.0;   ///< stop this far past the wall plane [m]
  double align_tol_m = 0.04;      ///< aligned when this close to the standoff point [m]
  double align_speed_mps = 0.08;  ///< ... and slower than this [m/s]
  double align_settle_s = 1.0;    ///< ... for this long [s]
  double vehicle_span_m = 0.45;   ///< rotor tip to rotor tip, across [m]
  double vehicle_height_m = 0.2;  ///< gear feet to rotor top [m]
  double clearance_m = 0.05;      ///< refuse openings narrower than vehicle + 2 clearance [m]
  /// Target unseen this long while aligning: lost [s]; 0: no check, the converged estimate is
  /// flown as the paper's fixed fly-to-waypoint manoeuvre (3.4). Aligning on the normal moves
  /// the camera along its axis, where the opening at the image centre shows no parallax, and
  /// hovering gives no baseline at all: real vision goes quiet there (closed-loop flights).
  double lost_timeout_s = 0.0;
  void validate() const;
};

struct FailsafeParams {
  double pose_stale_s = 0.3;    ///< mocap older: freeze the mission (outer loop holds level) [s]
  double pose_lost_s = 1.0;     ///< mocap older: controlled descent, disarm on touch-down [s]
  double descent_mps = 0.3;     ///< failsafe descent when the pose is back [m/s]
  /// Pose fresh again this long in the pose-lost failsafe: stop the descent and hold, waiting for
  /// the operator (descending blind-chosen onto a platform edge tips the vehicle) [s]
  double pose_recovered_s = 0.5;
  /// No VISION_TARGET this long while searching or refining: the camera or the vision process is
  /// down; hold and wait for the operator instead of searching blind [s]
  double vision_silent_s = 5.0;
  double abort_height_m = 1.5;  ///< ABORT climbs to at least this height, world z [m]
  double max_nudge_m = 0.5;     ///< largest NUDGE offset [m]
  void validate() const;
};

/// Restart semantics (issue 14), the PX4 way: an autonomy that starts while the vehicle flies
/// holds where it is, motors on, and waits for the operator; it never takes off again.
struct RestartParams {
  /// The first pose shows the vehicle flying when its gear is this far above the floor
  /// (geofence.min_W_m z; body z minus landing.gear_height_m) [m]. Below it a restart cannot
  /// tell a low hover from standing, and takes the previous instance's word (state file).
  double airborne_height_m = 0.15;
  double airborne_speed_mps = 0.3;  ///< ... or when it moves faster than this [m/s]
  /// The node restores a state file written (heartbeat) at most this long ago by an instance
  /// of the same session (same boot, same parent process): a launcher restart, not a new
  /// flight [s].
  double state_max_age_s = 60.0;
  void validate() const;
};

struct AutonomyParams {
  uint64_t seed = 1;                      ///< RNG seed of the vantage draws
  bool accept_unsigned_commands = false;  ///< accept operator_cmd_t with AUTH_NONE (testing only)
  std::string operator_key_file;          ///< HMAC key shared with the ground station (relative
                                          ///< to the vehicle file; empty: no signed commands)
  double command_max_age_s = 2.0;         ///< signed commands older / newer than this are stale [s]
  std::string vehicle_id = "alight";      ///< signed commands must name it (operator_cmd_t)
  double status_period_s = 0.1;           ///< AUTONOMY_STATUS at least this often [s]
  double hover_tol_m = 0.1;               ///< "arrived" for path and hold points [m]
  TakeoffParams takeoff;
  GeofenceParams geofence;
  DetectionParams detection;
  RefinementParams refinement;
  LandingParams landing;
  IngressParams ingress;
  FailsafeParams failsafe;
  RestartParams restart;
  void validate() const;
};

/// Reads the `autonomy:` section of a vehicle file (finish() on it).
AutonomyParams load_params(const std::string& vehicle_file);
AutonomyParams load_params(const ParamNode& vehicle_root);

}  // namespace alight::autonomy

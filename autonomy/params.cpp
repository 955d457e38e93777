#include "autonomy/params.hpp"

#include <algorithm>
#include <cmath>

#include "common/camera_mount.hpp"

namespace alight::autonomy {

const ParamSchema<TakeoffParams>& TakeoffParams::schema() {
  using P = TakeoffParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("height_m", &P::height_m, Range::open(0.3, 10), "m",
          "hover height after take-off, world z");
    s.add("climb_rate_mps", &P::climb_rate_mps, Range::open_closed(0, 2), "m/s",
          "setpoint ramp while climbing");
    s.add("reached_tol_m", &P::reached_tol_m, Range::gt(0), "m",
          "position error that counts as arrived");
    return s;
  }();
  return schema;
}

const ParamSchema<GeofenceParams>& GeofenceParams::schema() {
  using P = GeofenceParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("min_W_m", &P::min_W_m, Range::any(), "m",
          "lower corner of the box every setpoint is clamped into; its z is the floor (LAND_HERE "
          "lands on it)");
    s.add("max_W_m", &P::max_W_m, Range::any(), "m", "upper corner")
        .check(
            [](const P& p) {
              for (int i = 0; i < 3; ++i)
                if (!(p.max_W_m[i] > p.min_W_m[i] + 0.5)) return false;
              return true;
            },
            "must exceed min_W_m by 0.5 m on every axis");
    return s;
  }();
  return schema;
}

const ParamSchema<DetectionParams>& DetectionParams::schema() {
  using P = DetectionParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("speed_mps", &P::speed_mps, Range::open_closed(0, 2), "m/s", "along the search path");
    s.add("landing_area_min_W_m", &P::landing_area_min_W_m, Range::any(), "m",
          "the lawnmower covers this rectangle: lower corner (x, y)");
    s.add("landing_area_max_W_m", &P::landing_area_max_W_m, Range::any(), "m", "upper corner")
        .check(
            [](const P& p) {
              return (p.landing_area_max_W_m - p.landing_area_min_W_m).minCoeff() >= 0;
            },
            "must not be below landing_area_min_W_m");
    s.add("lane_spacing_m", &P::lane_spacing_m, Range::gt(0.05), "m",
          "lawnmower lanes (along x) this far apart in y");
    s.add("landing_height_m", &P::landing_height_m, Range::gt(0.3), "m",
          "search (and vantage) height, world z");
    s.add("ingress_start_W_m", &P::ingress_start_W_m, Range::any(), "m",
          "pass along the wall: from");
    s.add("ingress_end_W_m", &P::ingress_end_W_m, Range::any(), "m", "pass along the wall: to")
        .check([](const P& p) { return (p.ingress_end_W_m - p.ingress_start_W_m).norm() > 0.1; },
               "must be > 0.1 m from ingress_start_W_m");
    s.add("ingress_yaw_deg", &P::ingress_yaw_deg, Range::any(), "deg",
          "heading during the pass (camera at the wall)");
    s.add("max_retries", &P::max_retries, Range::closed(0, 20), "",
          "detections retried after a lost target");
    return s;
  }();
  return schema;
}

const ParamSchema<RefinementParams>& RefinementParams::schema() {
  using P = RefinementParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("n_min", &P::n_min, Range::ge(2), "",
          "eq. 7: at least this many measurements (eq. 8 compares two means)");
    s.add("eps_horz_m", &P::eps_horz_m, Range::gt(0), "m",
          "eq. 8: largest horizontal change of the mean");
    s.add("eps_vert_m", &P::eps_vert_m, Range::gt(0), "m",
          "eq. 9: largest vertical change of the mean");
    s.add("cutoff_m", &P::cutoff_m, Range::gt(0), "m",
          "vantage draws farther than this from the mean are redrawn; keeps the target in view "
          "(a 43 cm platform at 1.1 m range: within ~0.2 m)");
    s.add("prior_sigma_m", &P::prior_sigma_m, Range::gt(0), "m",
          "Sigma of the vantage draws before 2 waypoints exist");
    s.add("vantage_sigma_floor_m", &P::vantage_sigma_floor_m, Range::ge(0), "m",
          "added to Sigma of the draws so vantages keep apart");
    s.add("vantage_reach_tol_m", &P::vantage_reach_tol_m, Range::gt(0), "m",
          "at a vantage point when this close");
    s.add("vantage_dwell_s", &P::vantage_dwell_s, Range::closed(0, 10), "s",
          "stay this long at a vantage point");
    s.add("vantage_timeout_s", &P::vantage_timeout_s, Range::le(60), "s",
          "draw the next vantage after this long anyway")
        .check([](const P& p) { return p.vantage_timeout_s > p.vantage_dwell_s; },
               "must exceed vantage_dwell_s");
    s.add("one_waypoint_per_vantage", &P::one_waypoint_per_vantage, Range::any(), "",
          "one waypoint per vantage: the component-wise median of the frames seen while dwelling "
          "there. Successive frames from one place share the reference image and the features, "
          "so their errors are not independent: counted one by one, eqs. 7-9 would be met after "
          "n_min frames from a single point (in flight: 0.8 s, 43 cm off)");
    s.add("gate_chi2", &P::gate_chi2, Range::gt(0), "",
          "Mahalanobis gate d^2 (chi^2, 3 dof, p = 0.001)");
    s.add("gate_min_n", &P::gate_min_n, Range::ge(3), "",
          "the gate is active from this many waypoints on");
    s.add("gate_floor_sigma_m", &P::gate_floor_sigma_m, Range::gt(0), "m",
          "isotropic sigma added to the sample covariance in the gate");
    s.add("max_consecutive_rejections", &P::max_consecutive_rejections, Range::ge(1), "",
          "then the estimate is restarted (it was seeded by an outlier)");
    s.add("lost_timeout_s", &P::lost_timeout_s, Range::open_closed(0, 60), "s",
          "no target seen this long: target lost");
    s.add("max_time_s", &P::max_time_s, Range::open_closed(0, 3600), "s",
          "no convergence in this time: hold and report");
    s.add("ingress_standoff_m", &P::ingress_standoff_m, Range::gt(0.3), "m",
          "ingress vantages lie this far in front of the wall");
    return s;
  }();
  return schema;
}

const ParamSchema<LandingParams>& LandingParams::schema() {
  using P = LandingParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("descent_rate_mps", &P::descent_rate_mps, Range::open_closed(0, 1), "m/s",
          "v_des: x3(t+1) = x3(t) - v_des dt");
    s.add("radial_tol_m", &P::radial_tol_m, Range::gt(0), "m",
          "descend only while e_r(t) is within this at final_height_m; above it, within the "
          "cone of that angle seen from the top");
    s.add("final_height_m", &P::final_height_m, Range::gt(0), "m",
          "gear this high above the estimate: final descent");
    s.add("final_descent_rate_mps", &P::final_descent_rate_mps, Range::gt(0), "m/s",
          "the \"rapid\" decrease of the setpoint")
        .check([](const P& p) { return p.final_descent_rate_mps >= p.descent_rate_mps; },
               "must be >= descent_rate_mps");
    s.add("final_depth_m", &P::final_depth_m, Range::ge(0), "m",
          "final setpoint this far below the platform top");
    s.add("gear_height_m", &P::gear_height_m, Range::ge(0), "m", "body origin above the gear feet");
    s.add("gear_footprint_m", &P::gear_footprint_m, Range::gt(0), "m",
          "side of the landing gear (paper 4.1: approx. 15 cm)");
    s.add("fit_margin_m", &P::fit_margin_m, Range::ge(0), "m",
          "refuse a platform whose short side < footprint + 2 margin");
    s.add("touchdown_accel_mps2", &P::touchdown_accel_mps2, Range::gt(0.5), "m/s^2",
          "impact: specific force above g by this much (above the IMU noise)");
    s.add("touchdown_still_s", &P::touchdown_still_s, Range::open_closed(0, 10), "s",
          "or: not descending this long although commanded");
    s.add("lost_timeout_s", &P::lost_timeout_s, Range::open_closed(0, 60), "s",
          "target unseen this long during approach, not counting the descent onto the "
          "estimate (the top at the epipole): lost");
    s.add("lost_check_height_m", &P::lost_check_height_m, Range::ge(0), "m",
          "... checked only while the gear is higher above it");
    s.add("align_yaw_tol_deg", &P::align_yaw_tol_deg, Range::closed_open(0, 45), "deg",
          "the square gear is turned to the platform's edges (its yaw from vision, modulo 90 deg) "
          "and descends only within this yaw error; 0: no turn. A corner of a 15 cm gear turned "
          "25 deg on a 21.6 cm wide ream lands within mm of the edge (Monte Carlo landing_c: 3 of "
          "20 tipped off it after touch-down)");
    s.add("final_hold_speed_mps", &P::final_hold_speed_mps, Range::ge(0), "m/s",
          "beyond the paper: at final_height_m the final descent waits, holding above the "
          "platform, until the horizontal speed is within this and e_r within "
          "final_hold_radial_m for final_hold_settle_s (a gust that pushes the vehicle now carries "
          "it off the centre "
          "during the half second of the rapid descent); 0: never held (the paper)");
    s.add("final_hold_speed_max_mps", &P::final_hold_speed_max_mps, Range::ge(0), "m/s",
          "... the speed bound grows from final_hold_speed_mps to this over half of "
          "final_hold_timeout_s of waiting (a still moment is worth some wait, but in fast gusts "
          "the vehicle is rarely both centred and still); 0: it never grows")
        .check(
            [](const P& p) {
              return p.final_hold_speed_max_mps == 0 ||
                     p.final_hold_speed_max_mps >= p.final_hold_speed_mps;
            },
            "must be 0 or at least final_hold_speed_mps");
    s.add("final_hold_radial_m", &P::final_hold_radial_m, Range::gt(0), "m",
          "... and e_r within this (and within radial_tol_m): the rapid descent starts nearer "
          "the centre than the slow one needs. Over half of final_hold_timeout_s of waiting the "
          "radius grows to the room the measured top leaves around the gear, for e_r and where "
          "the vehicle heads over the rapid descent (an autopilot holding to centimetres)");
    s.add("final_hold_settle_s", &P::final_hold_settle_s, Range::ge(0), "s",
          "... both within for this long");
    s.add("final_hold_timeout_s", &P::final_hold_timeout_s, Range::gt(0), "s",
          "held this long without a calm moment: target lost (detection retry, then hold); over a "
          "moving platform, this long at the final height without a drop, or in all above it "
          "not matched well enough to descend: PLATFORM_TOO_FAST");
    s.add("final_pause_radial_m", &P::final_pause_radial_m, Range::ge(0), "m",
          "beyond the paper (as ArduPilot's PLND_XY_DIST_MAX): a gust that carries the vehicle "
          "more than this off the estimate during the final descent, with the gear still more "
          "than final_pause_min_height_m above the platform, stops the descent there until the "
          "final hold's calm moment comes again (final_hold_timeout_s without one: target lost); "
          "0: never paused")
        .check(
            [](const P& p) {
              return p.final_pause_radial_m == 0 ||
                     (p.final_hold_speed_mps > 0 && p.final_pause_radial_m > p.final_hold_radial_m);
            },
            "needs the final hold (final_hold_speed_mps > 0) and must exceed final_hold_radial_m");
    s.add("final_pause_min_height_m", &P::final_pause_min_height_m, Range::ge(0), "m",
          "... and only with the gear higher above the platform than this: lower, the descent is "
          "committed (the altitude loop's stop from final_descent_rate_mps would end on the top)")
        .check([](const P& p) { return p.final_pause_min_height_m < p.final_height_m; },
               "must be below final_height_m");
    s.add("precise_final", &P::precise_final, Range::any(), "",
          "beyond the paper: from the final hold (final_height_m above the platform) through the "
          "final descent the setpoints are marked precise (position_setpoint_t.MODE_PRECISE): "
          "the outer loop flies them on its precise lateral gains, so a gust moves the vehicle "
          "less there, where its offset becomes the touch-down's error");
    s.add("aim_gear", &P::aim_gear, Range::any(), "",
          "beyond the paper: the approach and the final descent put the gear's centre "
          "(gear_height_m below the body origin along the body's z axis) over the target, not "
          "the body origin. Tilted against the wind, the gear hangs downwind of the origin by "
          "gear_height_m sin(tilt); the vehicle lands where its feet touch and levels above them");
    return s;
  }();
  return schema;
}

const ParamSchema<IngressParams>& IngressParams::schema() {
  using P = IngressParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("standoff_m", &P::standoff_m, Range::gt(0.3), "m",
          "align on the normal this far in front of the opening");
    s.add("speed_mps", &P::speed_mps, Range::open_closed(0, 1), "m/s",
          "along the normal through the opening");
    s.add("lateral_tol_m", &P::lateral_tol_m, Range::gt(0), "m",
          "advance only while the lateral error is within");
    s.add("vertical_tol_m", &P::vertical_tol_m, Range::gt(0), "m", "... and the vertical error");
    s.add("pass_distance_m", &P::pass_distance_m, Range::gt(0), "m",
          "stop this far past the wall plane");
    s.add("align_tol_m", &P::align_tol_m, Range::gt(0), "m",
          "aligned when this close to the standoff point");
    s.add("align_speed_mps", &P::align_speed_mps, Range::gt(0), "m/s", "... and slower than this");
    s.add("align_settle_s", &P::align_settle_s, Range::closed(0, 30), "s", "... for this long");
    s.add("vehicle_span_m", &P::vehicle_span_m, Range::gt(0), "m",
          "rotor tip to rotor tip, across");
    s.add("vehicle_height_m", &P::vehicle_height_m, Range::gt(0), "m", "gear feet to rotor top");
    s.add("clearance_m", &P::clearance_m, Range::ge(0), "m",
          "refuse openings narrower than vehicle + 2 clearance");
    s.add("lost_timeout_s", &P::lost_timeout_s, Range::closed(0, 60), "s",
          "target unseen this long while aligning: lost; 0: no check, the converged estimate is "
          "flown as the paper's fixed fly-to-waypoint manoeuvre (3.4). Aligning on the normal "
          "moves the camera along its axis, where the opening at the image centre shows no "
          "parallax, and hovering gives no baseline at all: real vision goes quiet there "
          "(closed-loop flights)");
    return s;
  }();
  return schema;
}

const ParamSchema<FailsafeParams>& FailsafeParams::schema() {
  using P = FailsafeParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("pose_stale_s", &P::pose_stale_s, Range::open_closed(0, 2), "s",
          "mocap older: freeze the mission (the outer loop holds level)");
    s.add("pose_lost_s", &P::pose_lost_s, Range::le(10), "s",
          "mocap older: controlled descent, disarm on touch-down (bounded: a failsafe that never "
          "fires is none)")
        .check([](const P& p) { return p.pose_lost_s > p.pose_stale_s; },
               "must exceed pose_stale_s");
    s.add("descent_mps", &P::descent_mps, Range::open_closed(0, 1), "m/s",
          "failsafe descent when the pose is back");
    s.add("pose_recovered_s", &P::pose_recovered_s, Range::open_closed(0, 5), "s",
          "pose fresh again this long in the pose-lost failsafe: stop the descent and hold, "
          "waiting for the operator (descending blind onto a platform edge tips the vehicle)");
    s.add("vision_silent_s", &P::vision_silent_s, Range::open_closed(0, 60), "s",
          "no VISION_TARGET this long while searching or refining: the camera or the vision "
          "process is down; hold and wait for the operator instead of searching blind");
    s.add("abort_height_m", &P::abort_height_m, Range::gt(0.3), "m",
          "ABORT climbs to at least this height, world z");
    s.add("max_nudge_m", &P::max_nudge_m, Range::closed(0, 5), "m", "largest NUDGE offset");
    s.add("estimate_silent_s", &P::estimate_silent_s, Range::open_closed(0, 5), "s",
          "STATE_ESTIMATE heard once, then its newest estimate older than this: the estimate is "
          "LOST (failsafe descent), as if the estimator had said so (it publishes at the IMU "
          "rate, so 0.5 s is ~100 estimates missed)");
    s.add("require_estimate", &P::require_estimate, Range::any(), "",
          "true (flying without motion capture): TAKEOFF and GO are refused until a "
          "STATE_ESTIMATE says OK, also before the first one arrives; false: refused only while "
          "an estimate once heard is not OK, and without any STATE_ESTIMATE the autonomy flies "
          "on the pose alone");
    return s;
  }();
  return schema;
}

const ParamSchema<RestartParams>& RestartParams::schema() {
  using P = RestartParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("airborne_height_m", &P::airborne_height_m, Range::open_closed(0, 1), "m",
          "the first pose shows the vehicle flying when its gear is this far above the floor "
          "(geofence.min_W_m z; body z minus landing.gear_height_m). Below it a restart cannot "
          "tell a low hover from standing, and takes the previous instance's word (state file)");
    s.add("airborne_speed_mps", &P::airborne_speed_mps, Range::open_closed(0, 2), "m/s",
          "... or when it moves faster than this");
    s.add("state_max_age_s", &P::state_max_age_s, Range::closed(1, 3600), "s",
          "the node restores a state file written (heartbeat) at most this long ago by an "
          "instance of the same session (same boot, same parent process): a launcher restart, "
          "not a new flight");
    return s;
  }();
  return schema;
}

const ParamSchema<AutonomyParams>& AutonomyParams::schema() {
  using P = AutonomyParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("seed", &P::seed, Range::any(), "", "RNG seed of the refinement's vantage draws");
    s.add("accept_unsigned_commands", &P::accept_unsigned_commands, Range::any(), "",
          "accept OPERATOR_CMD with AUTH_NONE (testing only: anyone on the LAN could command)");
    s.add("operator_key_file", &P::operator_key_file, Range::any(), "",
          "HMAC key shared with the ground station (scripts/make-key); empty: signed commands "
          "are refused too")
        .path();
    // The verifier counts in whole microseconds and asserts a positive window: 1e-7 s reached it
    // (SIGABRT, restarted forever); beyond 30 s a recorded command stays replayable that long.
    s.add("command_max_age_s", &P::command_max_age_s, Range::closed(0.05, 30), "s",
          "signed commands older or newer than this (against the vehicle clock) are stale");
    s.add("vehicle_id", &P::vehicle_id, Range::any(), "",
          "signed commands must name it (ground_station.vehicle_id)")
        .check(
            [](const P& p) {
              return !p.vehicle_id.empty() && p.vehicle_id.size() <= 64 &&
                     p.vehicle_id.find_first_of(" \t\r\n\"'<>&") == std::string::npos;
            },
            "must be 1 to 64 characters without spaces, quotes or <>&");
    s.add("status_period_s", &P::status_period_s, Range::open_closed(0, 0.1), "s",
          "AUTONOMY_STATUS at least this often (>= 10 Hz)");
    s.add("hover_tol_m", &P::hover_tol_m, Range::gt(0), "m", "\"arrived\" at path and hold points");
    s.section("takeoff", &P::takeoff, TakeoffParams::schema(), "take-off");
    s.section("geofence", &P::geofence, GeofenceParams::schema(),
              "the flying area: every setpoint is clamped into this box");
    s.section("detection", &P::detection, DetectionParams::schema(),
              "paper 3.4.1 Platform Detection, 4.3: predefined search paths");
    s.section("refinement", &P::refinement, RefinementParams::schema(),
              "paper 3.4.1 Refinement of Estimate, eqs. 7-9");
    s.section("landing", &P::landing, LandingParams::schema(),
              "approach, landing: paper 3.4.1 Descent and Landing");
    s.section("ingress", &P::ingress, IngressParams::schema(),
              "approach, ingress: paper 3.4.2 (not flown in the paper)");
    s.section("failsafe", &P::failsafe, FailsafeParams::schema(),
              "lost motion capture, silent vision, the onboard estimate's health");
    s.section("restart", &P::restart, RestartParams::schema(),
              "a restart in flight holds and waits for the operator");
    s.section("moving_platform", &P::moving_platform, MovingLandingParams::schema(),
              "landing on a platform vision measures moving (autonomy/moving_landing.hpp)");
    s.check(
        "takeoff.height_m", [](const P& p) { return p.takeoff.height_m < p.geofence.max_W_m.z(); },
        "must be inside the geofence");
    return s;
  }();
  return schema;
}

void TakeoffParams::validate() const { schema().validate(*this); }
void GeofenceParams::validate() const { schema().validate(*this); }
void DetectionParams::validate() const { schema().validate(*this); }
void RefinementParams::validate() const { schema().validate(*this); }
void LandingParams::validate() const { schema().validate(*this); }
void IngressParams::validate() const { schema().validate(*this); }
void FailsafeParams::validate() const { schema().validate(*this); }
void RestartParams::validate() const { schema().validate(*this); }
void AutonomyParams::validate() const { schema().validate(*this); }

DownwardView downward_view(const CameraModel& camera, const Matrix3d& R_BC) {
  const double half_u = std::max(0.0, camera.width / 2.0 - kViewBorderPx) / camera.fx;
  const double half_v = std::max(0.0, camera.height / 2.0 - kViewBorderPx) / camera.fy;
  const bool u_long = half_u >= half_v;
  // The image's x (u) and y (v) axes in the body; the camera looks down, so both lie near the
  // body's x-y plane.
  const Vector3d axis = R_BC.col(u_long ? 0 : 1);
  return {std::max(half_u, half_v), std::min(half_u, half_v), std::atan2(axis.y(), axis.x())};
}

AutonomyParams load_params(const ParamNode& root) {
  AutonomyParams p;
  AutonomyParams::schema().read(root.child("autonomy"), p);
  // The downward camera is declared once, under cameras.downward, as vision and the simulator
  // read it.
  if (const auto cameras = root.optional_child("cameras");
      cameras && cameras->optional_child("downward")) {
    const CameraMount mount = load_camera_mount(root, "downward");
    p.downward_view = downward_view(load_camera_info(mount.camera_info_path), mount.R_BC);
    p.downward_view->offset_m = mount.t_B_C.head<2>().norm();
  }
  // The platform the vehicle follows is bounded by how fast its outer loop flies (the same file's
  // outer_loop section, as alight-outer-loop reads it).
  if (const auto outer = root.optional_child("outer_loop");
      outer && outer->has("max_feedforward_xy_mps")) {
    const double ff_mps = outer->get<double>("max_feedforward_xy_mps");
    outer->check(std::isfinite(ff_mps) && ff_mps > 0, "max_feedforward_xy_mps",
                 "must be a positive speed (the fastest platform followed derives from it)");
    p.moving_platform.max_speed_mps = followed_speed_mps(ff_mps);
  }
  return p;
}

AutonomyParams load_params(const std::string& vehicle_file) {
  return load_params(ParamNode::load_file(vehicle_file));
}

void fit_to_site(AutonomyParams& p, const SiteArea& site, const std::string& site_file) {
  if (!narrow_to_site(site, kSiteWallClearanceM, 0.5, p.geofence.min_W_m, p.geofence.max_W_m))
    throw ParamError(site_file, "area", site_text(site),
                     "leaves less than 0.5 m on an axis of the vehicle's autonomy.geofence, " +
                         std::to_string(kSiteWallClearanceM) + " m inside its walls");
  if (!(p.takeoff.height_m < p.geofence.max_W_m.z()))
    throw ParamError(site_file, "area.height_m", std::to_string(site.height_m),
                     "leaves no room above autonomy.takeoff.height_m (" +
                         std::to_string(p.takeoff.height_m) + " m) under the ceiling");
}

}  // namespace alight::autonomy

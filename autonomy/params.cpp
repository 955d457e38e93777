#include "autonomy/params.hpp"

#include <array>
#include <cmath>

#include "common/camera_mount.hpp"  // resolve_relative

namespace alight::autonomy {

namespace {
void read_v2(const ParamNode& n, const std::string& key, Vector2d& v) {
  std::array<double, 2> a{v.x(), v.y()};
  n.read(key, a);
  v = Vector2d(a[0], a[1]);
}
// validate() of a sub-struct, with the sub-section prepended to the key of its errors.
template <class P>
void validate_sub(const P& p, const std::string& prefix) {
  try {
    p.validate();
  } catch (const ParamError& e) {
    throw e.located("", prefix);
  }
}
}  // namespace

void TakeoffParams::validate() const {
  param_check(height_m > 0.3 && height_m < 10, "height_m", height_m, "must be in (0.3, 10) m");
  param_check(climb_rate_mps > 0 && climb_rate_mps <= 2, "climb_rate_mps", climb_rate_mps,
              "must be in (0, 2] m/s");
  param_check(reached_tol_m > 0, "reached_tol_m", reached_tol_m, "must be > 0");
}

void GeofenceParams::validate() const {
  for (int i = 0; i < 3; ++i) {
    param_check(max_W_m[i] > min_W_m[i] + 0.5, "max_W_m", max_W_m.transpose(),
                "must exceed min_W_m by 0.5 m on every axis");
  }
}

void DetectionParams::validate() const {
  param_check(speed_mps > 0 && speed_mps <= 2, "speed_mps", speed_mps, "must be in (0, 2] m/s");
  param_check((landing_area_max_W_m - landing_area_min_W_m).minCoeff() >= 0, "landing_area_max_W_m",
              landing_area_max_W_m.transpose(), "must not be below landing_area_min_W_m");
  param_check(lane_spacing_m > 0.05, "lane_spacing_m", lane_spacing_m, "must be > 0.05 m");
  param_check(landing_height_m > 0.3, "landing_height_m", landing_height_m, "must be > 0.3 m");
  param_check((ingress_end_W_m - ingress_start_W_m).norm() > 0.1, "ingress_end_W_m",
              ingress_end_W_m.transpose(), "must be > 0.1 m from ingress_start_W_m");
  param_check(max_retries >= 0 && max_retries <= 20, "max_retries", max_retries,
              "must be in [0, 20]");
}

void RefinementParams::validate() const {
  param_check(n_min >= 2, "n_min", n_min, "must be >= 2 (eq. 8 compares two means)");
  param_check(eps_horz_m > 0, "eps_horz_m", eps_horz_m, "must be > 0");
  param_check(eps_vert_m > 0, "eps_vert_m", eps_vert_m, "must be > 0");
  param_check(cutoff_m > 0, "cutoff_m", cutoff_m, "must be > 0");
  param_check(prior_sigma_m > 0, "prior_sigma_m", prior_sigma_m, "must be > 0");
  param_check(vantage_sigma_floor_m >= 0, "vantage_sigma_floor_m", vantage_sigma_floor_m,
              "must be >= 0");
  param_check(vantage_reach_tol_m > 0, "vantage_reach_tol_m", vantage_reach_tol_m, "must be > 0");
  param_check(vantage_dwell_s >= 0 && vantage_dwell_s <= 10, "vantage_dwell_s", vantage_dwell_s,
              "must be in [0, 10] s");
  param_check(vantage_timeout_s > vantage_dwell_s && vantage_timeout_s <= 60, "vantage_timeout_s",
              vantage_timeout_s, "must exceed vantage_dwell_s and be <= 60 s");
  param_check(gate_chi2 > 0, "gate_chi2", gate_chi2, "must be > 0");
  param_check(gate_min_n >= 3, "gate_min_n", gate_min_n, "must be >= 3");
  param_check(gate_floor_sigma_m > 0, "gate_floor_sigma_m", gate_floor_sigma_m, "must be > 0");
  param_check(max_consecutive_rejections >= 1, "max_consecutive_rejections",
              max_consecutive_rejections, "must be >= 1");
  param_check(lost_timeout_s > 0 && lost_timeout_s <= 60, "lost_timeout_s", lost_timeout_s,
              "must be in (0, 60] s");
  param_check(max_time_s > 0 && max_time_s <= 3600, "max_time_s", max_time_s,
              "must be in (0, 3600] s");
  param_check(ingress_standoff_m > 0.3, "ingress_standoff_m", ingress_standoff_m,
              "must be > 0.3 m");
}

void LandingParams::validate() const {
  param_check(descent_rate_mps > 0 && descent_rate_mps <= 1, "descent_rate_mps", descent_rate_mps,
              "must be in (0, 1] m/s");
  param_check(radial_tol_m > 0, "radial_tol_m", radial_tol_m, "must be > 0");
  param_check(final_height_m > 0, "final_height_m", final_height_m, "must be > 0");
  param_check(final_descent_rate_mps >= descent_rate_mps, "final_descent_rate_mps",
              final_descent_rate_mps, "must be >= descent_rate_mps");
  param_check(final_depth_m >= 0, "final_depth_m", final_depth_m, "must be >= 0");
  param_check(gear_height_m >= 0, "gear_height_m", gear_height_m, "must be >= 0");
  param_check(gear_footprint_m > 0, "gear_footprint_m", gear_footprint_m, "must be > 0");
  param_check(fit_margin_m >= 0, "fit_margin_m", fit_margin_m, "must be >= 0");
  param_check(touchdown_accel_mps2 > 0.5, "touchdown_accel_mps2", touchdown_accel_mps2,
              "must be > 0.5 m/s^2 (above the IMU noise)");
  param_check(touchdown_still_s > 0 && touchdown_still_s <= 10, "touchdown_still_s",
              touchdown_still_s, "must be in (0, 10] s");
  param_check(lost_timeout_s > 0 && lost_timeout_s <= 60, "lost_timeout_s", lost_timeout_s,
              "must be in (0, 60] s");
  param_check(lost_check_height_m >= 0, "lost_check_height_m", lost_check_height_m, "must be >= 0");
  param_check(align_yaw_tol_deg >= 0 && align_yaw_tol_deg < 45, "align_yaw_tol_deg",
              align_yaw_tol_deg, "must be in [0, 45) (0: no turn)");
}

void IngressParams::validate() const {
  param_check(standoff_m > 0.3, "standoff_m", standoff_m, "must be > 0.3 m");
  param_check(speed_mps > 0 && speed_mps <= 1, "speed_mps", speed_mps, "must be in (0, 1] m/s");
  param_check(lateral_tol_m > 0, "lateral_tol_m", lateral_tol_m, "must be > 0");
  param_check(vertical_tol_m > 0, "vertical_tol_m", vertical_tol_m, "must be > 0");
  param_check(pass_distance_m > 0, "pass_distance_m", pass_distance_m, "must be > 0");
  param_check(align_tol_m > 0, "align_tol_m", align_tol_m, "must be > 0");
  param_check(align_speed_mps > 0, "align_speed_mps", align_speed_mps, "must be > 0");
  param_check(align_settle_s >= 0 && align_settle_s <= 30, "align_settle_s", align_settle_s,
              "must be in [0, 30] s");
  param_check(vehicle_span_m > 0, "vehicle_span_m", vehicle_span_m, "must be > 0");
  param_check(vehicle_height_m > 0, "vehicle_height_m", vehicle_height_m, "must be > 0");
  param_check(clearance_m >= 0, "clearance_m", clearance_m, "must be >= 0");
  param_check(lost_timeout_s >= 0 && lost_timeout_s <= 60, "lost_timeout_s", lost_timeout_s,
              "must be in [0, 60] s (0: no check)");
}

void FailsafeParams::validate() const {
  param_check(pose_stale_s > 0 && pose_stale_s <= 2, "pose_stale_s", pose_stale_s,
              "must be in (0, 2] s");
  param_check(pose_lost_s > pose_stale_s && pose_lost_s <= 10, "pose_lost_s", pose_lost_s,
              "must exceed pose_stale_s and be <= 10 s (a failsafe that never fires)");
  param_check(descent_mps > 0 && descent_mps <= 1, "descent_mps", descent_mps, "must be in (0, 1]");
  param_check(pose_recovered_s > 0 && pose_recovered_s <= 5, "pose_recovered_s", pose_recovered_s,
              "must be in (0, 5] s");
  param_check(vision_silent_s > 0 && vision_silent_s <= 60, "vision_silent_s", vision_silent_s,
              "must be in (0, 60] s");
  param_check(abort_height_m > 0.3, "abort_height_m", abort_height_m, "must be > 0.3 m");
  param_check(max_nudge_m >= 0 && max_nudge_m <= 5, "max_nudge_m", max_nudge_m,
              "must be in [0, 5] m");
}

void RestartParams::validate() const {
  param_check(airborne_height_m > 0 && airborne_height_m <= 1, "airborne_height_m",
              airborne_height_m, "must be in (0, 1] m");
  param_check(airborne_speed_mps > 0 && airborne_speed_mps <= 2, "airborne_speed_mps",
              airborne_speed_mps, "must be in (0, 2] m/s");
  param_check(state_max_age_s >= 1 && state_max_age_s <= 3600, "state_max_age_s", state_max_age_s,
              "must be in [1, 3600] s");
}

void AutonomyParams::validate() const {
  param_check(status_period_s > 0 && status_period_s <= 0.1, "status_period_s", status_period_s,
              "must be in (0, 0.1] s (AUTONOMY_STATUS at >= 10 Hz)");
  param_check(hover_tol_m > 0, "hover_tol_m", hover_tol_m, "must be > 0");
  // The verifier counts in whole microseconds and asserts a positive window: 1e-7 s reached it
  // (SIGABRT, restarted forever); beyond 30 s a recorded command stays replayable that long.
  param_check(command_max_age_s >= 0.05 && command_max_age_s <= 30, "command_max_age_s",
              command_max_age_s, "must be in [0.05, 30] s");
  validate_sub(takeoff, "takeoff");
  validate_sub(geofence, "geofence");
  validate_sub(detection, "detection");
  validate_sub(refinement, "refinement");
  validate_sub(landing, "landing");
  validate_sub(ingress, "ingress");
  validate_sub(failsafe, "failsafe");
  validate_sub(restart, "restart");
  param_check(takeoff.height_m < geofence.max_W_m.z(), "takeoff.height_m", takeoff.height_m,
              "must be inside the geofence");
}

AutonomyParams load_params(const ParamNode& root) {
  const ParamNode n = root.child("autonomy");
  AutonomyParams p;
  int64_t seed = static_cast<int64_t>(p.seed);
  n.read("seed", seed);
  n.check(seed >= 0, "seed", "must be >= 0");
  p.seed = static_cast<uint64_t>(seed);
  n.read("accept_unsigned_commands", p.accept_unsigned_commands);
  n.read("operator_key_file", p.operator_key_file);
  if (!p.operator_key_file.empty())
    p.operator_key_file = resolve_relative(n.file(), p.operator_key_file);
  n.read("command_max_age_s", p.command_max_age_s);
  n.read("vehicle_id", p.vehicle_id);
  n.check(!p.vehicle_id.empty() && p.vehicle_id.size() <= 64 &&
              p.vehicle_id.find_first_of(" \t\r\n\"'<>&") == std::string::npos,
          "vehicle_id", "must be 1 to 64 characters without spaces, quotes or <>&");
  n.read("status_period_s", p.status_period_s);
  n.read("hover_tol_m", p.hover_tol_m);
  if (auto c = n.optional_child("takeoff")) {
    c->read("height_m", p.takeoff.height_m);
    c->read("climb_rate_mps", p.takeoff.climb_rate_mps);
    c->read("reached_tol_m", p.takeoff.reached_tol_m);
    c->finish();
  }
  if (auto c = n.optional_child("geofence")) {
    c->read("min_W_m", p.geofence.min_W_m);
    c->read("max_W_m", p.geofence.max_W_m);
    c->finish();
  }
  if (auto c = n.optional_child("detection")) {
    auto& d = p.detection;
    c->read("speed_mps", d.speed_mps);
    read_v2(*c, "landing_area_min_W_m", d.landing_area_min_W_m);
    read_v2(*c, "landing_area_max_W_m", d.landing_area_max_W_m);
    c->read("lane_spacing_m", d.lane_spacing_m);
    c->read("landing_height_m", d.landing_height_m);
    c->read("ingress_start_W_m", d.ingress_start_W_m);
    c->read("ingress_end_W_m", d.ingress_end_W_m);
    c->read("ingress_yaw_deg", d.ingress_yaw_deg);
    c->read("max_retries", d.max_retries);
    c->finish();
  }
  if (auto c = n.optional_child("refinement")) {
    auto& r = p.refinement;
    c->read("n_min", r.n_min);
    c->read("eps_horz_m", r.eps_horz_m);
    c->read("eps_vert_m", r.eps_vert_m);
    c->read("cutoff_m", r.cutoff_m);
    c->read("prior_sigma_m", r.prior_sigma_m);
    c->read("vantage_sigma_floor_m", r.vantage_sigma_floor_m);
    c->read("vantage_reach_tol_m", r.vantage_reach_tol_m);
    c->read("vantage_dwell_s", r.vantage_dwell_s);
    c->read("one_waypoint_per_vantage", r.one_waypoint_per_vantage);
    c->read("vantage_timeout_s", r.vantage_timeout_s);
    c->read("gate_chi2", r.gate_chi2);
    c->read("gate_min_n", r.gate_min_n);
    c->read("gate_floor_sigma_m", r.gate_floor_sigma_m);
    c->read("max_consecutive_rejections", r.max_consecutive_rejections);
    c->read("lost_timeout_s", r.lost_timeout_s);
    c->read("max_time_s", r.max_time_s);
    c->read("ingress_standoff_m", r.ingress_standoff_m);
    c->finish();
  }
  if (auto c = n.optional_child("landing")) {
    auto& l = p.landing;
    c->read("descent_rate_mps", l.descent_rate_mps);
    c->read("radial_tol_m", l.radial_tol_m);
    c->read("final_height_m", l.final_height_m);
    c->read("final_descent_rate_mps", l.final_descent_rate_mps);
    c->read("final_depth_m", l.final_depth_m);
    c->read("gear_height_m", l.gear_height_m);
    c->read("gear_footprint_m", l.gear_footprint_m);
    c->read("fit_margin_m", l.fit_margin_m);
    c->read("touchdown_accel_mps2", l.touchdown_accel_mps2);
    c->read("touchdown_still_s", l.touchdown_still_s);
    c->read("lost_timeout_s", l.lost_timeout_s);
    c->read("lost_check_height_m", l.lost_check_height_m);
    c->read("align_yaw_tol_deg", l.align_yaw_tol_deg);
    c->finish();
  }
  if (auto c = n.optional_child("ingress")) {
    auto& i = p.ingress;
    c->read("standoff_m", i.standoff_m);
    c->read("speed_mps", i.speed_mps);
    c->read("lateral_tol_m", i.lateral_tol_m);
    c->read("vertical_tol_m", i.vertical_tol_m);
    c->read("pass_distance_m", i.pass_distance_m);
    c->read("align_tol_m", i.align_tol_m);
    c->read("align_speed_mps", i.align_speed_mps);
    c->read("align_settle_s", i.align_settle_s);
    c->read("vehicle_span_m", i.vehicle_span_m);
    c->read("vehicle_height_m", i.vehicle_height_m);
    c->read("clearance_m", i.clearance_m);
    c->read("lost_timeout_s", i.lost_timeout_s);
    c->finish();
  }
  if (auto c = n.optional_child("failsafe")) {
    auto& f = p.failsafe;
    c->read("pose_stale_s", f.pose_stale_s);
    c->read("pose_lost_s", f.pose_lost_s);
    c->read("descent_mps", f.descent_mps);
    c->read("pose_recovered_s", f.pose_recovered_s);
    c->read("vision_silent_s", f.vision_silent_s);
    c->read("abort_height_m", f.abort_height_m);
    c->read("max_nudge_m", f.max_nudge_m);
    c->finish();
  }
  if (auto c = n.optional_child("restart")) {
    auto& r = p.restart;
    c->read("airborne_height_m", r.airborne_height_m);
    c->read("airborne_speed_mps", r.airborne_speed_mps);
    c->read("state_max_age_s", r.state_max_age_s);
    c->finish();
  }
  n.validate(p);
  n.finish();
  return p;
}

AutonomyParams load_params(const std::string& vehicle_file) {
  return load_params(ParamNode::load_file(vehicle_file));
}

}  // namespace alight::autonomy

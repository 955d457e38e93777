#include "outer_loop/params.hpp"

#include <cmath>
#include <utility>

namespace alight::outer_loop {

void OuterLoopParams::validate() const {
  // Non-finite values first: every comparison below is false for NaN, and an infinite timeout
  // switches its failsafe off.
  const std::pair<const char*, double> all[] = {
      {"mass_kg", mass_kg},
      {"gravity_mps2", gravity_mps2},
      {"kp_xy_per_s2", kp_xy_per_s2},
      {"kd_xy_per_s", kd_xy_per_s},
      {"ki_xy_per_s3", ki_xy_per_s3},
      {"i_limit_xy_mps2", i_limit_xy_mps2},
      {"kp_z_per_s2", kp_z_per_s2},
      {"kd_z_per_s", kd_z_per_s},
      {"ki_z_per_s3", ki_z_per_s3},
      {"i_limit_z_mps2", i_limit_z_mps2},
      {"max_tilt_deg", max_tilt_deg},
      {"thrust_min_N", thrust_min_N},
      {"thrust_max_N", thrust_max_N},
      {"max_accel_z_mps2", max_accel_z_mps2},
      {"yaw_kp_per_s", yaw_kp_per_s},
      {"max_yaw_rate_dps", max_yaw_rate_dps},
      {"pose_stale_s", pose_stale_s},
      {"pose_lost_s", pose_lost_s},
      {"failsafe_descent_mps", failsafe_descent_mps},
      {"failsafe_descent_accel_mps2", failsafe_descent_accel_mps2},
      {"drag_per_s", drag_per_s},
      {"failsafe_disarm_after_s", failsafe_disarm_after_s},
      {"setpoint_stale_s", setpoint_stale_s},
      {"setpoint_lost_s", setpoint_lost_s},
      {"setpoint_lost_descent_mps", setpoint_lost_descent_mps},
      {"landed_still_s", landed_still_s},
      {"land_detect_s", land_detect_s},
      {"land_vz_mps", land_vz_mps},
      {"land_accel_mps2", land_accel_mps2},
      {"i_zone_m", i_zone_m},
      {"i_still_mps", i_still_mps},
      {"max_dt_s", max_dt_s},
  };
  for (const auto& [key, value] : all)
    param_check(std::isfinite(value), key, value, "must be finite");

  param_check(mass_kg > 0.0 && mass_kg < 50.0, "mass_kg", mass_kg, "must be in (0, 50) kg");
  param_check(gravity_mps2 > 9.0 && gravity_mps2 < 10.5, "gravity_mps2", gravity_mps2,
              "must be Earth's gravity (9..10.5 m/s^2)");
  param_check(kp_xy_per_s2 > 0.0, "kp_xy_per_s2", kp_xy_per_s2, "must be > 0");
  param_check(kd_xy_per_s > 0.0, "kd_xy_per_s", kd_xy_per_s, "must be > 0");
  param_check(ki_xy_per_s3 >= 0.0, "ki_xy_per_s3", ki_xy_per_s3, "must be >= 0");
  param_check(i_limit_xy_mps2 >= 0.0, "i_limit_xy_mps2", i_limit_xy_mps2, "must be >= 0");
  param_check(kp_z_per_s2 > 0.0, "kp_z_per_s2", kp_z_per_s2, "must be > 0");
  param_check(kd_z_per_s > 0.0, "kd_z_per_s", kd_z_per_s, "must be > 0");
  param_check(ki_z_per_s3 >= 0.0, "ki_z_per_s3", ki_z_per_s3, "must be >= 0");
  param_check(i_limit_z_mps2 >= 0.0, "i_limit_z_mps2", i_limit_z_mps2, "must be >= 0");
  param_check(max_tilt_deg > 0.0 && max_tilt_deg <= 45.0, "max_tilt_deg", max_tilt_deg,
              "must be in (0, 45] deg");
  param_check(thrust_min_N >= 0.0, "thrust_min_N", thrust_min_N, "must be >= 0");
  param_check(thrust_max_N > mass_kg * gravity_mps2 * 1.1, "thrust_max_N", thrust_max_N,
              "must exceed the hover thrust mass_kg * g by 10% at least");
  param_check(thrust_min_N < mass_kg * gravity_mps2 * 0.9, "thrust_min_N", thrust_min_N,
              "must be below 90% of the hover thrust mass_kg * g");
  param_check(max_accel_z_mps2 > 0.0 && max_accel_z_mps2 < gravity_mps2, "max_accel_z_mps2",
              max_accel_z_mps2, "must be in (0, g)");
  param_check(yaw_kp_per_s >= 0.0, "yaw_kp_per_s", yaw_kp_per_s, "must be >= 0");
  param_check(max_yaw_rate_dps > 0.0, "max_yaw_rate_dps", max_yaw_rate_dps, "must be > 0");
  param_check(pose_stale_s > 0.0 && pose_stale_s <= 2.0, "pose_stale_s", pose_stale_s,
              "must be in (0, 2] s");
  param_check(pose_lost_s > pose_stale_s, "pose_lost_s", pose_lost_s, "must exceed pose_stale_s");
  param_check(pose_lost_s <= 5.0, "pose_lost_s", pose_lost_s,
              "must be <= 5 s (without pose the vehicle holds level open loop until then)");
  param_check(failsafe_descent_mps > 0.0 && failsafe_descent_mps <= 1.0, "failsafe_descent_mps",
              failsafe_descent_mps, "must be in (0, 1] m/s");
  param_check(failsafe_descent_accel_mps2 > 0.0 && failsafe_descent_accel_mps2 < 5.0,
              "failsafe_descent_accel_mps2", failsafe_descent_accel_mps2, "must be in (0, 5)");
  param_check(drag_per_s >= 0.0 && drag_per_s < 2.0, "drag_per_s", drag_per_s, "must be in [0, 2)");
  param_check(i_zone_m > 0.0, "i_zone_m", i_zone_m, "must be > 0");
  param_check(i_still_mps >= 0.0, "i_still_mps", i_still_mps, "must be >= 0");
  param_check(failsafe_disarm_after_s > 0.0 && failsafe_disarm_after_s <= 120.0,
              "failsafe_disarm_after_s", failsafe_disarm_after_s, "must be in (0, 120] s");
  param_check(setpoint_stale_s > 0.0 && setpoint_stale_s <= 5.0, "setpoint_stale_s",
              setpoint_stale_s, "must be in (0, 5] s");
  param_check(setpoint_lost_s > setpoint_stale_s, "setpoint_lost_s", setpoint_lost_s,
              "must exceed setpoint_stale_s");
  param_check(setpoint_lost_s <= 30.0, "setpoint_lost_s", setpoint_lost_s,
              "must be <= 30 s (without setpoints the vehicle holds position until then)");
  param_check(setpoint_lost_descent_mps > 0.0 && setpoint_lost_descent_mps <= 1.0,
              "setpoint_lost_descent_mps", setpoint_lost_descent_mps, "must be in (0, 1] m/s");
  param_check(landed_still_s > 0.0 && landed_still_s <= 10.0, "landed_still_s", landed_still_s,
              "must be in (0, 10] s");
  param_check(land_detect_s > 0.0 && land_detect_s <= 5.0, "land_detect_s", land_detect_s,
              "must be in (0, 5] s");
  param_check(land_vz_mps > 0.0 && land_vz_mps <= 0.5, "land_vz_mps", land_vz_mps,
              "must be in (0, 0.5] m/s");
  param_check(land_accel_mps2 > 0.0 && land_accel_mps2 < max_accel_z_mps2, "land_accel_mps2",
              land_accel_mps2, "must be in (0, max_accel_z_mps2)");
  param_check(max_dt_s > 0.0 && max_dt_s <= 0.2, "max_dt_s", max_dt_s, "must be in (0, 0.2] s");
}

OuterLoopParams load_params(const ParamNode& root) {
  const ParamNode n = root.child("outer_loop");
  OuterLoopParams p;
  n.require("mass_kg", p.mass_kg);
  n.read("gravity_mps2", p.gravity_mps2);
  n.read("kp_xy_per_s2", p.kp_xy_per_s2);
  n.read("kd_xy_per_s", p.kd_xy_per_s);
  n.read("ki_xy_per_s3", p.ki_xy_per_s3);
  n.read("i_limit_xy_mps2", p.i_limit_xy_mps2);
  n.read("kp_z_per_s2", p.kp_z_per_s2);
  n.read("kd_z_per_s", p.kd_z_per_s);
  n.read("ki_z_per_s3", p.ki_z_per_s3);
  n.read("i_limit_z_mps2", p.i_limit_z_mps2);
  n.read("max_tilt_deg", p.max_tilt_deg);
  n.read("thrust_min_N", p.thrust_min_N);
  n.read("thrust_max_N", p.thrust_max_N);
  n.read("max_accel_z_mps2", p.max_accel_z_mps2);
  n.read("yaw_kp_per_s", p.yaw_kp_per_s);
  n.read("max_yaw_rate_dps", p.max_yaw_rate_dps);
  n.read("pose_stale_s", p.pose_stale_s);
  n.read("pose_lost_s", p.pose_lost_s);
  n.read("failsafe_descent_mps", p.failsafe_descent_mps);
  n.read("failsafe_descent_accel_mps2", p.failsafe_descent_accel_mps2);
  n.read("failsafe_disarm_after_s", p.failsafe_disarm_after_s);
  n.read("drag_per_s", p.drag_per_s);
  n.read("land_detect_s", p.land_detect_s);
  n.read("land_vz_mps", p.land_vz_mps);
  n.read("land_accel_mps2", p.land_accel_mps2);
  n.read("i_zone_m", p.i_zone_m);
  n.read("i_still_mps", p.i_still_mps);
  n.read("setpoint_stale_s", p.setpoint_stale_s);
  n.read("setpoint_lost_s", p.setpoint_lost_s);
  n.read("setpoint_lost_descent_mps", p.setpoint_lost_descent_mps);
  n.read("landed_still_s", p.landed_still_s);
  n.read("max_dt_s", p.max_dt_s);
  n.validate(p);
  n.finish();
  return p;
}

OuterLoopParams load_params(const std::string& vehicle_file) {
  return load_params(ParamNode::load_file(vehicle_file));
}

}  // namespace alight::outer_loop

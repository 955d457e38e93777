#include "outer_loop/params.hpp"

namespace alight::outer_loop {

const ParamSchema<OuterLoopParams>& OuterLoopParams::schema() {
  using P = OuterLoopParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("mass_kg", &P::mass_kg, Range::open(0, 50), "kg",
          "controller's nominal vehicle mass (hover thrust = m g)")
        .required();
    s.add("gravity_mps2", &P::gravity_mps2, Range::open(9, 10.5), "m/s^2", "Earth's gravity");

    // Lateral (x, y) PD + optional I on position, turned into roll / pitch.
    s.add("kp_xy_per_s2", &P::kp_xy_per_s2, Range::gt(0), "1/s^2",
          "position gain: commanded acceleration per metre of error");
    s.add("kd_xy_per_s", &P::kd_xy_per_s, Range::gt(0), "1/s",
          "velocity gain: commanded acceleration per m/s of error");
    s.add("ki_xy_per_s3", &P::ki_xy_per_s3, Range::ge(0), "1/s^3",
          "lateral integral gain; 0 disables the integrator");
    s.add("i_limit_xy_mps2", &P::i_limit_xy_mps2, Range::ge(0), "m/s^2",
          "anti-windup: largest lateral integral contribution");
    // Stiffer lateral gains where autonomy asks for them (landing's final hold and descent):
    // there a gust's offset is the touch-down's error, while elsewhere the vision wants the
    // vehicle's own motion (its baseline) more than a tight hold.
    s.add("precise_kp_xy_per_s2", &P::precise_kp_xy_per_s2, Range::gt(0), "1/s^2",
          "kp_xy_per_s2 for setpoints marked precise (MODE_PRECISE)");
    s.add("precise_kd_xy_per_s", &P::precise_kd_xy_per_s, Range::gt(0), "1/s",
          "kd_xy_per_s for setpoints marked precise");
    s.add("precise_ki_xy_per_s3", &P::precise_ki_xy_per_s3, Range::ge(0), "1/s^3",
          "ki_xy_per_s3 for setpoints marked precise (the integral carries over: it is an "
          "acceleration, so switching gains does not step it)");

    // Altitude PD + I with gravity feed-forward.
    s.add("kp_z_per_s2", &P::kp_z_per_s2, Range::gt(0), "1/s^2", "altitude position gain");
    s.add("kd_z_per_s", &P::kd_z_per_s, Range::gt(0), "1/s", "altitude velocity gain");
    s.add("ki_z_per_s3", &P::ki_z_per_s3, Range::ge(0), "1/s^3",
          "altitude integral gain; 0 disables");
    s.add("i_limit_z_mps2", &P::i_limit_z_mps2, Range::ge(0), "m/s^2",
          "anti-windup: largest altitude integral contribution");

    s.add("max_tilt_deg", &P::max_tilt_deg, Range::open_closed(0, 45), "deg",
          "largest commanded roll / pitch (and tilt of the thrust)");
    s.add("thrust_min_N", &P::thrust_min_N, Range::ge(0), "N",
          "smallest collective thrust while armed")
        .check([](const P& p) { return p.thrust_min_N < p.mass_kg * p.gravity_mps2 * 0.9; },
               "must be below 90% of the hover thrust mass_kg * g");
    s.add("thrust_max_N", &P::thrust_max_N, Range::any(), "N", "largest collective thrust")
        .check([](const P& p) { return p.thrust_max_N > p.mass_kg * p.gravity_mps2 * 1.1; },
               "must exceed the hover thrust mass_kg * g by 10% at least");
    s.add("max_accel_z_mps2", &P::max_accel_z_mps2, Range::gt(0), "m/s^2",
          "largest commanded vertical acceleration magnitude")
        .check([](const P& p) { return p.max_accel_z_mps2 < p.gravity_mps2; }, "must be in (0, g)");
    s.add("yaw_kp_per_s", &P::yaw_kp_per_s, Range::ge(0), "1/s",
          "yaw rate per radian of heading error");
    s.add("max_yaw_rate_dps", &P::max_yaw_rate_dps, Range::gt(0), "deg/s",
          "largest commanded yaw rate");

    // Stale inputs (never fly on old data); ages are measured against the newest input time.
    s.add("pose_stale_s", &P::pose_stale_s, Range::open_closed(0, 2), "s",
          "pose older than this: level attitude, hover thrust");
    s.add("pose_lost_s", &P::pose_lost_s, Range::le(5), "s",
          "pose older than this: open-loop slow descent (without pose the vehicle holds level "
          "open loop until then)")
        .check([](const P& p) { return p.pose_lost_s > p.pose_stale_s; },
               "must exceed pose_stale_s");
    s.add("failsafe_descent_mps", &P::failsafe_descent_mps, Range::open_closed(0, 1), "m/s",
          "open-loop descent speed without pose");
    s.add("failsafe_descent_accel_mps2", &P::failsafe_descent_accel_mps2, Range::open(0, 5),
          "m/s^2", "how hard that descent is started");
    s.add("failsafe_disarm_after_s", &P::failsafe_disarm_after_s, Range::open_closed(0, 120), "s",
          "without pose, disarm this long into the descent (the flying area is lower than 8 m)");
    s.add("drag_per_s", &P::drag_per_s, Range::closed_open(0, 2), "1/s",
          "linear drag over mass: without pose the descent speed is held open loop by "
          "thrust = m (g - drag v)");
    s.add("land_detect_s", &P::land_detect_s, Range::open_closed(0, 5), "s",
          "land detector (as PX4's; a motors-off setpoint without KILL is honoured only on the "
          "ground): on the ground once this long with the demand below");
    s.add("land_vz_mps", &P::land_vz_mps, Range::open_closed(0, 0.5), "m/s",
          "land detector: no faster vertically than this");
    s.add("land_accel_mps2", &P::land_accel_mps2, Range::gt(0), "m/s^2",
          "land detector: the position loop asks for at least this much downward acceleration "
          "(the ground holds the vehicle up)")
        .check([](const P& p) { return p.land_accel_mps2 < p.max_accel_z_mps2; },
               "must be in (0, max_accel_z_mps2)");
    s.add("land_max_descent_mps", &P::land_max_descent_mps, Range::open_closed(0, 2), "m/s",
          "a refused motors-off keeps descending at the speed autonomy last commanded, at most "
          "this (at least setpoint_lost_descent_mps)");
    s.add("land_contact_cut", &P::land_contact_cut, Range::any(), "",
          "beyond the land detector: a landing (a refused motors-off) that has descended and is "
          "then held up by the ground cuts the thrust to thrust_min_N at once (PX4's "
          "maybe-landed). Otherwise the thrust stays near hover until the detector's verdict, "
          "the gear carries almost no weight and the wind slides the levelled vehicle across the "
          "top. A contact that was not the ground ends itself: the vehicle falls, and faster than "
          "land_vz_mps it is no longer held up");
    // The autopilot's own limits, as PX4 and ArduPilot keep them whatever the offboard
    // setpoints say: a forged or faulty setpoint stream cannot fly the vehicle out of the room
    // or faster than it can stop.
    s.add("geofence_min_W_m", &P::geofence_min_W_m, Range::any(), "m",
          "flying area's lower corner, world (setpoints are kept 0.2 m inside it; leaving it is "
          "a failsafe: hold failsafe_hold_s, then land). Autonomy's own geofence lies inside it")
        .required();
    s.add("geofence_max_W_m", &P::geofence_max_W_m, Range::any(), "m",
          "flying area's upper corner, world")
        .required()
        .check(
            [](const P& p) {
              return (p.geofence_max_W_m - p.geofence_min_W_m).minCoeff() > 2 * kFenceInsetM;
            },
            "must exceed geofence_min_W_m by more than 0.4 m on every axis");
    s.add("max_speed_xy_mps", &P::max_speed_xy_mps, Range::open_closed(0, 10), "m/s",
          "horizontal speed the position loop never asks for more of (a far setpoint is "
          "approached at this speed, relative to the setpoint's own motion)");
    s.add("max_feedforward_xy_mps", &P::max_feedforward_xy_mps, Range::open_closed(0, 10), "m/s",
          "a setpoint's own horizontal velocity (a moving platform's) is followed up to this; "
          "autonomy follows a platform up to 0.8 of it");
    s.add("max_speed_z_mps", &P::max_speed_z_mps, Range::open_closed(0, 5), "m/s",
          "vertical speed the position loop never asks for more of");
    s.add("failsafe_hold_s", &P::failsafe_hold_s, Range::closed(0, 30), "s",
          "the landing failsafe (the geofence left) first holds this long");
    s.add("i_zone_m", &P::i_zone_m, Range::gt(0), "m",
          "integrate only while the error is smaller (no windup during large steps)");
    s.add("i_still_mps", &P::i_still_mps, Range::ge(0), "m/s",
          "... or while slower than this (steady offsets)");
    s.add("setpoint_stale_s", &P::setpoint_stale_s, Range::open_closed(0, 5), "s",
          "setpoint older than this: hold where it went stale");
    s.add("setpoint_lost_s", &P::setpoint_lost_s, Range::le(30), "s",
          "setpoint older than this: slow descent on motion capture (without setpoints the "
          "vehicle holds position until then)")
        .check([](const P& p) { return p.setpoint_lost_s > p.setpoint_stale_s; },
               "must exceed setpoint_stale_s");
    s.add("setpoint_lost_descent_mps", &P::setpoint_lost_descent_mps, Range::open_closed(0, 1),
          "m/s", "descent speed with pose but no setpoint");
    s.add("landed_still_s", &P::landed_still_s, Range::open_closed(0, 10), "s",
          "with no setpoint: disarm after this long not descending although commanded to (on "
          "the ground)");
    s.add("max_dt_s", &P::max_dt_s, Range::open_closed(0, 0.2), "s",
          "larger input gaps are integrated as this step");
    return s;
  }();
  return schema;
}

void OuterLoopParams::validate() const { schema().validate(*this); }

OuterLoopParams load_params(const ParamNode& root) {
  OuterLoopParams p;
  OuterLoopParams::schema().read(root.child("outer_loop"), p);
  return p;
}

OuterLoopParams load_params(const std::string& vehicle_file) {
  return load_params(ParamNode::load_file(vehicle_file));
}

void fit_to_site(OuterLoopParams& p, const SiteArea& site, const std::string& site_file) {
  if (!narrow_to_site(site, 0.0, 2 * kFenceInsetM, p.geofence_min_W_m, p.geofence_max_W_m))
    throw ParamError(site_file, "area", site_text(site),
                     "leaves 0.4 m or less on an axis of the vehicle's outer_loop geofence");
}

}  // namespace alight::outer_loop

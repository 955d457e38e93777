// The simulator's parameters declared (common/param_schema.hpp): pure (part of alight_sim), so a
// test or a closed-loop harness that fills the structs in code gets the same checks as a loaded
// file. Loading files (and image textures) is in params.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "sim/params.hpp"

namespace alight::sim {

namespace {
bool is_pow2(int n) { return n > 0 && (n & (n - 1)) == 0; }
}  // namespace

double footprint_distance_m(const PlatformParams& platform, const Vector2d& center_xy,
                            double yaw_rad, const Vector2d& p_xy) {
  const Vector2d d = p_xy - center_xy;
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Vector2d q(c * d.x() + s * d.y(), -s * d.x() + c * d.y());  // in the platform's frame
  return (q.cwiseAbs() - 0.5 * platform.size_m.head<2>()).cwiseMax(0.0).norm();
}

const ParamSchema<VehicleParams>& VehicleParams::schema() {
  using P = VehicleParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("name", &P::name, Range::any(), "", "the vehicle's name (reports, the monitor)");
    s.add("mass_kg", &P::mass_kg, Range::open(0.05, 20), "kg", "take-off mass");
    s.add("inertia_kgm2", &P::inertia_kgm2, Range::gt(0), "kg m^2",
          "principal inertia Jxx, Jyy, Jzz");
    s.add("max_thrust_N", &P::max_thrust_N, Range::gt(0), "N", "collective thrust limit")
        .check([](const P& p) { return p.max_thrust_N > p.hover_thrust_N() * 1.2; },
               "must exceed 1.2 x the hover thrust (mass_kg * 9.81)");
    s.add("max_tilt_deg", &P::max_tilt_deg, Range::open_closed(0, 60), "deg",
          "roll / pitch command limit of the inner loop");
    s.add("max_yaw_rate_dps", &P::max_yaw_rate_dps, Range::gt(0), "deg/s",
          "yaw-rate command limit");
    s.add("arm_length_m", &P::arm_length_m, Range::gt(0), "m", "body centre to a rotor axis");
    s.add("rotor_tip_span_m", &P::rotor_tip_span_m, Range::gt(0), "m",
          "rotor tip to rotor tip, across")
        .check([](const P& p) { return p.rotor_tip_span_m > 2 * p.arm_length_m; },
               "must exceed 2 x arm_length_m");
    s.add("gear_footprint_m", &P::gear_footprint_m, Range::open(0.02, 1), "m",
          "side of the square landing gear");
    s.add("gear_height_m", &P::gear_height_m, Range::gt(0), "m", "body origin above the gear feet");
    s.add("gear_max_impact_mps", &P::gear_max_impact_mps, Range::open_closed(0, 10), "m/s",
          "fastest sink rate at touch-down the landing gear takes; alight-score counts a faster "
          "touch-down as a crash");
    s.add("rotor_height_m", &P::rotor_height_m, Range::any(), "m",
          "rotor plane above the body origin");
    s.add("motor_tau_s", &P::motor_tau_s, Range::closed_open(0, 1), "s", "thrust first-order lag");
    s.add("attitude_bandwidth_hz", &P::attitude_bandwidth_hz, Range::open(0, 50), "Hz",
          "inner loop natural frequency (roll, pitch)");
    s.add("attitude_damping", &P::attitude_damping, Range::gt(0), "", "inner loop damping ratio");
    s.add("yaw_bandwidth_hz", &P::yaw_bandwidth_hz, Range::open(0, 50), "Hz",
          "yaw loop natural frequency");
    s.add("max_torque_Nm", &P::max_torque_Nm, Range::gt(0), "N m", "roll / pitch torque limit");
    s.add("max_yaw_torque_Nm", &P::max_yaw_torque_Nm, Range::gt(0), "N m", "yaw torque limit");
    s.add("drag_linear_Nspm", &P::drag_linear_Nspm, Range::ge(0), "N s/m",
          "linear drag on airspeed");
    s.add("drag_quadratic_Ns2pm2", &P::drag_quadratic_Ns2pm2, Range::ge(0), "N s^2/m^2",
          "quadratic drag on airspeed");
    s.add("contact_stiffness_Npm", &P::contact_stiffness_Npm, Range::gt(0), "N/m",
          "gear and rotor-rim contact springs, per contact point");
    s.add("contact_damping_Nspm", &P::contact_damping_Nspm, Range::ge(0), "N s/m",
          "per contact point");
    s.add("friction_coefficient", &P::friction_coefficient, Range::ge(0), "",
          "Coulomb friction, gear on surfaces");
    // Every timeout bounded: an infinite one is no failsafe.
    s.add("cmd_loss_timeout_s", &P::cmd_loss_timeout_s, Range::open_closed(0, 10), "s",
          "the autopilot's command-loss failsafe (PX4's offboard loss): ATTITUDE_CMD silent this "
          "long while armed: level and hold the vertical speed at 0, then descend, then disarm "
          "once resting on the ground");
    s.add("cmd_loss_level_s", &P::cmd_loss_level_s, Range::closed(0, 30), "s",
          "level, vertical speed 0, this long first");
    s.add("cmd_loss_descent_mps", &P::cmd_loss_descent_mps, Range::open_closed(0, 2), "m/s",
          "then descend at this speed");
    s.add("cmd_loss_disarm_after_s", &P::cmd_loss_disarm_after_s, Range::open_closed(0, 10), "s",
          "disarm after resting on the ground this long");
    return s;
  }();
  return schema;
}

const ParamSchema<TextureSpec>& TextureSpec::schema() {
  using P = TextureSpec;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("kind", &P::kind, Range::any(), "", "procedural (seeded), or an image file")
        .one_of({"noise", "blobs", "paper", "checker", "tiles", "image"});
    s.add("seed", &P::seed, Range::any(), "", "added to the scenario seed (so surfaces differ)");
    s.add("size_px", &P::size_px, Range::closed(64, 4096), "px",
          "procedural textures are size_px x size_px")
        .check([](const P& p) { return is_pow2(p.size_px); },
               "must be a power of two in [64, 4096]");
    s.add("texel_m", &P::texel_m, Range::open(1e-5, 1), "m", "size of one texel on the surface");
    s.add("mean", &P::mean, Range::closed(0, 255), "grey levels", "mean grey level");
    s.add("contrast", &P::contrast, Range::closed(0, 2), "", "1 = full contrast");
    s.add("feature_m", &P::feature_m, Range::gt(0), "m",
          "typical feature size: blob radius, text line height, tile side");
    s.add("path", &P::path, Range::any(), "", "image file (kind image)")
        .path()
        .check([](const P& p) { return p.kind != "image" || !p.path.empty(); },
               "an image texture needs a path");
    return s;
  }();
  return schema;
}

namespace {
constexpr double kTwoPi = 2.0 * M_PI;
std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}
// The message of a peak beyond its limit ("" within it): the figure, its parts and the limit.
std::string over_limit(double peak, double limit, const std::string& unit,
                       const std::string& what) {
  if (peak <= limit + 1e-9) return "";
  return what + " reaches " + number(peak) + " " + unit + ": must be at most " + number(limit) +
         " " + unit + " (the fastest platform the simulator takes)";
}
}  // namespace

double PlatformMotionParams::peak_speed_bound_mps() const {
  const double along_path = path == "none" ? 0.0 : speed_mps;
  const double heave_rate =
      kTwoPi * (heave_frequency_hz * heave_amplitude_m + sea_band_hz.y() * sea_heave_m);
  return velocity_mps.norm() + along_path + heave_rate;
}

double PlatformMotionParams::turn_speed_mps() const {
  if (max_course_rate_dps <= 0) return speed_mps;
  return std::min(speed_mps, path_radius_m * max_course_rate_dps * M_PI / 180.0);
}

double PlatformMotionParams::peak_yaw_rate_dps() const {
  const bool turns = heading_follows_path && path != "none";
  const double path_rate = turns ? turn_speed_mps() / path_radius_m * 180.0 / M_PI : 0.0;
  return std::abs(yaw_rate_dps) + path_rate;
}

double PlatformMotionParams::peak_roll_rate_dps() const {
  return kTwoPi * (roll_frequency_hz * roll_amplitude_deg + sea_band_hz.y() * sea_roll_deg);
}

double PlatformMotionParams::peak_pitch_rate_dps() const {
  return kTwoPi * (pitch_frequency_hz * pitch_amplitude_deg + sea_band_hz.y() * sea_pitch_deg);
}

const ParamSchema<PlatformMotionParams>& PlatformMotionParams::schema() {
  using P = PlatformMotionParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("velocity_mps", &P::velocity_mps, Range::any(), "m/s",
          "constant drift in world xy (added to the path)")
        .check_with([](const P& p) {
          return over_limit(p.velocity_mps.norm(), kMaxSpeedMps, "m/s", "its speed");
        });
    s.add("path", &P::path, Range::any(), "",
          "none; line: back and forth along a straight of path_length_m turning on semicircles "
          "of path_radius_m (a stadium); circle of path_radius_m; figure_eight: two circles of "
          "path_radius_m touching where it starts. Left turns first, from the platform's place")
        .one_of({"none", "line", "circle", "figure_eight"});
    s.add("speed_mps", &P::speed_mps, Range::closed(0, kMaxSpeedMps), "m/s",
          "constant speed along the path")
        .check_with([](const P& p) -> std::string {
          if (p.path == "none" || p.speed_mps == 0) return "";
          return over_limit(p.peak_speed_bound_mps(), kMaxSpeedMps, "m/s",
                            "the top centre's speed (|velocity_mps| + speed_mps + the heave's "
                            "rates)");
        });
    s.add("path_heading_deg", &P::path_heading_deg, Range::any(), "deg",
          "direction the path starts in, about world z");
    s.add("path_length_m", &P::path_length_m, Range::open_closed(0, 20), "m",
          "line: length of the straight");
    s.add("path_radius_m", &P::path_radius_m, Range::open_closed(0.05, 20), "m",
          "the turns' radius (line, circle, figure_eight)");
    s.add("heading_follows_path", &P::heading_follows_path, Range::any(), "",
          "the platform turns with its path as a cart does (yaw rate: the speed in the turns / "
          "path_radius_m); false: it keeps its yaw")
        .check_with([](const P& p) {
          return over_limit(p.peak_yaw_rate_dps(), kMaxRateDps, "deg/s",
                            "its turn rate (|yaw_rate_dps| + the speed in the turns / "
                            "path_radius_m)");
        });
    s.add("max_course_rate_dps", &P::max_course_rate_dps, Range::closed(0, 360), "deg/s",
          "the turns are taken at most this fast (speed / path_radius_m), slowing for them and "
          "speeding up after at " +
              number(kTurnAccelMps2) + " m/s^2 as a cart does; 0: every turn at speed_mps");
    s.add("yaw_rate_dps", &P::yaw_rate_dps, Range::closed(-kMaxRateDps, kMaxRateDps), "deg/s",
          "a constant turn about world z, added");
    // A sine's amplitude, frequency and phase; its peak rate (with the sea state's) bounded. A
    // peak over a limit is reported at a key that adds to it (a zero amplitude stays silent), so
    // the message names what to change.
    const auto sine = [](const char* amp_key, double P::*amp, double P::*freq, double P::*phase,
                         const char* unit, Range amp_range, const char* what, bool is_heave,
                         double (P::*peak)() const) {
      return [=](ParamSchema<P>& g) {
        g.add(amp_key, amp, amp_range, unit, std::string("of the ") + what + " sine")
            .check_with([=](const P& p) -> std::string {
              if (p.*amp == 0) return "";
              return over_limit(
                  (p.*peak)(), is_heave ? kMaxSpeedMps : kMaxRateDps, is_heave ? "m/s" : "deg/s",
                  is_heave ? "the top centre's speed (with the path and the heave)"
                           : std::string("the ") + what +
                                 " rate (2 pi frequency amplitude, with sea_state's)");
            });
        g.add("frequency_hz", freq, Range::open_closed(0, 2), "Hz", std::string("of the ") + what);
        g.add("phase_deg", phase, Range::any(), "deg", "at the simulator's start");
      };
    };
    s.group("heave", "the deck's heave: amplitude sin(2 pi frequency t + phase), up",
            sine("amplitude_m", &P::heave_amplitude_m, &P::heave_frequency_hz, &P::heave_phase_deg,
                 "m", Range::closed(0, 0.5), "heave", true, &P::peak_speed_bound_mps));
    s.group("roll", "the deck's roll about its length (its x), a sine",
            sine("amplitude_deg", &P::roll_amplitude_deg, &P::roll_frequency_hz, &P::roll_phase_deg,
                 "deg", Range::closed(0, 20), "roll", false, &P::peak_roll_rate_dps));
    s.group(
        "pitch", "the deck's pitch about its width (its y), a sine",
        sine("amplitude_deg", &P::pitch_amplitude_deg, &P::pitch_frequency_hz, &P::pitch_phase_deg,
             "deg", Range::closed(0, 20), "pitch", false, &P::peak_pitch_rate_dps));
    s.group(
        "sea_state",
        "a random sea: per motion, `components` sines of frequencies and phases drawn from the "
        "seed in band_hz, each of amplitude bound / components (the sum never passes the bound), "
        "added to the sines above",
        [](ParamSchema<P>& g) {
          g.add("heave_m", &P::sea_heave_m, Range::closed(0, 0.5), "m", "bound of the heave")
              .check_with([](const P& p) -> std::string {
                if (p.sea_heave_m == 0) return "";
                return over_limit(p.peak_speed_bound_mps(), kMaxSpeedMps, "m/s",
                                  "the top centre's speed (with the heave's rates)");
              });
          g.add("roll_deg", &P::sea_roll_deg, Range::closed(0, 20), "deg", "bound of the roll")
              .check_with([](const P& p) -> std::string {
                if (p.sea_roll_deg == 0) return "";
                return over_limit(p.peak_roll_rate_dps(), kMaxRateDps, "deg/s",
                                  "the roll rate (with the roll sine's)");
              });
          g.add("pitch_deg", &P::sea_pitch_deg, Range::closed(0, 20), "deg", "bound of the pitch")
              .check_with([](const P& p) -> std::string {
                if (p.sea_pitch_deg == 0) return "";
                return over_limit(p.peak_pitch_rate_dps(), kMaxRateDps, "deg/s",
                                  "the pitch rate (with the pitch sine's)");
              });
          g.add("band_hz", &P::sea_band_hz, Range::open_closed(0, 2), "Hz",
                "lowest and highest frequency of the components")
              .check([](const P& p) { return p.sea_band_hz.x() <= p.sea_band_hz.y(); },
                     "must be [low, high] with low <= high");
          g.add("components", &P::sea_components, Range::closed(1, 32), "", "sines per motion");
        });
    return s;
  }();
  return schema;
}

const ParamSchema<PlatformParams>& PlatformParams::schema() {
  using P = PlatformParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("center_xy_m", &P::center_xy_m, Range::any(), "m", "centre of its footprint");
    s.add("size_m", &P::size_m, Range::open(0.01, 5), "m", "length x, width y, height").required();
    s.add("yaw_deg", &P::yaw_deg, Range::any(), "deg", "rotation about world z");
    s.section("texture", &P::texture, TextureSpec::schema(), "of its top and sides");
    s.section("motion", &P::motion, PlatformMotionParams::schema(),
              "how it moves (a cart, a vehicle's roof, a boat's deck; sim/README.md, \"Moving "
              "platforms\"); absent: it stands still",
              &P::moving);
    s.section("reflection", &P::reflection, ReflectionParams::schema(),
              "a wet, glazed or polished top that mirrors the sky; absent: a matte top",
              &P::reflective);
    return s;
  }();
  return schema;
}

const ParamSchema<ReflectionParams>& ReflectionParams::schema() {
  using P = ReflectionParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("reflectance", &P::reflectance, Range::closed(0, 1), "",
          "share of the top's brightness that is the sky's mirror image, seen straight down "
          "(Schlick's approximation raises it towards 1 at grazing)");
    s.add("sky_height_m", &P::sky_height_m, Range::gt(0), "m",
          "the mirrored sky (clouds, a ceiling) is a plane this far above the top");
    s.section("sky", &P::sky, TextureSpec::schema(), "the sky's texture, seen in the mirror");
    return s;
  }();
  return schema;
}

const ParamSchema<WallParams>& WallParams::schema() {
  using P = WallParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("x_m", &P::x_m, Range::any(), "m", "position of the approach face along world x");
    s.add("center_y_m", &P::center_y_m, Range::any(), "m", "centre of the wall along world y");
    s.add("width_m", &P::width_m, Range::gt(0.2), "m", "along world y");
    s.add("height_m", &P::height_m, Range::gt(0.2), "m", "from the floor up");
    s.add("thickness_m", &P::thickness_m, Range::gt(0.005), "m", "along world x");
    s.add("room_depth_m", &P::room_depth_m, Range::gt(0), "m", "back wall this far behind the wall")
        .check([](const P& p) { return p.room_depth_m > p.thickness_m; },
               "must exceed the wall thickness");
    s.group(
        "opening", "a rectangular opening (paper 4.1: 60 x 60 cm); without it the wall is solid",
        [](ParamSchema<P>& g) {
          g.add("center_yz_m", &P::opening_center_yz_m, Range::any(), "m",
                "centre of the opening (y, z)");
          g.add("size_m", &P::opening_size_m, Range::gt(0.05), "m", "width (y), height (z)");
        },
        &P::has_opening);
    s.section("texture", &P::texture, TextureSpec::schema(), "of the wall");
    s.section("room_texture", &P::room_texture, TextureSpec::schema(), "of the room behind it");
    s.check(
        "opening.center_yz_m",
        [](const P& p) {
          if (!p.has_opening) return true;
          const double half_w = 0.5 * p.opening_size_m.x(), half_h = 0.5 * p.opening_size_m.y();
          return p.opening_center_yz_m.y() - half_h > 0.01 &&
                 p.opening_center_yz_m.y() + half_h < p.height_m - 0.01 &&
                 std::abs(p.opening_center_yz_m.x() - p.center_y_m) + half_w <
                     0.5 * p.width_m - 0.01;
        },
        "the opening must lie inside the wall, not touching its border");
    return s;
  }();
  return schema;
}

const ParamSchema<WindParams>& WindParams::schema() {
  using P = WindParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("steady_mps", &P::steady_mps, Range::any(), "m/s", "mean wind in world")
        .check([](const P& p) { return p.steady_mps.norm() < 20; }, "must be < 20 m/s");
    s.add("gust_sigma_mps", &P::gust_sigma_mps, Range::closed_open(0, 10), "m/s",
          "standard deviation of gusts per axis");
    s.add("gust_tau_s", &P::gust_tau_s, Range::gt(0), "s", "gust correlation time");
    return s;
  }();
  return schema;
}

const ParamSchema<MocapParams>& MocapParams::schema() {
  using P = MocapParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "",
          "publish MOCAP_POSE (false: fly without motion capture; SIM_TRUTH is still sent)");
    s.add("rate_hz", &P::rate_hz, Range::open_closed(0, 1000), "Hz", "MOCAP_POSE rate");
    s.add("latency_s", &P::latency_s, Range::closed_open(0, 1), "s", "sample time to availability");
    s.add("pos_sigma_m", &P::pos_sigma_m, Range::ge(0), "m", "position noise");
    s.add("rot_sigma_rad", &P::rot_sigma_rad, Range::ge(0), "rad", "orientation noise per axis");
    s.add("vel_sigma_mps", &P::vel_sigma_mps, Range::ge(0), "m/s", "velocity noise");
    s.add("rate_sigma_radps", &P::rate_sigma_radps, Range::ge(0), "rad/s", "angular rate noise");
    s.add("dropout_probability", &P::dropout_probability, Range::closed_open(0, 1), "",
          "chance that a sample is lost");
    s.add("dropouts_s", &P::dropouts_s, Range::ge(0), "s",
          "intervals [start_s, end_s] after the sim start without any sample (failsafe tests)")
        .check(
            [](const P& p) {
              for (const auto& d : p.dropouts_s)
                if (!(d[1] > d[0])) return false;
              return true;
            },
            "each interval must be [start_s, end_s] with 0 <= start_s < end_s");
    return s;
  }();
  return schema;
}

const ParamSchema<ImuParams>& ImuParams::schema() {
  using P = ImuParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "", "publish IMU");
    s.add("rate_hz", &P::rate_hz, Range::open_closed(0, 1000), "Hz", "IMU rate");
    s.add("accel_sigma_mps2", &P::accel_sigma_mps2, Range::ge(0), "m/s^2",
          "white noise per sample");
    s.add("gyro_sigma_radps", &P::gyro_sigma_radps, Range::ge(0), "rad/s",
          "white noise per sample");
    s.add("accel_bias_sigma_mps2", &P::accel_bias_sigma_mps2, Range::ge(0), "m/s^2",
          "bias at the start, drawn per run");
    s.add("gyro_bias_sigma_radps", &P::gyro_bias_sigma_radps, Range::ge(0), "rad/s",
          "bias at the start, drawn per run");
    s.add("accel_bias_walk_mps2_per_sqrt_s", &P::accel_bias_walk_mps2_per_sqrt_s,
          Range::closed(0, 0.1), "m/s^2/sqrt(s)",
          "bias random walk: the bias moves by this x sqrt(t) in t seconds (standard deviation)");
    s.add("gyro_bias_walk_radps_per_sqrt_s", &P::gyro_bias_walk_radps_per_sqrt_s,
          Range::closed(0, 0.01), "rad/s/sqrt(s)",
          "bias random walk: the bias moves by this x sqrt(t) in t seconds (standard deviation)");
    return s;
  }();
  return schema;
}

const ParamSchema<RangefinderParams>& RangefinderParams::schema() {
  using P = RangefinderParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "", "publish RANGE");
    s.add("rate_hz", &P::rate_hz, Range::open_closed(0, 1000), "Hz", "samples per second");
    s.add("min_range_m", &P::min_range_m, Range::ge(0), "m",
          "shortest measurable distance: nearer surfaces give STATUS_TOO_NEAR");
    s.add("max_range_m", &P::max_range_m, Range::open_closed(0, 200), "m",
          "longest measurable distance: beyond it STATUS_OUT_OF_RANGE")
        .check([](const P& p) { return p.max_range_m > p.min_range_m; }, "must exceed min_range_m");
    s.add("sigma_m", &P::sigma_m, Range::closed(0, 1), "m",
          "noise: sigma = sigma_m + sigma_frac x distance");
    s.add("sigma_frac", &P::sigma_frac, Range::closed(0, 0.5), "",
          "noise growing with the distance (0.01: 1 %)");
    s.add("dropout_prob", &P::dropout_prob, Range::closed(0, 0.5), "",
          "long-run fraction of samples whose return is lost (STATUS_NO_ECHO)");
    s.add("dropout_burst_s", &P::dropout_burst_s, Range::closed(0, 10), "s",
          "mean length of a run of lost returns (at most one period: isolated losses)");
    s.add("latency_s", &P::latency_s, Range::closed_open(0, 1), "s", "sample time to availability");
    s.add("offset_B_m", &P::offset_B_m, Range::closed(-2, 2), "m",
          "t_B_R: the sensor's origin in body (x forward, y left, z up)");
    s.add("direction_B", &P::direction_B, Range::any(), "",
          "the beam in body, normalised on use ([0, 0, -1]: straight down)")
        .check([](const P& p) { return p.direction_B.norm() > 1e-6; }, "must not be zero");
    return s;
  }();
  return schema;
}

const ParamSchema<BaroParams>& BaroParams::schema() {
  using P = BaroParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "", "publish BARO");
    s.add("rate_hz", &P::rate_hz, Range::open_closed(0, 1000), "Hz", "samples per second");
    s.add("latency_s", &P::latency_s, Range::closed_open(0, 1), "s", "sample time to availability");
    s.add("sigma_pa", &P::sigma_pa, Range::closed(0, 1000), "Pa",
          "white noise per sample (12 Pa is about 1 m near sea level)");
    s.add("offset_sigma_pa", &P::offset_sigma_pa, Range::closed(0, 1000), "Pa",
          "constant offset drawn per run (the sensor's absolute accuracy)");
    s.add("drift_pa_per_sqrt_s", &P::drift_pa_per_sqrt_s, Range::closed(0, 100), "Pa/sqrt(s)",
          "drift, a first-order Gauss-Markov process started at 0: it moves by this x sqrt(t) "
          "in t seconds well below drift_tau_s");
    s.add("drift_tau_s", &P::drift_tau_s, Range::open_closed(0, 1e6), "s",
          "the drift's correlation time: its standard deviation stays below "
          "drift_pa_per_sqrt_s x sqrt(drift_tau_s / 2)");
    s.add("ground_altitude_m", &P::ground_altitude_m, Range::closed(-500, 8000), "m",
          "altitude of the floor (world z = 0) above mean sea level");
    s.add("sea_level_pressure_pa", &P::sea_level_pressure_pa, Range::closed(80000, 110000), "Pa",
          "the day's pressure reduced to sea level (ISA: 101325)");
    s.add("sea_level_temperature_c", &P::sea_level_temperature_c, Range::closed(-60, 60), "deg C",
          "the day's temperature reduced to sea level (ISA: 15)");
    return s;
  }();
  return schema;
}

const ParamSchema<CameraEffects>& CameraEffects::schema() {
  using P = CameraEffects;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.group("rolling_shutter",
            "a rolling-shutter CMOS sensor: rows exposed one after another, each with the "
            "vehicle's pose at its own time; the frame's stamp stays row 0's mid-exposure (as "
            "alight-camera stamps a V4L2 start-of-exposure buffer) and the line delay goes out "
            "as the image's line_delay_ns metadata",
            [](ParamSchema<P>& g) {
              g.add("enabled", &P::rolling_shutter, Range::any(), "", "expose row by row");
              g.add("line_delay_s", &P::line_delay_s, Range::closed(1e-6, 1e-4), "s",
                    "from one row's exposure to the next's (10-40 us: 5-20 ms readout at 480 "
                    "rows)");
            });
    s.group("exposure_steps",
            "a camera's automatic exposure stepping: a step of up to +-max_ev, then its control "
            "brings it back over lag_frames frames; only the brightness changes (the blur stays "
            "exposure_s's)",
            [](ParamSchema<P>& g) {
              g.add("enabled", &P::exposure_steps, Range::any(), "", "step the exposure");
              g.add("max_ev", &P::ae_max_ev, Range::open_closed(0, 3), "EV",
                    "largest step (uniform in +-max_ev; 1 EV doubles the brightness)");
              g.add("rate_hz", &P::ae_rate_hz, Range::open_closed(0, 10), "Hz",
                    "steps per second on average (a step starts on a frame with probability "
                    "rate_hz / camera rate)");
              g.add("lag_frames", &P::ae_lag_frames, Range::closed(1, 60), "frames",
                    "frames until the exposure has settled back (linear in EV)");
            });
    s.group("vignetting", "the lens's radial falloff of brightness (cos^4-like)",
            [](ParamSchema<P>& g) {
              g.add("enabled", &P::vignetting, Range::any(), "", "darken towards the corners");
              g.add("corner_ratio", &P::vignetting_corner, Range::closed(0.1, 1), "",
                    "brightness at the image's farthest corner relative to the principal point");
            });
    s.group("lens",
            "the lens rendered instead of the camera_info's (the vision must undistort with the "
            "same: in process the harness hands it this model; over LCM give alight-vision a "
            "vehicle file whose camera_info names it)",
            [](ParamSchema<P>& g) {
              g.add("enabled", &P::lens, Range::any(), "", "render with this lens");
              g.add("model", &P::lens_model, Range::any(), "",
                    "plumb_bob (radial-tangential) or equidistant (fisheye, OpenCV's and ROS's)")
                  .one_of({"plumb_bob", "equidistant"});
              g.add("coefficients", &P::lens_coefficients, Range::closed(-2, 2), "",
                    "plumb_bob: k1 k2 p1 p2 k3; equidistant: k1 k2 k3 k4 0")
                  .check(
                      [](const P& p) {
                        return p.lens_model != "equidistant" || p.lens_coefficients[4] == 0.0;
                      },
                      "must end in 0 for equidistant (four coefficients k1..k4)");
            });
    s.group("driver", "the camera driver's delivery, as V4L2 and UVC drivers misbehave",
            [](ParamSchema<P>& g) {
              g.add("enabled", &P::driver, Range::any(), "", "drop, repeat and jitter frames");
              g.add("drop_prob", &P::drop_prob, Range::closed(0, 0.5), "",
                    "a frame is lost (its seq skipped, as a V4L2 sequence gap)");
              g.add("dup_prob", &P::dup_prob, Range::closed(0, 0.5), "",
                    "a frame repeats the previous one's pixels under a new seq and stamp");
              g.add("stamp_jitter_s", &P::stamp_jitter_s, Range::closed(0, 0.005), "s",
                    "standard deviation of the stamp's error (the pixels keep their true time; "
                    "stamps stay increasing)");
            });
    return s;
  }();
  return schema;
}

const ParamSchema<VibrationParams>& VibrationParams::schema() {
  using P = VibrationParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "", "shake the cameras' mounts and the IMU");
    s.add("base_hz", &P::base_hz, Range::closed(80, 250), "Hz",
          "the motors' fundamental (their rotation rate)");
    s.add("harmonics", &P::harmonics, Range::closed(1, 3), "",
          "harmonics base_hz x k, k = 1..harmonics, each with amplitude / k");
    s.add("angle_rad", &P::angle_rad, Range::closed(0, 0.02), "rad",
          "angular amplitude of the fundamental about each body axis");
    s.add("linear_m", &P::linear_m, Range::closed(0, 0.002), "m",
          "linear amplitude of the fundamental along each body axis");
    s.add("imu_share", &P::imu_share, Range::closed(0, 1), "",
          "share of that motion the IMU feels (1: on the same rigid frame; less: damped mount)");
    return s;
  }();
  return schema;
}

const ParamSchema<CameraParams>& CameraParams::schema() {
  using P = CameraParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "", "render and publish its frames");
    s.add("mount", &P::mount, Range::any(), "", "the camera of the vehicle file's cameras:")
        .one_of({"downward", "forward"});
    s.add("rate_hz", &P::rate_hz, Range::open_closed(0, 60), "Hz", "frames per second");
    s.add("exposure_s", &P::exposure_s, Range::gt(0), "s",
          "exposure time; frames are stamped at its middle")
        .check([](const P& p) { return p.exposure_s < 1.0 / p.rate_hz; },
               "must be > 0 and shorter than the frame period");
    s.add("latency_s", &P::latency_s, Range::closed_open(0, 1), "s",
          "end of exposure to availability");
    s.add("noise_sigma", &P::noise_sigma, Range::closed_open(0, 50), "grey levels", "sensor noise");
    s.add("motion_blur_samples", &P::motion_blur_samples, Range::closed(1, 16), "",
          "poses averaged over the exposure (1 = no blur)");
    s.add("gain_jitter", &P::gain_jitter, Range::closed_open(0, 0.5), "",
          "per-frame exposure / gain change, standard deviation");
    s.add("supersample", &P::supersample, Range::closed(1, 4), "",
          "rays per pixel side (1 = mip-mapping only, 2 = 4 rays)");
    s.add("auto_gain", &P::auto_gain, Range::any(), "",
          "the sensor's automatic gain (simulator.hpp AutoGain), as a camera on automatic "
          "exposure (the camera driver's default) meters its highlights: a view that would put "
          "more than 1 - auto_gain_quantile of its pixels above auto_gain_target is dimmed over "
          "a few frames until it does not; the exposure time, and so the blur, stays "
          "exposure_s. A view that never passes the target keeps gain 1. false: a fixed gain "
          "that clips a bright scene white, top and texture alike");
    s.add("auto_gain_quantile", &P::auto_gain_quantile, Range::open(0.5, 1), "",
          "share of the view's pixels metered below auto_gain_target");
    s.add("auto_gain_target", &P::auto_gain_target, Range::open_closed(64, 255), "grey levels",
          "where that quantile is held at most");
    s.add("auto_gain_min", &P::auto_gain_min, Range::open_closed(0, 1), "",
          "the lowest gain it dims to");
    s.add("auto_gain_rate", &P::auto_gain_rate, Range::open_closed(0, 1), "",
          "the newest frame's weight in the metering averaged over frames (in its logarithm): "
          "a camera's automatic exposure settles over a few frames, not at once");
    s.add("auto_gain_tolerance", &P::auto_gain_tolerance, Range::closed_open(0, 1), "",
          "the gain changes only once the metering wants it this much higher or lower "
          "(hysteresis: a still view keeps one gain instead of hunting frame to frame; the "
          "target leaves room for it below full scale)");
    s.section("effects", &P::effects, CameraEffects::schema(),
              "a real camera's imperfections, each off by default");
    return s;
  }();
  return schema;
}

const ParamSchema<LightingParams>& LightingParams::schema() {
  using P = LightingParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("ambient", &P::ambient, Range::closed(0, 2), "",
          "shade of a surface facing away from the light");
    s.add("diffuse", &P::diffuse, Range::closed(0, 2), "", "added for a surface facing the light");
    s.add("light_dir_W", &P::light_dir_W, Range::any(), "", "towards the light (normalised on use)")
        .check([](const P& p) { return p.light_dir_W.norm() > 1e-6; }, "must not be zero");
    s.add("gain", &P::gain, Range::open(0, 4), "", "overall brightness");
    s.add("falloff", &P::falloff, Range::closed(0, 0.5), "",
          "uneven illumination of a hall lit from one side of the ceiling: the light falls off "
          "with the distance d from lamp_W as 1 + falloff (2 r^2 / (r^2 + d^2) - 1), r = "
          "lamp_radius_m; smooth and fixed in the world, so features still match from frame to "
          "frame. 0: even light");
    s.add("lamp_W", &P::lamp_W, Range::any(), "m", "brightest point of the light");
    s.add("lamp_radius_m", &P::lamp_radius_m, Range::gt(0), "m",
          "distance of the half-way illumination");
    s.add("shadows", &P::shadows, Range::any(), "",
          "cast shadows: the boxes and the casters block the light along light_dir_W (a distant "
          "sun); a surface in shadow keeps only the ambient share of its shade");
    s.add("casters", &P::casters, Range::any(), "m, deg",
          "shadow casters out of the camera's view (a mast, a parapet, a tree): boxes standing on "
          "the floor, each [x, y, length, width, height, yaw_deg], that only cast shadows, "
          "neither rendered nor touched; needs shadows")
        .check(
            [](const P& p) {
              for (const auto& c : p.casters) {
                for (double v : c)
                  if (!std::isfinite(v)) return false;
                if (!(c[2] > 0 && c[3] > 0 && c[4] > 0)) return false;
              }
              return p.casters.empty() || p.shadows;
            },
            "each caster must be finite with length, width and height > 0, and casters need "
            "shadows: true");
    return s;
  }();
  return schema;
}

const ParamSchema<RandomizeParams>& RandomizeParams::schema() {
  using P = RandomizeParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("platform_xy_m", &P::platform_xy_m, Range::ge(0), "m",
          "uniform +- offset of the platform centre");
    s.add("platform_yaw_deg", &P::platform_yaw_deg, Range::closed(0, 180), "deg",
          "uniform +- yaw of the platform");
    s.add("start_clearance_m", &P::start_clearance_m, Range::ge(0), "m",
          "a randomised platform keeps its footprint this far from the start position in xy: "
          "the vehicle standing there must not have a rotor over it (the largest preset's "
          "rotor-tip radius is 0.375 m)");
    s.add("light_gain", &P::light_gain, Range::closed_open(0, 1), "",
          "uniform +- relative change of the brightness");
    s.add("light_dir_deg", &P::light_dir_deg, Range::closed(0, 180), "deg",
          "uniform +- turn of the light direction about world z");
    s.add("light_falloff", &P::light_falloff, Range::closed(0, 0.5), "",
          "uniform [0, light_falloff] depth of the lamp's falloff (lighting.falloff), the lamp "
          "anywhere above the flying area (at its configured height)");
    return s;
  }();
  return schema;
}

const ParamSchema<Scenario>& Scenario::schema() {
  using P = Scenario;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("name", &P::name, Range::any(), "", "the scenario's name").required();
    s.group("sim", "the simulation", [](ParamSchema<P>& g) {
      g.add("physics_dt_s", &P::physics_dt_s, Range::open_closed(0, 0.001), "s",
            "fixed physics step (1 kHz or finer)");
      g.add("start_utime", &P::start_utime, Range::ge(0), "us",
            "sim clock at the start (without --start-now)");
    });
    s.group("area",
            "the flying area: where the motion capture tracks the vehicle and nothing is in the "
            "way; leaving it is reported in SIM_TRUTH (out_of_area) and fails the run",
            [](ParamSchema<P>& g) {
              g.add("size_m", &P::area_size_m, Range::gt(0), "m", "x, y extent");
              g.add("center_xy_m", &P::area_center_xy_m, Range::any(), "m",
                    "centre of the area on the floor");
              g.add("height_m", &P::area_height_m, Range::gt(0), "m", "ceiling of the area");
              g.section("floor_texture", &P::floor_texture, TextureSpec::schema(), "the floor");
            });
    s.optional_section("platform", &P::platform, PlatformParams::schema(),
                       "the elevated landing platform (paper 4.2): a box on the floor");
    s.optional_section("wall", &P::wall, WallParams::schema(),
                       "a wall facing -x, with an opening and a room behind it (paper 4.3)");
    s.section("wind", &P::wind, WindParams::schema(), "wind");
    s.section("mocap", &P::mocap, MocapParams::schema(), "motion capture (MOCAP_POSE)");
    s.section("imu", &P::imu, ImuParams::schema(), "IMU");
    s.section("rangefinder", &P::rangefinder, RangefinderParams::schema(),
              "a rangefinder fixed to the body, looking down by default (RANGE)");
    s.section("baro", &P::baro, BaroParams::schema(), "a barometer (BARO)");
    s.section("camera", &P::camera, CameraParams::schema(), "the rendered camera (CAMERA)");
    s.section("flow_camera", &P::flow_camera, CameraParams::schema(),
              "the downward camera rendered besides `camera` for the onboard estimator's flow "
              "(FLOW_CAMERA; ingress without motion capture); enabled: false by default");
    s.section("vibration", &P::vibration, VibrationParams::schema(),
              "motor vibration of the airframe: the cameras' mounts and the IMU; off by default");
    s.section("lighting", &P::lighting, LightingParams::schema(), "the renderer's light");
    s.section("randomize", &P::randomize, RandomizeParams::schema(),
              "what a seed changes: platform pose, texture seeds (always) and lighting");
    s.group("start", "the start state", [](ParamSchema<P>& g) {
      g.add("position_m", &P::start_position_m, Range::any(), "m",
            "the gear stands on the floor below this point");
      g.add("yaw_deg", &P::start_yaw_deg, Range::any(), "deg", "heading at the start");
    });
    // The estimator's flow takes the vehicle file's downward camera (estimator_node.cpp).
    s.check(
        "flow_camera.mount", [](const P& p) { return p.flow_camera.mount == "downward"; },
        "must be downward: the onboard estimator's flow looks at the floor");
    s.check(
        "start.position_m",
        [](const P& p) {
          const Vector2d off = p.start_position_m.head<2>() - p.area_center_xy_m;
          return (off.cwiseAbs() - 0.5 * p.area_size_m).maxCoeff() < 0;
        },
        "must be inside the flying area (area.center_xy_m, area.size_m)");
    // Seeded placements are drawn until one clears the start; the nominal one must, so one does.
    s.check(
        "platform.center_xy_m",
        [](const P& p) {
          if (!p.platform) return true;
          const double d = footprint_distance_m(*p.platform, p.platform->center_xy_m,
                                                p.platform->yaw_deg * M_PI / 180.0,
                                                p.start_position_m.head<2>());
          const bool randomised = p.randomize.platform_xy_m > 0 || p.randomize.platform_yaw_deg > 0;
          return !randomised || d >= p.randomize.start_clearance_m;
        },
        "the platform must stand at least randomize.start_clearance_m from the start "
        "position");
    return s;
  }();
  return schema;
}

void VehicleParams::validate() const { schema().validate(*this); }
void TextureSpec::validate() const { schema().validate(*this); }
void PlatformMotionParams::validate() const { schema().validate(*this); }
void PlatformParams::validate() const { schema().validate(*this); }
void ReflectionParams::validate() const { schema().validate(*this); }
void WallParams::validate() const { schema().validate(*this); }
void WindParams::validate() const { schema().validate(*this); }
void MocapParams::validate() const { schema().validate(*this); }
void ImuParams::validate() const { schema().validate(*this); }
void RangefinderParams::validate() const { schema().validate(*this); }
void BaroParams::validate() const { schema().validate(*this); }
void CameraParams::validate() const { schema().validate(*this); }
void CameraEffects::validate() const { schema().validate(*this); }
void VibrationParams::validate() const { schema().validate(*this); }

CameraModel with_lens(const CameraModel& model, const CameraEffects& effects) {
  if (!effects.lens) return model;
  CameraModel m = model;
  m.distortion = effects.lens_model == "equidistant" ? CameraModel::Distortion::kEquidistant
                                                     : CameraModel::Distortion::kPlumbBob;
  m.D = effects.lens_coefficients;
  return m;
}
void LightingParams::validate() const { schema().validate(*this); }
void RandomizeParams::validate() const { schema().validate(*this); }
void Scenario::validate() const { schema().validate(*this); }

}  // namespace alight::sim

// validate() of the simulator's parameter structs: pure (part of alight_sim), so a test or a
// closed-loop harness that fills the structs in code gets the same checks as a loaded file.
#include "sim/params.hpp"

#include <cmath>

#include "common/params.hpp"

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

void VehicleParams::validate() const {
  param_check(mass_kg > 0.05 && mass_kg < 20, "mass_kg", mass_kg, "must be in (0.05, 20) kg");
  param_check(inertia_kgm2.minCoeff() > 0, "inertia_kgm2", inertia_kgm2.transpose(),
              "must be positive");
  param_check(max_thrust_N > hover_thrust_N() * 1.2, "max_thrust_N", max_thrust_N,
              "must exceed 1.2 x the hover thrust (mass_kg * 9.81)");
  param_check(max_tilt_deg > 0 && max_tilt_deg <= 60, "max_tilt_deg", max_tilt_deg,
              "must be in (0, 60] deg");
  param_check(max_yaw_rate_dps > 0, "max_yaw_rate_dps", max_yaw_rate_dps, "must be > 0");
  param_check(arm_length_m > 0, "arm_length_m", arm_length_m, "must be > 0");
  param_check(rotor_tip_span_m > 2 * arm_length_m, "rotor_tip_span_m", rotor_tip_span_m,
              "must exceed 2 x arm_length_m");
  param_check(gear_footprint_m > 0.02 && gear_footprint_m < 1, "gear_footprint_m",
              gear_footprint_m, "must be in (0.02, 1) m");
  param_check(gear_height_m > 0, "gear_height_m", gear_height_m, "must be > 0");
  param_check(motor_tau_s >= 0 && motor_tau_s < 1, "motor_tau_s", motor_tau_s,
              "must be in [0, 1) s");
  param_check(attitude_bandwidth_hz > 0 && attitude_bandwidth_hz < 50, "attitude_bandwidth_hz",
              attitude_bandwidth_hz, "must be in (0, 50) Hz");
  param_check(attitude_damping > 0, "attitude_damping", attitude_damping, "must be > 0");
  param_check(yaw_bandwidth_hz > 0 && yaw_bandwidth_hz < 50, "yaw_bandwidth_hz",
              yaw_bandwidth_hz, "must be in (0, 50) Hz");
  param_check(max_torque_Nm > 0, "max_torque_Nm", max_torque_Nm, "must be > 0");
  param_check(max_yaw_torque_Nm > 0, "max_yaw_torque_Nm", max_yaw_torque_Nm, "must be > 0");
  param_check(drag_linear_Nspm >= 0, "drag_linear_Nspm", drag_linear_Nspm, "must be >= 0");
  param_check(drag_quadratic_Ns2pm2 >= 0, "drag_quadratic_Ns2pm2", drag_quadratic_Ns2pm2,
              "must be >= 0");
  param_check(contact_stiffness_Npm > 0, "contact_stiffness_Npm", contact_stiffness_Npm,
              "must be > 0");
  param_check(contact_damping_Nspm >= 0, "contact_damping_Nspm", contact_damping_Nspm,
              "must be >= 0");
  param_check(friction_coefficient >= 0, "friction_coefficient", friction_coefficient,
              "must be >= 0");
  // Written so that NaN fails too; every timeout bounded (an infinite one is no failsafe).
  param_check(cmd_loss_timeout_s > 0 && cmd_loss_timeout_s <= 10, "cmd_loss_timeout_s",
              cmd_loss_timeout_s, "must be in (0, 10] s");
  param_check(cmd_loss_level_s >= 0 && cmd_loss_level_s <= 30, "cmd_loss_level_s",
              cmd_loss_level_s, "must be in [0, 30] s");
  param_check(cmd_loss_descent_mps > 0 && cmd_loss_descent_mps <= 2, "cmd_loss_descent_mps",
              cmd_loss_descent_mps, "must be in (0, 2] m/s");
  param_check(cmd_loss_disarm_after_s > 0 && cmd_loss_disarm_after_s <= 10,
              "cmd_loss_disarm_after_s", cmd_loss_disarm_after_s, "must be in (0, 10] s");
}

void TextureSpec::validate() const {
  param_check(kind == "noise" || kind == "blobs" || kind == "paper" || kind == "checker" ||
                  kind == "image",
              "kind", kind, "must be noise, blobs, paper, checker or image");
  param_check(is_pow2(size_px) && size_px >= 64 && size_px <= 4096, "size_px", size_px,
              "must be a power of two in [64, 4096]");
  param_check(texel_m > 1e-5 && texel_m < 1, "texel_m", texel_m, "must be in (1e-5, 1) m");
  param_check(mean >= 0 && mean <= 255, "mean", mean, "must be in [0, 255]");
  param_check(contrast >= 0 && contrast <= 2, "contrast", contrast, "must be in [0, 2]");
  param_check(feature_m > 0, "feature_m", feature_m, "must be > 0");
}

void PlatformParams::validate() const {
  param_check(size_m.minCoeff() > 0.01 && size_m.maxCoeff() < 5, "size_m", size_m.transpose(),
              "each side must be in (0.01, 5) m");
}

void WallParams::validate() const {
  param_check(width_m > 0.2, "width_m", width_m, "must be > 0.2 m");
  param_check(height_m > 0.2, "height_m", height_m, "must be > 0.2 m");
  param_check(thickness_m > 0.005, "thickness_m", thickness_m, "must be > 0.005 m");
  param_check(room_depth_m > thickness_m, "room_depth_m", room_depth_m,
              "must exceed the wall thickness");
  if (has_opening) {
    param_check(opening_size_m.minCoeff() > 0.05, "opening_size_m",
                opening_size_m.transpose(), "must be > 0.05 m");
    const double half_w = 0.5 * opening_size_m.x(), half_h = 0.5 * opening_size_m.y();
    const bool inside = opening_center_yz_m.y() - half_h > 0.01 &&
                        opening_center_yz_m.y() + half_h < height_m - 0.01 &&
                        std::abs(opening_center_yz_m.x() - center_y_m) + half_w < 0.5 * width_m - 0.01;
    param_check(inside, "opening_center_yz_m", opening_center_yz_m.transpose(),
                "the opening must lie inside the wall, not touching its border");
  }
}

void WindParams::validate() const {
  param_check(steady_mps.norm() < 20, "steady_mps", steady_mps.transpose(), "must be < 20 m/s");
  param_check(gust_sigma_mps >= 0 && gust_sigma_mps < 10, "gust_sigma_mps", gust_sigma_mps,
              "must be in [0, 10) m/s");
  param_check(gust_tau_s > 0, "gust_tau_s", gust_tau_s, "must be > 0");
}

void MocapParams::validate() const {
  param_check(rate_hz > 0 && rate_hz <= 1000, "rate_hz", rate_hz, "must be in (0, 1000] Hz");
  param_check(latency_s >= 0 && latency_s < 1, "latency_s", latency_s, "must be in [0, 1) s");
  param_check(pos_sigma_m >= 0, "pos_sigma_m", pos_sigma_m, "must be >= 0");
  param_check(rot_sigma_rad >= 0, "rot_sigma_rad", rot_sigma_rad, "must be >= 0");
  param_check(vel_sigma_mps >= 0, "vel_sigma_mps", vel_sigma_mps, "must be >= 0");
  param_check(rate_sigma_radps >= 0, "rate_sigma_radps", rate_sigma_radps, "must be >= 0");
  param_check(dropout_probability >= 0 && dropout_probability < 1, "dropout_probability",
              dropout_probability, "must be in [0, 1)");
  for (const auto& d : dropouts_s)
    param_check(d[0] >= 0 && d[1] > d[0], "dropouts_s", std::to_string(d[0]) + ", " + std::to_string(d[1]),
                "each interval must be [start_s, end_s] with 0 <= start_s < end_s");
}

void ImuParams::validate() const {
  param_check(rate_hz > 0 && rate_hz <= 1000, "rate_hz", rate_hz, "must be in (0, 1000] Hz");
  param_check(accel_sigma_mps2 >= 0, "accel_sigma_mps2", accel_sigma_mps2, "must be >= 0");
  param_check(gyro_sigma_radps >= 0, "gyro_sigma_radps", gyro_sigma_radps, "must be >= 0");
  param_check(accel_bias_sigma_mps2 >= 0, "accel_bias_sigma_mps2", accel_bias_sigma_mps2,
              "must be >= 0");
  param_check(gyro_bias_sigma_radps >= 0, "gyro_bias_sigma_radps", gyro_bias_sigma_radps,
              "must be >= 0");
}

void CameraParams::validate() const {
  param_check(mount == "downward" || mount == "forward", "mount", mount,
              "must be downward or forward");
  param_check(rate_hz > 0 && rate_hz <= 60, "rate_hz", rate_hz, "must be in (0, 60] Hz");
  param_check(exposure_s > 0 && exposure_s < 1.0 / rate_hz, "exposure_s", exposure_s,
              "must be > 0 and shorter than the frame period");
  param_check(latency_s >= 0 && latency_s < 1, "latency_s", latency_s, "must be in [0, 1) s");
  param_check(noise_sigma >= 0 && noise_sigma < 50, "noise_sigma", noise_sigma,
              "must be in [0, 50) grey levels");
  param_check(motion_blur_samples >= 1 && motion_blur_samples <= 16, "motion_blur_samples",
              motion_blur_samples, "must be in [1, 16]");
  param_check(gain_jitter >= 0 && gain_jitter < 0.5, "gain_jitter", gain_jitter,
              "must be in [0, 0.5)");
  param_check(supersample >= 1 && supersample <= 4, "supersample", supersample,
              "must be in [1, 4]");
}

void LightingParams::validate() const {
  param_check(ambient >= 0 && ambient <= 2, "ambient", ambient, "must be in [0, 2]");
  param_check(diffuse >= 0 && diffuse <= 2, "diffuse", diffuse, "must be in [0, 2]");
  param_check(light_dir_W.norm() > 1e-6, "light_dir_W", light_dir_W.transpose(),
              "must not be zero");
  param_check(gain > 0 && gain < 4, "gain", gain, "must be in (0, 4)");
  param_check(falloff >= 0 && falloff <= 0.5, "falloff", falloff, "must be in [0, 0.5]");
  param_check(lamp_W.allFinite(), "lamp_W", lamp_W.transpose(), "must be finite");
  param_check(lamp_radius_m > 0, "lamp_radius_m", lamp_radius_m, "must be > 0");
}

void RandomizeParams::validate() const {
  param_check(platform_xy_m >= 0, "platform_xy_m", platform_xy_m, "must be >= 0");
  param_check(platform_yaw_deg >= 0 && platform_yaw_deg <= 180, "platform_yaw_deg",
              platform_yaw_deg, "must be in [0, 180]");
  param_check(light_gain >= 0 && light_gain < 1, "light_gain", light_gain, "must be in [0, 1)");
  param_check(start_clearance_m >= 0, "start_clearance_m", start_clearance_m, "must be >= 0");
  param_check(light_dir_deg >= 0 && light_dir_deg <= 180, "light_dir_deg", light_dir_deg,
              "must be in [0, 180]");
  param_check(light_falloff >= 0 && light_falloff <= 0.5, "light_falloff", light_falloff,
              "must be in [0, 0.5]");
}

void Scenario::validate() const {
  param_check(physics_dt_s > 0 && physics_dt_s <= 0.001, "physics_dt_s", physics_dt_s,
              "must be in (0, 0.001] s (1 kHz or finer)");
  param_check(start_utime >= 0, "start_utime", start_utime, "must be >= 0");
  param_check(area_size_m.minCoeff() > 0, "area.size_m", area_size_m.transpose(),
              "must be positive");
  param_check(area_height_m > 0, "area.height_m", area_height_m, "must be > 0");
  const Vector2d start_off = start_position_m.head<2>() - area_center_xy_m;
  param_check((start_off.cwiseAbs() - 0.5 * area_size_m).maxCoeff() < 0, "start.position_m",
              start_position_m.transpose(), "must be inside the flying area (area.center_xy_m, area.size_m)");
  if (platform) {
    // Seeded placements are drawn until one clears the start; the nominal one must, so one does.
    const double d = footprint_distance_m(*platform, platform->center_xy_m,
                                          platform->yaw_deg * M_PI / 180.0, start_position_m.head<2>());
    const bool randomised = randomize.platform_xy_m > 0 || randomize.platform_yaw_deg > 0;
    param_check(!randomised || d >= randomize.start_clearance_m,
                "platform.center_xy_m", platform->center_xy_m.transpose(),
                "the platform must stand at least randomize.start_clearance_m = " +
                    std::to_string(randomize.start_clearance_m) + " m from the start position");
  }
}

}  // namespace alight::sim

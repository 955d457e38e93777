#pragma once
// Parameters of the simulator: the vehicle's physical model (the `vehicle:` section of a vehicle
// file) and a scenario (config/scenarios/*.yaml: scene, wind, sensors, start state). The structs
// are plain data for the pure library; load_* (file I/O, in params.cpp) fill them and are called
// by nodes and tests only.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/geometry.hpp"

namespace alight::sim {

/// Physical model of a quadrotor and of its autopilot's inner attitude loop.
struct VehicleParams {
  std::string name = "starmac";
  double mass_kg = 1.2;                                  ///< take-off mass [kg]
  Vector3d inertia_kgm2 = Vector3d(0.013, 0.013, 0.023);  ///< principal inertia Jxx, Jyy, Jzz [kg m^2]
  double max_thrust_N = 24.0;                            ///< collective thrust limit [N]
  double max_tilt_deg = 30.0;                            ///< roll / pitch command limit [deg]
  double max_yaw_rate_dps = 120.0;                       ///< yaw-rate command limit [deg/s]
  double arm_length_m = 0.2;                             ///< body centre to a rotor axis [m]
  double rotor_tip_span_m = 0.6;                         ///< rotor tip to rotor tip, across [m]
  double gear_footprint_m = 0.15;                        ///< side of the square landing gear [m]
  double gear_height_m = 0.1;                            ///< body origin above the gear feet [m]
  double rotor_height_m = 0.02;                          ///< rotor plane above the body origin [m]
  double motor_tau_s = 0.03;                             ///< thrust first-order lag [s]
  double attitude_bandwidth_hz = 4.0;                    ///< inner loop natural frequency (roll, pitch) [Hz]
  double attitude_damping = 0.8;                         ///< inner loop damping ratio [-]
  double yaw_bandwidth_hz = 1.5;                         ///< yaw loop natural frequency [Hz]
  double max_torque_Nm = 1.5;                            ///< roll / pitch torque limit [N m]
  double max_yaw_torque_Nm = 0.3;                        ///< yaw torque limit [N m]
  double drag_linear_Nspm = 0.25;                        ///< linear drag on airspeed [N s/m]
  double drag_quadratic_Ns2pm2 = 0.05;                   ///< quadratic drag on airspeed [N s^2/m^2]
  double contact_stiffness_Npm = 3000.0;                 ///< per contact point [N/m]
  double contact_damping_Nspm = 40.0;                    ///< per contact point [N s/m]
  double friction_coefficient = 0.6;                     ///< Coulomb friction, gear on surfaces [-]

  // The autopilot's own command-loss failsafe (PX4's offboard loss, COM_OF_LOSS_T; ArduPilot's
  // guided timeout): ATTITUDE_CMD silent this long while armed: level and hold the vertical
  // speed at 0, then descend, then disarm once resting on the ground.
  double cmd_loss_timeout_s = 1.0;      ///< silence before the failsafe takes over [s]
  double cmd_loss_level_s = 1.0;        ///< level, vertical speed 0, this long first [s]
  double cmd_loss_descent_mps = 0.5;    ///< then descend at this speed [m/s]
  double cmd_loss_disarm_after_s = 1.0; ///< disarm after resting on the ground this long [s]

  double hover_thrust_N() const { return mass_kg * 9.81; }
  void validate() const;
};

/// A texture: procedural (seeded) or an image (loaded by the loader into `image`).
struct TextureSpec {
  std::string kind = "noise";  ///< noise | blobs | paper | checker | image
  int seed = 1;                ///< added to the scenario seed (so surfaces differ)
  int size_px = 1024;          ///< procedural textures are size_px x size_px (a power of two)
  double texel_m = 0.004;      ///< size of one texel on the surface [m]
  double mean = 128;           ///< mean grey level [0, 255]
  double contrast = 1.0;       ///< 1 = full contrast
  double feature_m = 0.03;     ///< typical feature size: blob radius, text line height [m]
  std::string path;            ///< image file (kind image), resolved relative to the scenario
  cv::Mat image;               ///< mono8 pixels of the image file (filled by the loader)
  void validate() const;
};

/// The elevated landing platform (paper 4.2): a box standing on the floor.
struct PlatformParams {
  Vector2d center_xy_m = Vector2d(1.0, 0.0);              ///< centre of its footprint [m]
  Vector3d size_m = Vector3d(0.432, 0.279, 0.109);        ///< length x, width y, height [m]
  double yaw_deg = 0.0;                                   ///< rotation about world z [deg]
  TextureSpec texture{"paper", 2, 1024, 0.0015, 200, 1.0, 0.01, {}, {}};
  void validate() const;
};

/// Distance in the floor plane from `p_xy` to the footprint of a platform whose footprint is
/// centred at `center_xy` and turned by `yaw_rad`; 0 inside it [m].
double footprint_distance_m(const PlatformParams& platform, const Vector2d& center_xy,
                            double yaw_rad, const Vector2d& p_xy);

/// A wall facing -x (approached from smaller x), optionally with a rectangular opening (paper
/// 4.1: 60 x 60 cm) and a room behind it.
struct WallParams {
  double x_m = 3.0;                       ///< position of the approach face along world x [m]
  double center_y_m = 0.0;                ///< centre of the wall along world y [m]
  double width_m = 4.0;                   ///< along world y [m]
  double height_m = 2.5;                  ///< [m]
  double thickness_m = 0.1;               ///< [m]
  bool has_opening = true;
  Vector2d opening_center_yz_m = Vector2d(0.0, 1.2);  ///< centre of the opening (y, z) [m]
  Vector2d opening_size_m = Vector2d(0.6, 0.6);        ///< width (y), height (z) [m]
  double room_depth_m = 3.0;              ///< back wall this far behind the wall [m]
  TextureSpec texture{"blobs", 3, 1024, 0.003, 128, 1.0, 0.03, {}, {}};
  TextureSpec room_texture{"noise", 4, 1024, 0.004, 90, 0.8, 0.05, {}, {}};
  void validate() const;
};

struct WindParams {
  Vector3d steady_mps = Vector3d::Zero();  ///< mean wind in world [m/s]
  double gust_sigma_mps = 0.0;             ///< standard deviation of gusts per axis [m/s]
  double gust_tau_s = 1.0;                 ///< gust correlation time [s]
  void validate() const;
};

struct MocapParams {
  double rate_hz = 100.0;
  double latency_s = 0.010;            ///< sample time to availability [s]
  double pos_sigma_m = 0.0003;         ///< position noise [m]
  double rot_sigma_rad = 0.0015;       ///< orientation noise per axis [rad]
  double vel_sigma_mps = 0.005;        ///< velocity noise [m/s]
  double rate_sigma_radps = 0.01;      ///< angular rate noise [rad/s]
  double dropout_probability = 0.0;    ///< chance that a sample is lost [-]
  /// Intervals [start_s, end_s] after the sim start without any sample (failsafe tests).
  std::vector<std::array<double, 2>> dropouts_s;
  void validate() const;
};

struct ImuParams {
  double rate_hz = 200.0;
  double accel_sigma_mps2 = 0.04;       ///< white noise per sample [m/s^2]
  double gyro_sigma_radps = 0.003;      ///< white noise per sample [rad/s]
  double accel_bias_sigma_mps2 = 0.05;  ///< constant bias drawn per run [m/s^2]
  double gyro_bias_sigma_radps = 0.005; ///< constant bias drawn per run [rad/s]
  void validate() const;
};

struct CameraParams {
  bool enabled = true;
  std::string mount = "downward";  ///< key under the vehicle file's `cameras:`
  double rate_hz = 30.0;           ///< frames per second (up to 60)
  double exposure_s = 0.004;       ///< exposure time [s]; frames are stamped at its middle
  double latency_s = 0.0;          ///< end of exposure to availability [s]
  double noise_sigma = 2.0;        ///< sensor noise [grey levels]
  int motion_blur_samples = 1;     ///< poses averaged over the exposure (1 = no blur)
  double gain_jitter = 0.0;        ///< per-frame exposure / gain change, standard deviation [-]
  int supersample = 1;             ///< rays per pixel side (1 = mip-mapping only, 2 = 4 rays)
  void validate() const;
};

struct LightingParams {
  double ambient = 0.75;                        ///< shade of a surface facing away from the light
  double diffuse = 0.35;                        ///< added for a surface facing the light
  Vector3d light_dir_W = Vector3d(0.3, 0.2, 1.0);  ///< towards the light (normalised on use)
  double gain = 1.0;                            ///< overall brightness [-]
  /// Uneven illumination of a hall lit from one side of the ceiling: the light falls off with the
  /// distance d from `lamp_W` as 1 + falloff (2 r^2 / (r^2 + d^2) - 1), r = lamp_radius_m: 1 +
  /// falloff under the lamp, 1 at d = r, towards 1 - falloff far away. Smooth and fixed in the
  /// world, so features still match from frame to frame. 0: even light.
  double falloff = 0.0;                         ///< depth of the falloff [-], in [0, 0.5]
  Vector3d lamp_W = Vector3d(0.0, 0.0, 3.0);    ///< brightest point of the light [m]
  double lamp_radius_m = 3.0;                   ///< distance of the half-way illumination [m]
  void validate() const;
};

/// What a seed changes: platform pose, texture seeds (always) and lighting.
struct RandomizeParams {
  double platform_xy_m = 0.0;     ///< uniform +- offset of the platform centre [m]
  double platform_yaw_deg = 0.0;  ///< uniform +- yaw of the platform [deg]
  /// A randomised platform keeps its footprint this far from the start position in xy: the
  /// vehicle standing there must not have a rotor over it (the largest preset's rotor-tip
  /// radius is 0.375 m) [m]
  double start_clearance_m = 0.5;
  double light_gain = 0.0;        ///< uniform +- relative change of the brightness [-]
  double light_dir_deg = 0.0;     ///< uniform +- turn of the light direction about world z [deg]
  /// Uniform [0, light_falloff] depth of the lamp's falloff (LightingParams::falloff), the lamp
  /// anywhere above the flying area (at its configured height) [-]
  double light_falloff = 0.0;
  void validate() const;
};

struct Scenario {
  std::string name = "landing_none";
  std::string file;                 ///< where it was loaded from (for messages only)
  double physics_dt_s = 0.001;      ///< fixed physics step [s] (1 kHz or finer)
  int64_t start_utime = 1700000000000000;  ///< sim clock at the start [us]
  /// The flying area: where the motion capture tracks the vehicle and nothing is in the way.
  /// Leaving it is reported in SIM_TRUTH (out_of_area) and fails the run.
  Vector2d area_size_m = Vector2d(6.0, 6.0);    ///< x, y extent [m]
  Vector2d area_center_xy_m = Vector2d::Zero(); ///< centre of the area on the floor [m]
  double area_height_m = 4.0;                   ///< ceiling of the area [m]
  TextureSpec floor_texture{"noise", 1, 1024, 0.004, 120, 1.0, 0.03, {}, {}};
  std::optional<PlatformParams> platform;
  std::optional<WallParams> wall;
  WindParams wind;
  MocapParams mocap;
  ImuParams imu;
  CameraParams camera;
  LightingParams lighting;
  RandomizeParams randomize;
  Vector3d start_position_m = Vector3d::Zero();  ///< gear on the floor below this point [m]
  double start_yaw_deg = 0.0;
  void validate() const;
};

/// The camera the simulator renders: where it sits and its intrinsics.
struct CameraRig {
  CameraMount mount;
  CameraModel model;
};

/// Reads the `vehicle:` section of a vehicle file.
VehicleParams load_vehicle_params(const std::string& vehicle_file);
/// Reads a scenario file, loading image textures it names. Throws ParamError (file, key, value).
Scenario load_scenario(const std::string& scenario_file);
/// The camera `mount_name` of a vehicle file with the intrinsics its camera_info names.
CameraRig load_camera_rig(const std::string& vehicle_file, const std::string& mount_name);

}  // namespace alight::sim

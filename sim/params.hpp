#pragma once
// Parameters of the simulator: the vehicle's physical model (the `vehicle:` section of a vehicle
// file) and a scenario (config/scenarios/*.yaml: scene, wind, sensors, start state). The structs
// are plain data for the pure library, their defaults the initialisers below; key, constraint,
// unit and meaning of each field are declared once in params_validate.cpp
// (common/param_schema.hpp). load_* (file I/O, in params.cpp) fill them and are called by nodes
// and tests only.

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "common/geometry.hpp"
#include "common/param_schema.hpp"

namespace alight::sim {

/// Physical model of a quadrotor and of its autopilot's inner attitude loop.
struct VehicleParams {
  std::string name = "starmac";
  double mass_kg = 1.2;
  Vector3d inertia_kgm2 = Vector3d(0.013, 0.013, 0.023);
  double max_thrust_N = 24.0;
  double max_tilt_deg = 30.0;
  double max_yaw_rate_dps = 120.0;
  double arm_length_m = 0.2;
  double rotor_tip_span_m = 0.6;
  double gear_footprint_m = 0.15;
  double gear_height_m = 0.1;
  double gear_max_impact_mps = 1.5;
  double rotor_height_m = 0.02;
  double motor_tau_s = 0.03;
  double attitude_bandwidth_hz = 4.0;
  double attitude_damping = 0.8;
  double yaw_bandwidth_hz = 1.5;
  double max_torque_Nm = 1.5;
  double max_yaw_torque_Nm = 0.3;
  double drag_linear_Nspm = 0.25;
  double drag_quadratic_Ns2pm2 = 0.05;
  double contact_stiffness_Npm = 3000.0;
  double contact_damping_Nspm = 40.0;
  double friction_coefficient = 0.6;

  // The autopilot's own command-loss failsafe (PX4's offboard loss, COM_OF_LOSS_T; ArduPilot's
  // guided timeout): ATTITUDE_CMD silent this long while armed: level and hold the vertical
  // speed at 0, then descend, then disarm once resting on the ground.
  double cmd_loss_timeout_s = 1.0;
  double cmd_loss_level_s = 1.0;
  double cmd_loss_descent_mps = 0.5;
  double cmd_loss_disarm_after_s = 1.0;

  double hover_thrust_N() const { return mass_kg * 9.81; }
  static const ParamSchema<VehicleParams>& schema();
  void validate() const;
};

/// A texture: procedural (seeded) or an image (loaded by the loader into `image`).
struct TextureSpec {
  std::string kind = "noise";  ///< noise | blobs | paper | checker | tiles | image
  int seed = 1;
  int size_px = 1024;
  double texel_m = 0.004;
  double mean = 128;
  double contrast = 1.0;
  double feature_m = 0.03;
  std::string path;  ///< image file (kind image), resolved relative to the scenario
  cv::Mat image;     ///< mono8 pixels of the image file (filled by the loader)
  static const ParamSchema<TextureSpec>& schema();
  void validate() const;
};

/// How a platform moves (`platform.motion`; sim/platform_motion.hpp evaluates it): a
/// constant drift, a path travelled at a constant speed, a turn rate, and a deck's heave, roll
/// and pitch as sines and as a seeded random sea state. Time counts from the simulator's start.
/// At most kMaxSpeedMps for the top centre and kMaxRateDps about each axis: what a cart, a
/// vehicle's roof or a boat's deck a multirotor may land on does (refused beyond, key named).
struct PlatformMotionParams {
  static constexpr double kMaxSpeedMps = 1.0;
  static constexpr double kMaxRateDps = 15.0;
  Vector2d velocity_mps = Vector2d::Zero();  ///< constant drift in world xy
  /// none | line (back and forth along a straight of path_length_m, turning on semicircles of
  /// path_radius_m: a stadium) | circle (radius path_radius_m) | figure_eight (two circles of
  /// path_radius_m touching where it starts). Left turns first; starts at the platform's place.
  std::string path = "none";
  double speed_mps = 0.0;         ///< along the path
  double path_heading_deg = 0.0;  ///< direction the path starts in, about world z
  double path_length_m = 2.0;
  double path_radius_m = 1.0;
  bool heading_follows_path = false;  ///< a cart turns with its path; false: it keeps its yaw
  /// The path's turns are taken at most this fast, the course turning at speed / radius [deg/s]:
  /// a cart slows for its turns (at kTurnAccelMps2) and speeds up after. 0: every turn at
  /// speed_mps.
  double max_course_rate_dps = 0.0;
  /// How fast a cart slows for a turn and speeds up after it [m/s^2]: a car's gentle braking
  /// (0.05 g), well within what the vehicle following it can match.
  static constexpr double kTurnAccelMps2 = 0.5;
  double yaw_rate_dps = 0.0;  ///< a constant turn about world z (added)
  // Sines: amplitude * sin(2 pi frequency t + phase).
  double heave_amplitude_m = 0.0, heave_frequency_hz = 0.3, heave_phase_deg = 0.0;
  double roll_amplitude_deg = 0.0, roll_frequency_hz = 0.3, roll_phase_deg = 0.0;
  double pitch_amplitude_deg = 0.0, pitch_frequency_hz = 0.3, pitch_phase_deg = 0.0;
  // Random sea state: per motion, sea_components sines of seeded frequencies in sea_band_hz and
  // seeded phases, each of amplitude bound / sea_components, so the sum never passes the bound.
  double sea_heave_m = 0.0, sea_roll_deg = 0.0, sea_pitch_deg = 0.0;
  Vector2d sea_band_hz = Vector2d(0.2, 0.5);
  int sea_components = 4;

  /// Upper bound of the top centre's speed over all time [m/s].
  double peak_speed_bound_mps() const;
  /// The speed along the path in its turns [m/s]: speed_mps, or less where max_course_rate_dps
  /// bounds the course's turn rate on path_radius_m.
  double turn_speed_mps() const;
  /// Upper bounds of the turn rates about world z, and of the roll and pitch rates [deg/s].
  double peak_yaw_rate_dps() const;
  double peak_roll_rate_dps() const;
  double peak_pitch_rate_dps() const;
  static const ParamSchema<PlatformMotionParams>& schema();
  void validate() const;
};

/// A wet, glazed or polished top (`platform.reflection`): over its own texture it mirrors the sky
/// (clouds, or a hall's ceiling), a textured plane sky_height_m above the top. The mirrored share
/// is Schlick's approximation of Fresnel's, reflectance at normal incidence rising to 1 at
/// grazing, and the mirror image moves with the camera as the sky's image would, not with the
/// top's texture.
struct ReflectionParams {
  double reflectance = 0.3;
  double sky_height_m = 30.0;
  TextureSpec sky{"blobs", 7, 1024, 0.05, 200, 0.6, 2.0, {}, {}};
  static const ParamSchema<ReflectionParams>& schema();
  void validate() const;
};

/// The elevated landing platform (paper 4.2): a box standing on the floor.
struct PlatformParams {
  Vector2d center_xy_m = Vector2d(1.0, 0.0);
  Vector3d size_m = Vector3d(0.432, 0.279, 0.109);  ///< length x, width y, height [m]
  double yaw_deg = 0.0;
  TextureSpec texture{"paper", 2, 1024, 0.0015, 200, 1.0, 0.01, {}, {}};
  /// `motion:` present: the platform moves; absent: it stands still.
  bool moving = false;
  PlatformMotionParams motion;
  /// `reflection:` present: the top mirrors the sky; absent: it is matte.
  bool reflective = false;
  ReflectionParams reflection;
  static const ParamSchema<PlatformParams>& schema();
  void validate() const;
};

/// Distance in the floor plane from `p_xy` to the footprint of a platform whose footprint is
/// centred at `center_xy` and turned by `yaw_rad`; 0 inside it [m].
double footprint_distance_m(const PlatformParams& platform, const Vector2d& center_xy,
                            double yaw_rad, const Vector2d& p_xy);

/// A wall facing -x (approached from smaller x), optionally with a rectangular opening (paper
/// 4.1: 60 x 60 cm) and a room behind it.
struct WallParams {
  double x_m = 3.0;
  double center_y_m = 0.0;
  double width_m = 4.0;
  double height_m = 2.5;
  double thickness_m = 0.1;
  bool has_opening = true;                            ///< the file has an `opening:` section
  Vector2d opening_center_yz_m = Vector2d(0.0, 1.2);  ///< `opening.center_yz_m`
  Vector2d opening_size_m = Vector2d(0.6, 0.6);       ///< `opening.size_m`
  double room_depth_m = 3.0;
  TextureSpec texture{"blobs", 3, 1024, 0.003, 128, 1.0, 0.03, {}, {}};
  TextureSpec room_texture{"noise", 4, 1024, 0.004, 90, 0.8, 0.05, {}, {}};
  static const ParamSchema<WallParams>& schema();
  void validate() const;
};

struct WindParams {
  Vector3d steady_mps = Vector3d::Zero();
  double gust_sigma_mps = 0.0;
  double gust_tau_s = 1.0;
  static const ParamSchema<WindParams>& schema();
  void validate() const;
};

struct MocapParams {
  bool enabled = true;  ///< false: no MOCAP_POSE at all (flying on the onboard estimator)
  double rate_hz = 100.0;
  double latency_s = 0.010;
  double pos_sigma_m = 0.0003;
  double rot_sigma_rad = 0.0015;
  double vel_sigma_mps = 0.005;
  double rate_sigma_radps = 0.01;
  double dropout_probability = 0.0;
  std::vector<std::array<double, 2>> dropouts_s;  ///< [start_s, end_s] after the sim start
  static const ParamSchema<MocapParams>& schema();
  void validate() const;
};

/// A strapdown MEMS IMU; sim/README.md ("Sensors") relates the defaults to the TDK
/// ICM-42688-P's data sheet.
struct ImuParams {
  bool enabled = true;
  double rate_hz = 200.0;
  double accel_sigma_mps2 = 0.04;
  double gyro_sigma_radps = 0.003;
  double accel_bias_sigma_mps2 = 0.05;
  double gyro_bias_sigma_radps = 0.005;
  /// Bias random walk: the bias moves by this times sqrt(t) (standard deviation) after t seconds.
  double accel_bias_walk_mps2_per_sqrt_s = 4e-4;
  double gyro_bias_walk_radps_per_sqrt_s = 3e-5;
  static const ParamSchema<ImuParams>& schema();
  void validate() const;
};

/// A single-beam rangefinder fixed to the body (LIDAR-Lite / TFmini class): one ray cast into
/// the scene per sample, Gaussian noise growing with the distance, lost returns in bursts.
struct RangefinderParams {
  bool enabled = true;
  double rate_hz = 100.0;
  double min_range_m = 0.1;
  double max_range_m = 8.0;
  double sigma_m = 0.01;  ///< noise sigma = sigma_m + sigma_frac * distance
  double sigma_frac = 0.01;
  double dropout_prob = 0.01;     ///< long-run fraction of samples whose return is lost
  double dropout_burst_s = 0.03;  ///< mean length of a run of lost returns
  double latency_s = 0.01;
  Vector3d offset_B_m = Vector3d(0.0, 0.0, -0.05);  ///< t_B_R: sensor origin in body
  Vector3d direction_B = Vector3d(0.0, 0.0, -1.0);  ///< beam in body (normalised on use)
  static const ParamSchema<RangefinderParams>& schema();
  void validate() const;
};

/// A MEMS barometer at the body origin in a standard atmosphere (ISA), with white noise, a
/// constant offset per run and a slowly wandering drift (first-order Gauss-Markov).
struct BaroParams {
  bool enabled = true;
  double rate_hz = 50.0;
  double latency_s = 0.01;
  double sigma_pa = 2.0;
  double offset_sigma_pa = 100.0;
  /// Drift: first-order Gauss-Markov b' = -b / drift_tau_s + w; it moves by
  /// drift_pa_per_sqrt_s * sqrt(t) for t well below drift_tau_s and stays within
  /// drift_pa_per_sqrt_s * sqrt(drift_tau_s / 2) (its standard deviation) for ever.
  double drift_pa_per_sqrt_s = 0.2;
  double drift_tau_s = 300.0;
  double ground_altitude_m = 0.0;  ///< world z = 0 above mean sea level
  double sea_level_pressure_pa = 101325.0;
  double sea_level_temperature_c = 15.0;
  static const ParamSchema<BaroParams>& schema();
  void validate() const;
};

/// A real small-drone camera's imperfections (sim/camera_effects.hpp models them), each
/// switched on by its own `enabled` under a camera's `effects:` and off by default, so a
/// scenario without the block renders bit for bit as before.
struct CameraEffects {
  /// Rolling shutter: row v is exposed line_delay_s x v after row 0 (the frame's stamp names
  /// row 0's mid-exposure, as alight-camera stamps a V4L2 start-of-exposure buffer).
  bool rolling_shutter = false;
  double line_delay_s = 2e-5;
  /// Automatic exposure steps: a step of up to +-ae_max_ev, ae_rate_hz on average, then the
  /// exposure control brings it back over ae_lag_frames frames.
  bool exposure_steps = false;
  double ae_max_ev = 2.0;
  double ae_rate_hz = 0.5;
  int ae_lag_frames = 6;
  /// Vignetting: natural (cos^4-like) radial falloff, the image corner at vignetting_corner of
  /// the centre.
  bool vignetting = false;
  double vignetting_corner = 0.6;
  /// The lens the simulator renders with instead of the camera_info's: plumb_bob (radial-
  /// tangential k1 k2 p1 p2 k3) or equidistant (fisheye k1 k2 k3 k4; the fifth must be 0).
  bool lens = false;
  std::string lens_model = "plumb_bob";
  std::array<double, 5> lens_coefficients{};
  /// The driver's delivery: frames dropped or delivered twice, stamps jittered.
  bool driver = false;
  double drop_prob = 0.02;
  double dup_prob = 0.02;
  double stamp_jitter_s = 0.001;
  static const ParamSchema<CameraEffects>& schema();
  void validate() const;
};

/// Motor vibration of the airframe: harmonics base_hz x k (k = 1..harmonics,
/// amplitude / k) as angular and linear jitter of every camera mount, and the same motion seen
/// by the IMU (imu_share of it).
struct VibrationParams {
  bool enabled = false;
  double base_hz = 120.0;
  int harmonics = 2;
  double angle_rad = 0.002;
  double linear_m = 5e-5;
  double imu_share = 1.0;
  static const ParamSchema<VibrationParams>& schema();
  void validate() const;
};

struct CameraParams {
  bool enabled = true;
  std::string mount = "downward";  ///< key under the vehicle file's `cameras:`
  double rate_hz = 30.0;
  double exposure_s = 0.004;
  double latency_s = 0.0;
  double noise_sigma = 2.0;
  int motion_blur_samples = 1;
  double gain_jitter = 0.0;
  int supersample = 1;
  /// The sensor's automatic gain with highlight protection (simulator.hpp AutoGain).
  bool auto_gain = true;
  double auto_gain_quantile = 0.99;
  double auto_gain_target = 240.0;  ///< grey levels
  double auto_gain_min = 0.25;
  double auto_gain_rate = 0.1;
  double auto_gain_tolerance = 0.05;
  CameraEffects effects;  ///< `effects:`, all off by default
  static const ParamSchema<CameraParams>& schema();
  void validate() const;
};

struct LightingParams {
  double ambient = 0.75;
  double diffuse = 0.35;
  Vector3d light_dir_W = Vector3d(0.3, 0.2, 1.0);  ///< towards the light (normalised on use)
  double gain = 1.0;
  /// Uneven illumination of a hall lit from one side of the ceiling: the light falls off with the
  /// distance d from `lamp_W` as 1 + falloff (2 r^2 / (r^2 + d^2) - 1), r = lamp_radius_m: 1 +
  /// falloff under the lamp, 1 at d = r, towards 1 - falloff far away. Smooth and fixed in the
  /// world, so features still match from frame to frame. 0: even light.
  double falloff = 0.0;
  Vector3d lamp_W = Vector3d(0.0, 0.0, 3.0);
  double lamp_radius_m = 3.0;
  /// Cast shadows: the boxes and the casters block the light along light_dir_W (a distant sun);
  /// a surface in shadow keeps only the ambient share of its shade. Off: no surface shadows
  /// another.
  bool shadows = false;
  /// Shadow casters out of the camera's view (a mast, a parapet, a tree): boxes standing on the
  /// floor, each [x, y, length, width, height, yaw_deg] [m, deg], that only cast shadows: neither
  /// rendered nor touched.
  std::vector<std::array<double, 6>> casters;
  static const ParamSchema<LightingParams>& schema();
  void validate() const;
};

/// What a seed changes: platform pose, texture seeds (always) and lighting.
struct RandomizeParams {
  double platform_xy_m = 0.0;
  double platform_yaw_deg = 0.0;
  double start_clearance_m = 0.5;
  double light_gain = 0.0;
  double light_dir_deg = 0.0;
  double light_falloff = 0.0;
  static const ParamSchema<RandomizeParams>& schema();
  void validate() const;
};

struct Scenario {
  std::string name = "landing_none";
  std::string file;             ///< where it was loaded from (for messages only; not a parameter)
  double physics_dt_s = 0.001;  ///< `sim.physics_dt_s`
  int64_t start_utime = 1700000000000000;  ///< `sim.start_utime`
  /// The flying area (`area:`): where the motion capture tracks the vehicle and nothing is in
  /// the way. Leaving it is reported in SIM_TRUTH (out_of_area) and fails the run.
  Vector2d area_size_m = Vector2d(6.0, 6.0);
  Vector2d area_center_xy_m = Vector2d::Zero();
  double area_height_m = 4.0;
  TextureSpec floor_texture{"noise", 1, 1024, 0.004, 120, 1.0, 0.03, {}, {}};
  std::optional<PlatformParams> platform;
  std::optional<WallParams> wall;
  WindParams wind;
  MocapParams mocap;
  ImuParams imu;
  RangefinderParams rangefinder;
  BaroParams baro;
  CameraParams camera;
  /// The downward camera once more, for the onboard estimator's flow (FLOW_CAMERA), when
  /// `camera` is another one: ingress without motion capture renders the forward camera for the
  /// vision and this one for the estimator. Off unless enabled here or by
  /// alight-sim --flow-camera.
  CameraParams flow_camera = [] {
    CameraParams c;
    c.enabled = false;
    return c;
  }();
  VibrationParams vibration;
  LightingParams lighting;
  RandomizeParams randomize;
  Vector3d start_position_m = Vector3d::Zero();  ///< `start.position_m`
  double start_yaw_deg = 0.0;                    ///< `start.yaw_deg`
  static const ParamSchema<Scenario>& schema();
  void validate() const;
};

/// The camera the simulator renders: where it sits and its intrinsics.
struct CameraRig {
  CameraMount mount;
  CameraModel model;
};

/// `model` with the lens of `effects` when effects.lens is on (the simulator renders with it;
/// the vision must undistort with the same model), else `model` unchanged.
CameraModel with_lens(const CameraModel& model, const CameraEffects& effects);

/// Reads the `vehicle:` section of a vehicle file.
VehicleParams load_vehicle_params(const std::string& vehicle_file);
/// Reads a scenario file, loading image textures it names. Throws ParamError (file, key, value).
Scenario load_scenario(const std::string& scenario_file);
/// The camera `mount_name` of a vehicle file with the intrinsics its camera_info names.
CameraRig load_camera_rig(const std::string& vehicle_file, const std::string& mount_name);

}  // namespace alight::sim

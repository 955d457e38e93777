#pragma once
// alight-sim's pure library: the quadrotor (dynamics.hpp), the motion-capture room, the IMU, the
// rangefinder and the barometer (sensors.hpp) and the camera (renderer.hpp) in one deterministic
// simulation. No LCM, no clock,
// no files: the caller passes commands and the utime to advance to, and takes the sensor samples
// that became due. Same scenario, seed and command sequence give identical outputs.
//
//   Simulator sim(scenario, vehicle, seed, camera_rig);
//   sim.step(cmd, sim.now_utime() + 10000);   // 10 ms under cmd
//   for (const auto& m : sim.take_mocap()) ...;
//   if (auto frame = sim.take_camera()) ...;
//   if (auto frame = sim.take_flow_camera()) ...;   // with a flow_camera rig

#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "common/pose_buffer.hpp"
#include "sim/camera_effects.hpp"
#include "sim/dynamics.hpp"
#include "sim/params.hpp"
#include "sim/platform_motion.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "sim/sensors.hpp"

namespace alight::sim {

/// Ground truth (what SIM_TRUTH carries).
struct Truth {
  int64_t utime = 0;
  std::string scenario;
  VehicleState state;
  std::optional<PlatformTruth> platform;
  std::optional<OpeningTruth> opening;
  Contact contact = Contact::kNone;
  bool landed = false;    ///< at rest with all gear on the platform top and motors off
  bool tipped = false;    ///< tilted past 35 deg while touching the floor or platform (sticky)
  bool collided = false;  ///< touched the wall or the opening's frame (sticky)
  int n_collisions = 0;   ///< distinct wall / frame contacts
  /// The body left the flying area (Scenario::area_*: the motion-capture volume, clear of the
  /// hall's walls and ceiling) at some time this run (sticky): a real flight would have lost
  /// tracking or hit the hall there, so the run has failed.
  bool out_of_area = false;
  /// The autopilot's command-loss failsafe is flying the vehicle (ATTITUDE_CMD silent).
  bool command_lost = false;
  Vector3d wind_W = Vector3d::Zero();  ///< wind at the vehicle [m/s]
};

/// One camera frame.
struct CameraFrame {
  /// Middle of the exposure [us]; under a rolling shutter, of row 0's (row v's is utime + v x
  /// line_delay_s), as alight-camera stamps a V4L2 start-of-exposure buffer. With the driver's
  /// stamp jitter (CameraEffects::stamp_jitter_s) this stamp carries the error, not the pixels.
  int64_t utime = 0;
  int64_t seq = 0;  ///< frame counter (a dropped frame's number is skipped)
  double exposure_s = 0.0;
  double gain = 1.0;          ///< gain applied to this frame (flicker times the automatic gain)
  double line_delay_s = 0.0;  ///< rolling shutter's row-to-row delay; 0: global shutter
  double exposure_ev = 0.0;   ///< the automatic exposure's step on this frame [EV]
  bool duplicate = false;     ///< the driver delivered the previous frame's pixels again
  Isometry3d X_WC = Isometry3d::Identity();  ///< camera pose at (row 0's) mid-exposure
  cv::Mat pixels;                            ///< mono8
};

/// The sensor's automatic gain (a camera on automatic exposure, the camera driver's default)
/// with highlight protection. After each frame it meters the view's brightness at unit gain at
/// auto_gain_quantile (on every fourth pixel of every fourth row) and averages its logarithm
/// over frames (auto_gain_rate: the newest frame's weight), as a camera's exposure control
/// smooths its metering: a small bright patch at the quantile flips it frame to frame. The gain
/// that holds the averaged brightness at auto_gain_target, bounded to [auto_gain_min, 1], is
/// taken once it differs from the gain by more than auto_gain_tolerance (hysteresis: a still
/// view keeps one gain). A view whose quantile never passes the target keeps gain 1, so such a
/// scene renders as without it.
class AutoGain {
 public:
  explicit AutoGain(const CameraParams& params = {});
  /// The gain for the next frame: 1 until a view has been too bright.
  double gain() const { return gain_; }
  /// After a frame: `linear` is the frame as the light reached the sensor (CV_32F grey levels,
  /// before noise and clipping) under the total gain `frame_gain` (flicker times gain()). Does
  /// nothing when params.auto_gain is false.
  void update(const cv::Mat& linear, double frame_gain);

 private:
  CameraParams params_;
  double gain_ = 1.0;
  double log_brightness_;  // the averaged metering at unit gain, log grey levels
};

/// The scene a Simulator built with `seed` flies in: built from a stream of the seed of its own,
/// so a tool that needs the truth (the platform's placement after the scenario's randomize) sees
/// the simulator's scene, not the one build_scene(scenario, seed) would draw.
Scene simulated_scene(const Scenario& scenario, uint64_t seed);

class Simulator {
 public:
  /// `camera`: the camera to render (extrinsics and intrinsics); without it take_camera()
  /// returns nothing. `flow_camera`: the downward camera rendered besides it for the onboard
  /// estimator when the scenario's flow_camera.enabled (take_flow_camera()); its frames have
  /// their own noise stream, so rendering it or not changes nothing else. Throws ParamError when
  /// the scenario's randomize.start_clearance_m leaves less room than the vehicle's rotor-tip
  /// radius.
  Simulator(const Scenario& scenario, const VehicleParams& vehicle, uint64_t seed,
            std::optional<CameraRig> camera = std::nullopt,
            std::optional<CameraRig> flow_camera = std::nullopt);

  /// Holds `cmd` from now until `until_utime`, as if it were received all the while (fixed
  /// physics steps; time never goes back).
  void step(const AttitudeCommand& cmd, int64_t until_utime);
  /// A command received now (the node: one ATTITUDE_CMD message). As PX4 and ArduPilot refuse a
  /// disarm in flight unless it is forced, a disarm (armed false) while the vehicle is armed and
  /// touches nothing but air (or a wall) is refused unless `forced`: the vehicle keeps flying the
  /// last armed command, and the refusal is counted (disarms_refused()).
  void command(const AttitudeCommand& cmd);
  uint64_t disarms_refused() const { return disarms_refused_; }
  /// The autopilot's command-loss failsafe is flying the vehicle.
  bool command_lost() const { return cmd_lost_since_.has_value(); }
  /// Advances under the last command received. When none arrived for the vehicle's
  /// cmd_loss_timeout_s while armed, the autopilot's command-loss failsafe flies it: level, then
  /// a descent at cmd_loss_descent_mps, then disarmed once it rests on the ground, and then
  /// armed again only after a disarmed command.
  void advance_to(int64_t until_utime);

  /// The vehicle flown by another simulator (an autopilot's SITL): every physics step
  /// takes `state_at(t)` instead of integrating the dynamics, and contact (a point within
  /// `contact_margin_m` above a surface touches it: that simulator's ground is flat, its heights
  /// are its own), the outcome flags, motion capture, the rangefinder, the barometer and the
  /// cameras follow it. The IMU is not simulated (the autopilot has its own); no wind.
  void follow(const std::function<VehicleState(int64_t)>& state_at, int64_t until_utime,
              double contact_margin_m);

  int64_t now_utime() const { return now_utime_; }
  const VehicleState& state() const { return state_; }
  /// Places the vehicle (tests: start in a hover, above a platform...).
  void set_state(const VehicleState& state);
  Truth truth() const;
  const Scene& scene() const { return *scene_; }
  /// The platform's motion (scenario platform.motion), null for a platform standing still or
  /// none. The scene's platform box and Truth::platform follow it: posed at now_utime() after
  /// every physics step, at a frame's mid-exposure while that frame renders.
  const PlatformMotion* platform_motion() const {
    return platform_motion_ ? &*platform_motion_ : nullptr;
  }
  /// Seconds since the simulator's start at `utime` (the platform motion's time).
  double motion_time_s(int64_t utime) const {
    return 1e-6 * static_cast<double>(utime - start_utime_);
  }
  const Scenario& scenario() const { return scenario_; }
  const Dynamics& dynamics() const { return *dynamics_; }
  /// Specific force of the last physics step in body (noise-free IMU) [m/s^2].
  const Vector3d& specific_force_B() const { return last_.specific_force_B; }

  /// Motion-capture samples whose latency has elapsed, oldest first (none when the scenario's
  /// mocap.enabled is false).
  std::vector<MocapSample> take_mocap();
  /// IMU samples taken since the last call, oldest first (none when imu.enabled is false).
  std::vector<ImuSample> take_imu();
  /// Rangefinder samples whose latency has elapsed, oldest first, with and without a
  /// measurement (none when rangefinder.enabled is false).
  std::vector<RangeSample> take_range();
  /// Barometer samples whose latency has elapsed, oldest first (none when baro.enabled is
  /// false).
  std::vector<BaroSample> take_baro();
  /// The newest camera frame completed since the last call, rendered now (older unrendered
  /// frames are skipped: rendering is what costs). Nothing without a camera.
  std::optional<CameraFrame> take_camera();
  /// Number of frames skipped by take_camera() so far.
  int64_t camera_frames_skipped() const { return camera_.frames_skipped; }
  /// Frames the simulated driver lost (camera.effects.driver) so far.
  int64_t camera_frames_dropped() const { return camera_.frames_dropped; }
  /// The camera's model as rendered: the rig's with the scenario's lens (camera.effects.lens);
  /// the vision must undistort with this one. The rig's when there is no camera.
  std::optional<CameraModel> camera_model() const {
    return camera_.rig ? std::optional<CameraModel>(camera_.rig->model) : std::nullopt;
  }
  /// The airframe's vibration (scenario vibration:).
  const Vibration& vibration() const { return vibration_; }
  /// The same for the flow camera (scenario flow_camera, FLOW_CAMERA).
  std::optional<CameraFrame> take_flow_camera();
  int64_t flow_camera_frames_skipped() const { return flow_camera_.frames_skipped; }
  /// Motion capture delivers nothing sampled in [from, to) (failsafe tests).
  void inject_mocap_dropout(int64_t from_utime, int64_t to_utime);

  /// Noise-free image of the scene from any camera on a vehicle at X_WB.
  cv::Mat render(const CameraMount& mount, const CameraModel& model, const Isometry3d& X_WB) const;
  /// Threads the camera renderer may use (default 1).
  void set_render_threads(int n);

 private:
  struct PendingFrame {
    int64_t utime = 0, seq = 0;
    double gain = 1.0;
    size_t noise_offset = 0;
    std::vector<Isometry3d> X_WC;     // over the exposure
    std::vector<int64_t> X_WC_utime;  // their times: a moving platform is placed at each
    // Camera effects: per band of rows [band_rows[b], band_rows[b + 1]) its poses over the
    // exposure (rolling shutter, vibration) and their times; empty: the whole frame from X_WC.
    std::vector<int> band_rows;
    std::vector<std::vector<Isometry3d>> band_X_WC;
    std::vector<std::vector<int64_t>> band_utime;
    double ev = 0.0;
    bool duplicate = false;
    int64_t stamp = 0;  // the published stamp (utime plus the driver's jitter)
  };
  // One rendered camera: its parameters, rig, renderer, noise and frame schedule.
  struct CameraStream {
    CameraParams params;
    std::optional<CameraRig> rig;
    std::unique_ptr<Renderer> renderer;  // set when the camera is rendered
    std::mt19937_64 rng;
    std::vector<float> noise;
    int64_t period_us = 0, next_frame_utime = 0, frame_seq = 0, frames_skipped = 0;
    AutoGain auto_gain;
    std::optional<PendingFrame> pending;
    // Camera effects (camera_effects.hpp): their own random stream, so switching one on
    // changes nothing else of a seed.
    std::mt19937_64 fx_rng;
    ExposureSteps exposure_steps;
    cv::Mat vignette;     // per-pixel factor; empty without vignetting
    cv::Mat last_pixels;  // for the driver's duplicates
    int64_t last_stamp = 0;
    int64_t frames_dropped = 0;
  };
  void physics_step();
  // Outcome flags and sensors after the state moved to now_utime_ (the IMU only when this
  // simulator flew the step).
  void after_step(double dt, bool imu);
  // Poses the scene's moving platform (box and truth) at `utime`.
  void place_platform(int64_t utime);
  // What the autopilot's inner loop follows: the last command, or its command-loss failsafe.
  AttitudeCommand autopilot_command();
  void start_camera(CameraStream& c);
  void schedule_camera(CameraStream& c);
  // The camera's pose at t_us along the simulated trajectory (pose history), shaken by the
  // vibration.
  Isometry3d camera_pose_at(double t_us, const Isometry3d& X_BC) const;
  std::optional<CameraFrame> take_frame(CameraStream& c);

  Scenario scenario_;
  VehicleParams vehicle_;
  std::unique_ptr<Scene> scene_;  // stable address: Dynamics refers to it
  std::unique_ptr<Dynamics> dynamics_;
  std::optional<PlatformMotion> platform_motion_;
  VehicleState state_;
  AttitudeCommand cmd_;
  int64_t last_command_utime_ = 0;         // sim time the last command was received
  std::optional<int64_t> cmd_lost_since_;  // failsafe active since
  std::optional<int64_t> cmd_loss_rest_since_;
  bool cmd_loss_disarmed_ = false;
  uint64_t disarms_refused_ = 0;
  int64_t now_utime_;
  int64_t start_utime_;
  int64_t dt_us_;
  StepResult last_;

  std::mt19937_64 wind_rng_;
  Vector3d gust_W_ = Vector3d::Zero();
  MocapEmulator mocap_;
  ImuEmulator imu_;
  RangefinderEmulator rangefinder_;
  BaroEmulator baro_;

  bool landed_ = false, tipped_ = false, collided_ = false, wall_contact_ = false;
  bool out_of_area_ = false;
  int n_collisions_ = 0;
  double rest_s_ = 0.0;

  Vibration vibration_;
  CameraStream camera_, flow_camera_;
  mutable std::unique_ptr<Renderer> adhoc_renderer_;  // for render() with another model
  PoseBuffer history_;
  int render_threads_ = 1;
};

}  // namespace alight::sim

#pragma once
// Closed-loop flights composed in-process, deterministic: alight_sim (vehicle, motion capture,
// IMU; camera rendering only for real vision) + outer_loop::PositionController +
// autonomy::Autonomy + ORACLE VISION (the test fixture standing in for the vision process) or,
// with camera_vision set, the caller's real vision on rendered frames. Used by the ctest
// closed-loop tests (a few seeds) and by bench/autonomy (20 seeds per platform). Commands are
// issued as the node's --auto-go does: TAKEOFF once a pose arrived, GO once hovering.
// With onboard_estimate it flies without motion capture (issue 17): the onboard estimator
// (test/estimator/sim_onboard.hpp: alight-estimator's work) gives the pose and its health.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "autonomy/autonomy.hpp"
#include "common/pose_buffer.hpp"
#include "estimator/onboard.hpp"
#include "oracle_vision.hpp"
#include "sim/simulator.hpp"

namespace alight::autonomy::test {

struct ClosedLoopConfig {
  std::string vehicle_file;   ///< config/vehicles/*.yaml
  std::string scenario_file;  ///< config/scenarios/*.yaml
  Mission mission = Mission::kLanding;
  uint64_t seed = 1;          ///< sim seed (platform placement, noise) and oracle / autonomy seed
  double time_limit_s = 240;  ///< sim time limit after the start [s]
  OracleVisionParams vision;  ///< mission, mount and seed are filled in from the above
  /// Called every 5 ms of sim time; may issue an operator command (ABORT, KILL), silence the
  /// vision, cut motion capture or set the onboard estimate's health.
  std::function<void(const Autonomy&, double t_s, struct ScriptActions&)> script;
  /// Overrides the scenario's opening size (width, height) [m].
  std::optional<Vector2d> opening_size_m;
  /// Overrides the vehicle's rotor tip span (sim model and autonomy's fit check alike) [m].
  std::optional<double> rotor_span_m;
  /// Overrides the velocity the outer loop follows a setpoint at (and so the fastest platform
  /// autonomy follows, as load_params derives it) [m/s].
  std::optional<double> max_feedforward_xy_mps;
  /// Overrides autonomy.detection.max_retries: the searches flown after the first.
  std::optional<int> detection_max_retries;
  /// Real vision instead of the oracle: the simulator renders the mission's camera and this is
  /// called with each frame and the motion-capture pose interpolated at its exposure, paired by
  /// the vision node's policy (vision/node/frame_pose_pairing.hpp; nullopt when motion capture has
  /// none before a frame exposed 100 ms later); what it returns reaches autonomy at once
  /// (processing time is not simulated).
  std::function<std::optional<TargetMeasurement>(const sim::CameraFrame&,
                                                 const std::optional<PoseSample>&)>
      camera_vision;
  /// With camera_vision: the moving platform's measurement of the frame camera_vision just
  /// processed (VISION_PLATFORM, found), given to autonomy as the node would.
  std::function<std::optional<PlatformMeasurement>()> camera_platform;
  /// Flies without motion capture (issue 17), as config/launch/sim_landing_nomocap.yaml and
  /// sim_ingress_nomocap.yaml: the scenario's motion capture is off; the simulator's IMU,
  /// rangefinder, barometer and downward frames feed the onboard estimator as alight-estimator
  /// does (its parameters from the vehicle file), and its ESTIMATE_POSE (one per fused IMU
  /// sample) is the pose that vision's pairing, autonomy and the outer loop read, its
  /// STATE_ESTIMATE health goes to autonomy with the same step (a scripted `estimate` overrides
  /// it). The truth only scores. Landing: the flow and the vision share the downward camera.
  /// Ingress: the simulator renders the downward camera besides the forward one (the scenario's
  /// flow_camera, alight-sim --flow-camera) and only the estimator sees it. With camera_vision
  /// only (the oracle measures in the true frame, not the estimate's).
  bool onboard_estimate = false;
  /// With onboard_estimate: called after each downward frame reached the onboard estimator
  /// (diagnostics: its last_frame() and state()).
  std::function<void(const estimator::Onboard&)> on_flow_frame;
};

struct ScriptActions {
  Vector3d p_W_true = Vector3d::Zero();    ///< in: true vehicle position now
  std::optional<OperatorCommand> command;  ///< sent to autonomy now
  bool vision_silent = false;              ///< sticky: the oracle stops publishing
  std::optional<double> drop_mocap_for_s;  ///< motion capture lost from now on for this long
  /// Sticky: the onboard estimate's health (issue 17), sent with every IMU sample from now on,
  /// as alight-estimator publishes STATE_ESTIMATE; none: no STATE_ESTIMATE (the default).
  std::optional<EstimateHealth> estimate;
};

struct ClosedLoopResult {
  Phase phase = Phase::kIdle;  ///< final autonomy phase
  std::string reason;
  bool landed = false;  ///< sim: at rest on the platform top, motors off
  bool tipped = false;
  bool collided = false;
  int n_collisions = 0;
  bool armed = true;              ///< sim: motors armed at the end
  double touchdown_error_m = -1;  ///< lateral distance body origin - platform top centre [m]
  double mission_time_s = 0;      ///< GO to LANDED / DONE [s]
  double sim_time_s = 0;
  Vector3d final_p_W = Vector3d::Zero();
  Vector3d estimate_error_W = Vector3d::Zero();  ///< final estimate - true target [m]
  int n_measurements = 0, n_rejected = 0, retries = 0;
  int candidate_looks = 0;  ///< the search paused over a believed platform (moving_landing.hpp)
  std::vector<std::string> retry_reasons;  ///< autonomy's reason at each retry
  double max_lateral_in_wall_m = 0;  ///< ingress: largest offset from the opening centre while
                                     ///< the body crossed the wall plane [m]
  bool crossed_wall = false;
  double min_z_after_event_m = 1e9;  ///< lowest body z after the first scripted action [m]
  double final_z_m = 0;
  double error_at_final_descent_m = -1;  ///< lateral body - platform centre entering FINAL_DESCENT
  double error_at_touchdown_m = -1;      ///< ... when autonomy detected the touch-down
  Vector3d p_W_at_touchdown = Vector3d::Zero();  ///< the body then (the slide: final_p_W - this)
  /// At the detected touch-down: the body's heading against the platform's axes (mod 90 deg)
  /// [deg]; at the first contact with the top: the body's vertical speed relative to the top's
  /// just before it (negative: closing) [m/s]; 0 when none.
  double heading_error_at_touchdown_deg = 0;
  double contact_rel_vz_mps = 0;
  double platform_yaw_rad = 0;
  /// Final body position relative to the platform top's centre, in the platform's frame (x along
  /// its length), and the platform's length and width: touchdown plots over the outline [m].
  Vector2d final_in_platform_m = Vector2d::Zero();
  Vector2d platform_size_m = Vector2d::Zero();
  bool tipped_before_go = false;  ///< sim's sticky "tipped" already set when GO was issued (a
                                  ///< scenario whose random platform overlaps the start spot)
  bool on_platform_top = false;   ///< sim contact at the end is the platform top
  // Flying on the onboard estimate (onboard_estimate):
  /// Autonomy's final target estimate taken into the true frame through the final estimated and
  /// true poses, minus the true target: the relative error that matters without motion capture
  /// (estimate_error_W above also holds the estimator's drift then) [m].
  Vector3d estimate_error_rel_W = Vector3d::Zero();
  Vector3d estimate_error_rel_at_approach_W = Vector3d::Zero();  ///< the same entering APPROACH
  /// ... and at the detected touch-down (the estimate the landing used; after it the estimator
  /// keeps running on the ground until the flight ends).
  Vector3d estimate_error_rel_at_touchdown_W = Vector3d::Zero();
  Vector3d pose_error_W = Vector3d::Zero();  ///< final estimated - true body position [m]
  Vector3d pose_error_at_approach_W = Vector3d::Zero();  ///< ... entering APPROACH [m]
  double max_pose_error_h_m = 0;  ///< largest horizontal estimated - true position in flight [m]
  double max_pose_error_z_m = 0;  ///< largest vertical ... [m]
  int estimate_degraded_steps = 0, estimate_lost_steps = 0;  ///< airborne IMU steps not OK
  std::string estimate_reasons;  ///< every health reason seen in flight, "no_flow|no_range"
  int64_t flow_fused = 0, flow_rejected = 0;  ///< the filter's verdicts on flow samples
  int64_t flow_on_floor = 0;         ///< ... judged against the floor while over the platform
  int64_t flow_inflated = 0;         ///< ... fused with their noise inflated after a run refused
  int64_t flow_velocity_resets = 0;  ///< horizontal velocity set to the flow's
  /// The flow front end's frame pairs by outcome (estimator::FlowReason order): why it gave
  /// no sample.
  std::vector<int64_t> flow_reasons;
  int terrain_resets = 0;  ///< platform steps on and off
  /// Ingress: the body origin's offset from the opening's centre (lateral along the wall, up)
  /// at the step it crossed the opening's plane; none when it never did [m].
  std::optional<Vector2d> crossing_offset_m;
  Vector3d pose_error_at_crossing_W = Vector3d::Zero();  ///< onboard: estimated - true there [m]
};

ClosedLoopResult fly_closed_loop(const ClosedLoopConfig& config);

}  // namespace alight::autonomy::test

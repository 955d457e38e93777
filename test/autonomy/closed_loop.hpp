#pragma once
// Closed-loop flights composed in-process, deterministic: alight_sim (vehicle, motion capture,
// IMU; camera rendering only for real vision) + outer_loop::PositionController +
// autonomy::Autonomy + ORACLE VISION (the test fixture standing in for the vision process) or,
// with camera_vision set, the caller's real vision on rendered frames. Used by the ctest
// closed-loop tests (a few seeds) and by bench/autonomy (20 seeds per platform). Commands are
// issued as the node's --auto-go does: TAKEOFF once a pose arrived, GO once hovering.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "autonomy/autonomy.hpp"
#include "common/pose_buffer.hpp"
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
  /// Real vision instead of the oracle: the simulator renders the mission's camera and this is
  /// called with each frame and the motion-capture pose interpolated at its exposure, paired by
  /// the vision node's policy (vision/frame_pose_pairing.hpp; nullopt when motion capture has
  /// none before a frame exposed 100 ms later); what it returns reaches autonomy at once
  /// (processing time is not simulated).
  std::function<std::optional<TargetMeasurement>(const sim::CameraFrame&,
                                                 const std::optional<PoseSample>&)>
      camera_vision;
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
  double max_lateral_in_wall_m = 0;  ///< ingress: largest offset from the opening centre while
                                     ///< the body crossed the wall plane [m]
  bool crossed_wall = false;
  double min_z_after_event_m = 1e9;  ///< lowest body z after the first scripted action [m]
  double final_z_m = 0;
  double error_at_final_descent_m = -1;  ///< lateral body - platform centre entering FINAL_DESCENT
  double error_at_touchdown_m = -1;      ///< ... when autonomy detected the touch-down
  double platform_yaw_rad = 0;
  bool tipped_before_go = false;  ///< sim's sticky "tipped" already set when GO was issued (a
                                  ///< scenario whose random platform overlaps the start spot)
  bool on_platform_top = false;   ///< sim contact at the end is the platform top
};

ClosedLoopResult fly_closed_loop(const ClosedLoopConfig& config);

}  // namespace alight::autonomy::test

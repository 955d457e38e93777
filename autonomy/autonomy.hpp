#pragma once
// The autonomy loop (paper 3.4, Fig. 4): IDLE -> TAKEOFF -> HOVER -> (GO) DETECTION ->
// REFINEMENT -> APPROACH (-> FINAL_DESCENT -> LANDED for landing, -> DONE for ingress), with
// lost-target retries, refusals, operator ABORT / KILL / LAND_HERE / NUDGE, the motion-capture
// failsafes and the geofence. Pure: stepped with the utime of its inputs, no clock, no LCM.
//
//  - Detection (3.4.1, 4.3): a lawnmower over the landing area / a pass along the wall until the
//    first VISION_TARGET of the mission's kind.
//  - Refinement (3.4.1, eqs. 7-9): autonomy/refinement.hpp (estimate, outlier gate, vantages).
//  - Approach, landing (3.4.1): above the estimate at the current altitude; descend at v_des
//    (x3(t+1) = x3(t) - v_des dt) only while the radial error e_r(t) is within radial_tol; below
//    final_height the setpoint drops rapidly; touch-down from the accelerometer (touchdown.hpp)
//    cuts the motors. A platform whose reported short side is smaller than the gear footprint
//    plus margins is refused (a fit check the paper does not have).
//  - Approach, ingress (3.4.2; the paper did not fly it): align on the opening's normal at a
//    standoff, then advance along the normal only while the lateral and vertical errors are
//    within tolerance, stop pass_distance beyond the wall -> DONE. Openings smaller than the
//    vehicle plus clearance are refused.
//  - Target lost in refinement or approach: back to a safe height, detection again, at most
//    max_retries times, then HOLD and report.
//  - Failsafes: pose older than pose_stale_s freezes the mission (the outer loop levels and
//    holds hover thrust); older than pose_lost_s: FAILSAFE, controlled descent, motors off at
//    touch-down. ABORT: climb to abort_height and HOLD. KILL: motors off at once, for good.
//  - Restart (issue 14, as PX4 does after an in-flight reboot of a module): nothing is
//    commanded before the first pose. If it (or the restored state) shows the vehicle flying,
//    the autonomy holds there with the motors on and waits for the operator (GO, NUDGE, ABORT,
//    LAND_HERE, KILL); it never takes off again. A restored KILL keeps the motors off; a
//    restored pose-lost failsafe continues its controlled descent.
//  - Every input is untrusted even here (defence in depth behind the node's conversions):
//    non-finite poses, IMU samples, targets and NUDGE offsets are ignored, and a non-finite
//    setpoint is never sent.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "autonomy/params.hpp"
#include "autonomy/refinement.hpp"
#include "autonomy/search_path.hpp"
#include "autonomy/touchdown.hpp"
#include "autonomy/types.hpp"

namespace alight::autonomy {

class Autonomy {
 public:
  /// `restored`: the latches of a previous instance (the node's state file); default: a fresh
  /// start.
  explicit Autonomy(const AutonomyParams& params, const RestartState& restored = {});

  /// One step at now_utime (the newest sensor time: pose or IMU; never the wall clock) with
  /// whatever arrived since the last step.
  Output update(const Inputs& in, int64_t now_utime);

  Phase phase() const { return phase_; }
  Mission mission() const { return mission_; }
  Failsafe failsafe() const { return failsafe_; }
  const RefinementEstimator& estimator() const { return estimator_; }
  const AutonomyParams& params() const { return params_; }
  /// The final estimate the approach flies to (valid from APPROACH on).
  const Vector3d& final_estimate() const { return estimate_W_; }
  const Vector3d& current_vantage() const { return vantage_W_; }
  int retries() const { return retries_; }
  /// Whether the first pose has been seen (and the start decided: on the ground, or flying).
  bool started() const { return started_; }
  /// Started while the vehicle was flying (or with a restored KILL): take-off and --auto-go
  /// must never run.
  bool resumed() const { return resumed_; }
  /// What a restart must restore (the node persists it whenever it changes).
  RestartState restart_state() const;

 private:
  enum class IngressStage { kAlign, kThrough };

  bool airborne() const;
  bool pose_fresh() const;
  void enter(Phase phase, std::string reason);
  void handle_command(const OperatorCommand& cmd);
  bool accept(const OperatorCommand& cmd);
  void handle_target(const TargetMeasurement& m);
  /// Holds (and says so) when no VISION_TARGET came for failsafe.vision_silent_s.
  bool vision_silent();
  void step_phase(double dt_s);
  void start_detection(const std::string& reason);
  void start_refinement(const TargetMeasurement& m);
  void finish_refinement();
  void next_vantage();
  void add_waypoint(const Vector3d& X_W);
  void target_lost(const std::string& what);
  void hold(const std::string& reason, Failsafe failsafe, double min_z_m);
  void enter_pose_lost();
  void start_from_first_pose();
  Output make_output();

  AutonomyParams params_;
  RefinementEstimator estimator_;
  VantageSampler sampler_;
  TouchdownDetector touchdown_;
  PathFollower path_;

  RestartState restored_;
  bool started_ = false;
  bool resumed_ = false;
  Vector3d last_finite_sp_p_W_ = Vector3d::Zero();
  double last_finite_yaw_rad_ = 0.0;

  int64_t now_utime_ = 0;
  std::optional<int64_t> last_step_utime_;
  std::optional<PoseSample> pose_;

  Phase phase_ = Phase::kIdle;
  Mission mission_ = Mission::kNone;
  Failsafe failsafe_ = Failsafe::kNone;
  Failsafe failsafe_before_stale_ = Failsafe::kNone;  // restored when the pose is back
  std::string reason_ = "waiting for the first pose";

  // Setpoint being commanded.
  Vector3d sp_p_W_ = Vector3d::Zero();
  Vector3d sp_v_W_ = Vector3d::Zero();
  double yaw_sp_rad_ = 0.0;
  bool motors_on_ = false;
  bool geofence_clamped_ = false;

  Vector3d hold_p_W_ = Vector3d::Zero();
  Vector2d takeoff_xy_ = Vector2d::Zero();
  double z_sp_m_ = 0.0;

  int retries_ = 0;
  std::optional<int64_t> go_utime_;
  std::optional<int64_t> end_utime_;
  std::optional<int64_t> last_found_utime_;
  std::optional<int64_t> last_vision_utime_;      // any VISION_TARGET, found or not
  std::optional<int64_t> pose_back_since_utime_;  // pose fresh again in the pose-lost failsafe
  int64_t phase_start_utime_ = 0;

  // Refinement.
  Vector3d vantage_W_ = Vector3d::Zero();
  int64_t vantage_since_utime_ = 0;
  std::optional<int64_t> at_vantage_since_;
  std::vector<Vector2d> sizes_m_;
  std::vector<Vector3d> at_vantage_W_;
  Vector3d first_sighting_W_ =
      Vector3d::Zero();  // X_V,1, possibly from a partial view  // waypoints seen while dwelling at
                         // the current vantage
  Vector3d normal_sum_W_ = Vector3d::Zero();
  Vector2d yaw4_sum_ = Vector2d::Zero();  // landing: sum of (cos, sin)(4 yaw), yaw modulo 90 deg

  // Approach.
  Vector3d estimate_W_ = Vector3d::Zero();
  Vector3d normal_W_ = Vector3d::UnitX();
  bool land_here_ = false;
  IngressStage ingress_stage_ = IngressStage::kAlign;
  std::optional<int64_t> aligned_since_;
  double through_s_m_ = 0.0;

  // Failsafe descent.
  double failsafe_z_m_ = 0.0;
  int64_t failsafe_since_utime_ = 0;

  // Operator commands.
  std::map<std::string, int64_t> last_seq_;
  int cmds_rejected_ = 0;
  int64_t last_cmd_seq_ = -1;
};

}  // namespace alight::autonomy

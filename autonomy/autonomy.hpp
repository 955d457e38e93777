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
//  - The onboard estimate's health (STATE_ESTIMATE; flying without motion capture the
//    pose is that estimate's): in flight, DEGRADED holds and waits for the operator (not in the
//    final descent, which finishes the landing; not a hold, a descent or a LAND_HERE already
//    under way; not the take-off's climb for the flow alone); LOST, or no STATE_ESTIMATE for
//    estimate_silent_s once one was heard, is the failsafe descent of a lost pose on the pose the
//    estimator still dead-reckons, stopped into a hold when the estimate is OK again for
//    pose_recovered_s. TAKEOFF and GO wait for an OK estimate once one was heard (with
//    require_estimate, also before). Never heard: nothing changes (flying on motion capture). As
//    PX4 does: its Land mode, in a failsafe, needs only the altitude and goes on landing without a
//    position estimate, and a vehicle that loses its position descends where it is (docs.px4.io
//    v1.14, flight_modes_mc/land; the Descend flight task, PX4 pull request 13143).
//  - Restart (as PX4 does after an in-flight reboot of a module): nothing is
//    commanded before the first pose. If it (or the restored state) shows the vehicle flying,
//    the autonomy holds there with the motors on and waits for the operator (GO, NUDGE, ABORT,
//    LAND_HERE, KILL); it never takes off again. A restored KILL keeps the motors off; a
//    restored pose-lost or estimate-lost failsafe continues its controlled descent.
//  - Structure: the state that matters in one phase only lives in that phase's struct
//    (phases:: below, one alternative of a std::variant per Phase): entering a phase constructs
//    it, leaving destroys it, so nothing is reset by hand. What differs between landing and
//    ingress is asked of the MissionProfile chosen at GO (autonomy/mission_profile.hpp); whether
//    an operator command is obeyed, of the CommandGate (autonomy/command_gate.hpp).
//  - Every input is untrusted even here (defence in depth behind the node's conversions):
//    non-finite poses, IMU samples, targets and NUDGE offsets are ignored, and a non-finite
//    setpoint is never sent.

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "autonomy/command_gate.hpp"
#include "autonomy/mission_profile.hpp"
#include "autonomy/moving_landing.hpp"
#include "autonomy/params.hpp"
#include "autonomy/refinement.hpp"
#include "autonomy/search_path.hpp"
#include "autonomy/touchdown.hpp"
#include "autonomy/types.hpp"

namespace alight::autonomy {

/// The state each phase of Phase owns, in the same order (PhaseState's index is the Phase).
namespace phases {
struct Idle {};
struct Takeoff {
  Vector2d xy_W = Vector2d::Zero();  ///< climbing straight up from here
  double z_sp_m = 0.0;               ///< altitude setpoint, rising at climb_rate
};
struct Hover {
  Vector3d hold_p_W = Vector3d::Zero();  ///< NUDGE moves it
};
struct Detection {
  PathFollower path;  ///< the mission's search path and the carrot's progress along it
  /// The platform track last looked at (its since_utime) and when the look began
  /// (moving_landing.hpp, step 0).
  int64_t looked_track_utime = 0, look_since_utime = 0;
  bool looking = false;
};
struct Refinement {
  std::optional<int64_t> last_found_utime;  ///< the target last in sight (full or partial view)
  Vector3d first_sighting_W = Vector3d::Zero();  ///< X_V,1, possibly from a partial view
  std::vector<Vector2d> sizes_m;                 ///< every full view's measured size
  Vector3d normal_sum_W = Vector3d::Zero();      ///< sum of the measured normals
  Vector2d yaw4_sum = Vector2d::Zero();   ///< landing: sum of (cos, sin)(4 yaw), yaw mod 90 deg
  Vector2d yaw2_sum = Vector2d::Zero();   ///< landing: sum of (cos, sin)(2 yaw), the long axis
  Vector3d vantage_W = Vector3d::Zero();  ///< the vantage point being flown to
  int64_t vantage_since_utime = 0;
  std::optional<int64_t> at_vantage_since_utime;  ///< dwelling at the vantage since
  std::vector<Vector3d> at_vantage_W;             ///< waypoints seen while dwelling there
  std::vector<Vector2d> at_vantage_size_m;        ///< and the sizes those views measured
  /// Landing: where the vantages look from since a view cut the top (mission_profile.hpp).
  std::optional<ViewToFit> view;
  std::vector<TargetMeasurement> cut_views;  ///< the latest kCutViewsToFit cut views, oldest first
};
struct Approach {
  ApproachState how;                            ///< the mission profile's own approach state
  std::optional<int64_t> last_found_utime;      ///< carried over from refinement
  std::optional<int64_t> disagree_since_utime;  ///< every found target far from the estimate
  /// A moving platform's approach (moving_landing.hpp): flown on the platform filter.
  std::optional<MovingApproach> moving;
  /// The target's size the refinement measured (the full views' medians, as size_m of
  /// TargetMeasurement); NaN: not measured.
  Vector2d size_m = Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  TopRoom room{};         ///< the room that top leaves the gear (the final hold's bounds)
  int n_disagreeing = 0;  ///< found targets far from the estimate since disagree_since_utime
  /// Flying on the onboard estimate: the refinement's filter going on over the frame's drift
  /// (refinement.hpp); none on motion capture, where the estimate is final (paper 3.4.1).
  std::optional<ApproachAnchor> anchor{};
};
struct FinalDescent {
  double z_sp_m = 0.0;
  TouchdownDetector touchdown;                ///< armed on entry
  bool may_pause = false;                     ///< onto a target (not the operator's LAND_HERE)
  std::optional<int64_t> paused_since_utime;  ///< a gust carried the vehicle off: stopped since
  std::optional<int64_t> calm_since_utime;    ///< ... and calm again since
  bool moving = false;                        ///< onto a moving platform: follows its filter
  TopRoom room{};       ///< the approach's room (the final hold's bounds, the pause's)
  double held_s = 0.0;  ///< the final hold's wait before the descent: the calm bounds it earned
};
struct Landed {};
struct Done {
  Vector3d hold_p_W = Vector3d::Zero();
};
struct Hold {
  Vector3d hold_p_W = Vector3d::Zero();
  std::optional<int64_t> descend_at_utime;  ///< a failsafe's hold: then the controlled descent
};
struct FailsafeDescent {
  double z0_m = 0.0;  ///< altitude when the pose (or the estimate) was lost
  int64_t since_utime = 0;
  /// The cause cleared since: the pose fresh again (pose lost), the estimate OK (estimate lost).
  std::optional<int64_t> recovered_since_utime;
  TouchdownDetector touchdown;  ///< armed on entry
};
struct Killed {};
}  // namespace phases

using PhaseState =
    std::variant<phases::Idle, phases::Takeoff, phases::Hover, phases::Detection,
                 phases::Refinement, phases::Approach, phases::FinalDescent, phases::Landed,
                 phases::Done, phases::Hold, phases::FailsafeDescent, phases::Killed>;

class Autonomy {
 public:
  /// `restored`: the latches of a previous instance (the node's state file); default: a fresh
  /// start.
  explicit Autonomy(const AutonomyParams& params, const RestartState& restored = {});

  /// One step at now_utime (the newest sensor time: pose or IMU; never the wall clock) with
  /// whatever arrived since the last step.
  Output update(const Inputs& in, int64_t now_utime);
  /// An operator command whose signature check failed at the link (cmd.link_reject says why):
  /// the command gate counts it like every refusal, but the loop does not step on it (a flood
  /// of forgeries drives nothing, and gets no setpoint published).
  void refused_at_link(const OperatorCommand& cmd);

  Phase phase() const { return static_cast<Phase>(state_.index()); }
  Mission mission() const { return profile_ ? profile_->mission() : Mission::kNone; }
  Failsafe failsafe() const { return failsafe_; }
  const RefinementEstimator& estimator() const { return estimator_; }
  /// The moving platform's filter (VISION_PLATFORM), landing only.
  const PlatformFilter& platform_filter() const { return platform_; }
  const AutonomyParams& params() const { return params_; }
  /// The final estimate the approach flies to (valid from APPROACH on, kept after the mission).
  const Vector3d& final_estimate() const { return estimate_W_; }
  /// Found targets refused in APPROACH for lying outside the gate around the final estimate.
  uint64_t vision_refused() const { return vision_refused_; }
  /// The vantage point refinement flies to (zero outside REFINEMENT).
  Vector3d current_vantage() const;
  int retries() const { return retries_; }
  /// Last drops onto a moving platform given up this mission (moving_landing.hpp, step 5).
  int drop_go_arounds() const { return drop_go_arounds_; }
  /// Looks the detection took at a believed platform not yet shown moving, this mission
  /// (moving_landing.hpp, step 0).
  int candidate_looks() const { return candidate_looks_; }
  /// Why the phase is what it is (AutonomyStatus::reason).
  const std::string& reason() const { return reason_; }
  /// Whether the first pose has been seen (and the start decided: on the ground, or flying).
  bool started() const { return started_; }
  /// Started while the vehicle was flying (or with a restored KILL): take-off and --auto-go
  /// must never run.
  bool resumed() const { return resumed_; }
  /// What a restart must restore (the node persists it whenever it changes).
  RestartState restart_state() const;
  /// The operator commands' checks and counters.
  const CommandGate& commands() const { return gate_; }

 private:
  bool airborne() const;
  bool pose_fresh() const;
  /// Landing's final hold and descent with landing.precise_final: setpoints marked precise.
  bool precise_setpoint() const;
  /// The estimate's level now and what to say about it: its own level, or kLost once it has been
  /// silent for estimate_silent_s; nullopt when no STATE_ESTIMATE was ever heard.
  struct EstimateCondition {
    EstimateHealth::Level level = EstimateHealth::Level::kOk;
    std::string what;  ///< "state estimate degraded (no_flow)", "no STATE_ESTIMATE for 0.6 s"
  };
  std::optional<EstimateCondition> estimate_condition() const;
  /// Why TAKEOFF / GO must wait for the estimate (nullopt: they need not).
  std::optional<std::string> estimate_refusal() const;
  /// In flight: DEGRADED pauses the mission, and holds once it has lasted kDegradedPauseS; LOST
  /// (or silent) starts the failsafe descent. True while paused (no progress this step).
  bool react_to_estimate();
  /// The position covariance of the frame the waypoints are measured in: the onboard estimate's
  /// (its growth is the frame's drift), zero on motion capture (no STATE_ESTIMATE heard).
  Matrix3d frame_cov() const { return estimate_ ? estimate_->position_cov : Matrix3d::Zero(); }
  /// The surface under the onboard estimate's rangefinder (W) while the estimate is fresh and
  /// fuses one; nullopt on motion capture, without a rangefinder, or a silent estimate.
  std::optional<double> terrain_m() const;
  /// Seconds since the target was last in sight (since the phase began when it never was).
  double since_found_s(const std::optional<int64_t>& last_found_utime) const;
  /// Leaves the current phase (destroying its state) for `state`.
  template <class State>
  State& enter(State state, std::string reason);
  /// The held position of HOVER, HOLD and DONE (nullptr in the other phases).
  Vector3d* held_position();
  /// The touch-down detector of FINAL_DESCENT and FAILSAFE (nullptr in the other phases).
  TouchdownDetector* touchdown();
  void handle_command(const OperatorCommand& cmd);
  void handle_target(const TargetMeasurement& m);
  /// A moving platform's measurement: into the filter; in detection or refinement, a platform
  /// the filter trusts moving starts the moving approach.
  void handle_platform(const PlatformMeasurement& m);
  void step_moving(phases::Approach& a, const Vector3d& p, double dt_s);
  /// DETECTION: over a believed platform track that has not yet shown its motion, for
  /// candidate_look_s once per track (the search paused); true while looking.
  bool look_at_candidate(phases::Detection& s);
  /// The last drop onto a moving platform carried off its top (check_drop): back to the moving
  /// approach at the final height, or the failsafe after kMaxDropGoArounds.
  void go_around(const DropCheck& c);
  /// Failsafe::kPlatformTooFast: climb over the platform's follow height and hold.
  void platform_too_fast(const std::string& reason);
  // APPROACH: true (and counted) when `m` lies outside the gate around the final estimate; a
  // sustained disagreement enters the VISION_DISAGREES failsafe.
  bool vision_disagrees(phases::Approach& a, const TargetMeasurement& m);
  /// Holds (and says so) when no VISION_TARGET came for failsafe.vision_silent_s; true then.
  bool hold_if_vision_silent();
  void step_phase(double dt_s);
  void step(phases::Takeoff& s, const Vector3d& p, double dt_s);
  void step(phases::Detection& s, const Vector3d& p, double dt_s);
  void step(phases::Refinement& s, const Vector3d& p, double dt_s);
  void step(phases::Approach& s, const Vector3d& p, double dt_s);
  void step(phases::FinalDescent& s, const Vector3d& p, double dt_s);
  /// The final descent stopped by a gust (final_pause_radial_m) until calm again, or given up
  /// after final_hold_timeout_s.
  enum class FinalPause { kNone, kPaused, kGaveUp };
  FinalPause pause_final_descent(phases::FinalDescent& s, double z_touch_m);
  void step(phases::FailsafeDescent& s, const Vector3d& p, double dt_s);
  void start_detection(const std::string& reason);
  void start_refinement(const TargetMeasurement& m);
  void finish_refinement(phases::Refinement& r);
  void next_vantage(phases::Refinement& r);
  /// A landing top cut by the view's border: higher and turned vantages when it would not fit
  /// the view from where they are (mission_profile.hpp, view_to_fit); true when they moved.
  bool look_to_fit(phases::Refinement& r, const TargetMeasurement& m);
  void add_waypoint(phases::Refinement& r, const Vector3d& X_W, const Vector2d& size_m);
  void target_lost(const std::string& what);
  void hold(const std::string& reason, Failsafe failsafe, double min_z_m);
  void enter_pose_lost();
  void enter_estimate_lost(const std::string& what);
  /// FAILSAFE for `cause`: controlled descent from the current altitude, over xy_W.
  void enter_failsafe_descent(Failsafe cause, std::string reason, const Vector2d& xy_W);
  /// ... over the vehicle (the setpoint's xy without a pose).
  void enter_failsafe_descent(Failsafe cause, std::string reason);
  void start_from_first_pose();
  /// The setpoint's feed-forwards (velocity, acceleration, yaw rate) back to none.
  void zero_feedforward();
  Output make_output();

  // Whole run.
  AutonomyParams params_;
  RefinementEstimator estimator_;  // the current mission's waypoints (reported after it too)
  VantageSampler sampler_;         // one random stream for the run (autonomy.seed)
  CommandGate gate_;

  RestartState restored_;
  bool started_ = false;
  bool resumed_ = false;
  Vector3d last_finite_sp_p_W_ = Vector3d::Zero();
  double last_finite_yaw_rad_ = 0.0;

  int64_t now_utime_ = 0;
  std::optional<int64_t> last_step_utime_;
  std::optional<PoseSample> pose_;
  std::optional<int64_t> last_vision_utime_;  // any VISION_TARGET, found or not
  std::optional<EstimateHealth> estimate_;    // the newest STATE_ESTIMATE's health

  PhaseState state_;
  int64_t phase_start_utime_ = 0;
  std::string reason_ = "waiting for the first pose";
  Failsafe failsafe_ = Failsafe::kNone;
  Failsafe failsafe_before_stale_ = Failsafe::kNone;  // restored when the pose is back
  std::optional<int64_t> degraded_since_utime_;       // the estimate DEGRADED in flight since
  bool paused_on_estimate_ = false;                   // the last step paused the mission for it
  Vector3d pause_p_W_ = Vector3d::Zero();             // ... holding there

  // Setpoint being commanded.
  Vector3d sp_p_W_ = Vector3d::Zero();
  Vector3d sp_v_W_ = Vector3d::Zero();
  Vector3d sp_a_W_ = Vector3d::Zero();  // a moving platform's acceleration fed forward
  double sp_yaw_rate_radps_ = 0.0;      // ... and its turn
  double yaw_sp_rad_ = 0.0;
  bool motors_on_ = false;
  bool geofence_clamped_ = false;

  // The mission (from GO or LAND_HERE; none after TAKEOFF).
  std::unique_ptr<const MissionProfile> profile_;
  int retries_ = 0;
  int drop_go_arounds_ = 0;
  int candidate_looks_ = 0;
  std::optional<int64_t> go_utime_;
  std::optional<int64_t> end_utime_;
  Vector3d estimate_W_ = Vector3d::Zero();  // the final estimate, from APPROACH on
  PlatformFilter platform_;
  uint64_t vision_refused_ = 0;  // found targets outside the gate in APPROACH
};

}  // namespace alight::autonomy

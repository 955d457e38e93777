#pragma once
// Domain inputs and outputs of the autonomy loop (paper 3.4): middleware-free forms of imu_t,
// target_t, operator_cmd_t, state_estimate_t's health and autonomy_status_t (conversions in
// autonomy/convert.hpp).

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "autonomy/platform_filter.hpp"
#include "common/command_reject.hpp"
#include "common/geometry.hpp"
#include "common/pose_buffer.hpp"
#include "outer_loop/setpoint.hpp"

namespace alight::autonomy {

enum class Mission { kNone, kLanding, kIngress };

/// Phases of Fig. 4 (detection, refinement, approach) with the operator's phases around them.
enum class Phase {
  kIdle,
  kTakeoff,
  kHover,
  kDetection,
  kRefinement,
  kApproach,
  kFinalDescent,
  kLanded,
  kDone,
  kHold,      ///< mission suspended: retries exhausted, refusal, abort; hovering
  kFailsafe,  ///< pose or state estimate lost: controlled descent, disarm on touch-down
  kKilled,
};

/// kEstimateLost: the onboard estimate (STATE_ESTIMATE) LOST or silent.
enum class Failsafe {
  kNone,
  kPoseStale,
  kPoseLost,
  kOperatorAbort,
  kKill,
  kEstimateLost,
  kVisionDisagrees,  ///< found targets far from the converged estimate: hold, then descend
  /// A moving platform faster (or turning faster) than the vehicle follows: climb, hold.
  kPlatformTooFast,
};

const char* mission_name(Mission m);
const char* phase_name(Phase p);

struct ImuSample {
  int64_t utime = 0;
  Vector3d accel_B = Vector3d(0, 0, 9.81);  ///< specific force in body [m/s^2]
  Vector3d gyro_B = Vector3d::Zero();       ///< [rad/s]
};

/// One waypoint measurement of the vision system (paper 3.1.3, X_V,i).
struct TargetMeasurement {
  int64_t utime = 0;  ///< exposure time of the image [us]
  Mission mission = Mission::kNone;
  bool found = false;
  /// Not found, but located: seen cut by the image border (target_t REASON_PARTIAL_VIEW:
  /// p_W_target is the centre of its visible part), or an opening seen with too little parallax
  /// to measure it (REASON_LOW_PARALLAX). Good enough to fly to, not to average.
  bool partial = false;
  /// A partial view cut by the image border (REASON_PARTIAL_VIEW), or of a top running on past
  /// its features (REASON_TOP_RUNS_ON): size_m is the extent of the part in view, a lower bound
  /// of the target's.
  bool cut = false;
  Vector3d p_W_target = Vector3d::Zero();  ///< platform centre / opening centre [m]
  Vector3d n_W = Vector3d::UnitZ();        ///< target plane normal, towards the camera
  Vector2d size_m = Vector2d::Zero();      ///< landing: platform extent (long, short);
                                           ///< ingress: opening width, height [m]
  double yaw_rad = 0.0;  ///< landing: platform long axis about world z, in (-pi/2, pi/2] [rad]
};

enum class Command { kNone, kTakeoff, kGo, kAbort, kLandHere, kKill, kNudge };
enum class CommandAuth {
  kNone,        ///< unsigned (accepted only with accept_unsigned_commands)
  kHmacSha256,  ///< signed: refused unless the link's CommandVerifier accepted it (kVerified)
  kVerified,    ///< HMAC-SHA256 verified by the node (common/operator_auth CommandVerifier)
  kInternal,    ///< issued by the node itself (--auto-go in simulation launch files)
};
inline constexpr int kCommandRejectSlots = 8;  ///< autonomy_status_t.cmds_rejected_by_reason

struct OperatorCommand {
  int64_t utime = 0;
  int64_t seq = 0;
  std::string sender;
  Command command = Command::kNone;
  Mission mission = Mission::kNone;  ///< for kGo
  Vector3d nudge_W = Vector3d::Zero();
  CommandAuth auth = CommandAuth::kNone;
  /// kHmacSha256 only: the link's CommandVerifier refused it, for this reason (kNone: the node
  /// had no key to verify it with).
  CommandReject link_reject = CommandReject::kNone;
};

/// The onboard state estimate's health (state_estimate_t, alight-estimator): all the
/// autonomy takes from STATE_ESTIMATE. Its pose reaches the autonomy as the pose (ESTIMATE_POSE
/// remapped onto MOCAP_POSE when flying without motion capture).
/// state_estimate_t.REASON_NO_FLOW: no flow fused for a while (autonomy/convert.cpp checks it).
inline constexpr uint32_t kEstimateReasonNoFlow = 2;

struct EstimateHealth {
  enum class Level { kOk, kDegraded, kLost };
  int64_t utime = 0;  ///< the estimate's time: its newest IMU sample [us]
  Level level = Level::kOk;
  uint32_t reasons = 0;  ///< state_estimate_t.REASON_* bits
  std::string text;      ///< the reasons as names, "no_flow|no_range" ("" for none)
  /// Covariance of p_W_B [m^2] (cov_pva's position block): its growth is the frame's drift.
  Matrix3d position_cov = Matrix3d::Zero();
  /// The height in W of the surface under the rangefinder (terrain_height_m), while the estimator
  /// fuses one (some range fused, and no REASON_NO_RANGE); nullopt otherwise.
  std::optional<double> terrain_m;
};
/// state_estimate_t.REASON_NO_RANGE (autonomy/convert.cpp checks it).
inline constexpr uint32_t kEstimateReasonNoRange = 4;

/// What arrived since the last step (each optional is a new message, consumed by the step).
struct Inputs {
  std::optional<PoseSample> pose;
  std::optional<ImuSample> imu;
  std::optional<TargetMeasurement> target;
  std::optional<OperatorCommand> command;
  std::optional<EstimateHealth> estimate;       ///< STATE_ESTIMATE (none ever: flying on mocap)
  std::optional<PlatformMeasurement> platform;  ///< VISION_PLATFORM, found
};

struct Status {
  int64_t utime = 0;
  Mission mission = Mission::kNone;
  Phase phase = Phase::kIdle;
  std::string reason;
  int n_measurements = 0;  ///< n of eq. 7
  int n_rejected = 0;      ///< waypoints rejected by the outlier gate
  int retries = 0;
  bool has_estimate = false;
  /// The target estimate: in refinement the sample mean of the waypoints (X^_n); from the
  /// approach on the estimate flown to (the mean on motion capture, refinement.hpp's filter of
  /// the drifting frame on the onboard estimate).
  Vector3d estimate_W = Vector3d::Zero();
  Matrix3d covariance = Matrix3d::Zero();  ///< sample covariance of the waypoints
  Vector3d setpoint_W = Vector3d::Zero();
  Failsafe failsafe = Failsafe::kNone;
  int cmds_rejected = 0;
  int64_t last_cmd_seq = -1;
  int64_t last_rejected_seq = -1;  ///< of the last command refused with a reason below
  CommandReject last_reject_reason = CommandReject::kNone;
  std::array<int, kCommandRejectSlots> cmds_rejected_by_reason{};  ///< by CommandReject
  bool geofence_clamped = false;
  double mission_time_s = 0.0;
};

struct Output {
  outer_loop::PositionSetpoint setpoint;
  /// False until the first pose told whether the vehicle is flying (and not after a KILL
  /// either way): an autonomy (re)started in the air must send the outer loop nothing rather
  /// than a motors-off setpoint.
  bool has_setpoint = true;
  Status status;
};

/// What the autonomy must know from before a restart (the node keeps it in a state file, see
/// autonomy/restart_state.hpp): the latches a restart must not forget, and whether it had the
/// motors on. A fresh start gets the defaults.
struct RestartState {
  bool killed = false;                  ///< KILL: the motors stay off for good
  Failsafe failsafe = Failsafe::kNone;  ///< latched failsafe (pose or estimate lost, abort)
  bool motors_on = false;               ///< the previous instance was flying the vehicle
  bool operator==(const RestartState& o) const {
    return killed == o.killed && failsafe == o.failsafe && motors_on == o.motors_on;
  }
  bool operator!=(const RestartState& o) const { return !(*this == o); }
};

}  // namespace alight::autonomy

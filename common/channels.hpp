#pragma once
// Every LCM channel of alight, by name (docs/ARCHITECTURE.md "Channels" has rates and
// subscribers), and the --remap option that renames them per process, as ROS remaps topics:
// `alight-vision --remap CAMERA=CAMERA_LEFT` subscribes to CAMERA_LEFT where the code says
// channels::kCamera. A node built on alight::Node applies its remapping to every channel it
// subscribes to, publishes on, counts or reports (NODE_STATUS shows the names used on LCM).
//
// Code names a channel through these constants only, so a renamed or remapped channel cannot be
// missed by a string literal somewhere.

#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace alight::channels {

/// image_t: raw frames, stamped at exposure. alight-camera or alight-sim → vision, ground
/// station.
inline constexpr const char kCamera[] = "CAMERA";
/// image_t: the downward camera's frames for the onboard estimator's flow when CAMERA carries
/// another camera (ingress without motion capture flies the forward one). alight-sim
/// (`flow_camera:`) → alight-estimator. Where the downward camera is the mission's, the estimator
/// reads CAMERA in its place (`--remap FLOW_CAMERA=CAMERA`).
inline constexpr const char kFlowCamera[] = "FLOW_CAMERA";
/// pose_t: vehicle pose and velocity in the world frame. alight-sim or alight-mocap → vision,
/// autonomy, outer loop, ground station.
inline constexpr const char kMocapPose[] = "MOCAP_POSE";
/// imu_t: accelerometer and gyro. alight-sim (or the autopilot) → autonomy.
inline constexpr const char kImu[] = "IMU";
/// range_t: distance along a body-fixed rangefinder's beam (downward), with its mounting.
/// alight-sim → the onboard estimator.
inline constexpr const char kRange[] = "RANGE";
/// baro_t: static pressure and temperature from a barometer. alight-sim → the onboard
/// estimator.
inline constexpr const char kBaro[] = "BARO";
/// state_estimate_t: the onboard estimate (pose, velocity, covariance, health) at the IMU rate.
/// alight-estimator → autonomy, ground station, logs.
inline constexpr const char kStateEstimate[] = "STATE_ESTIMATE";
/// pose_t: the onboard estimate's pose, the same as STATE_ESTIMATE's. alight-estimator → vision,
/// autonomy and outer loop in place of MOCAP_POSE when flying without motion capture (their
/// `--remap MOCAP_POSE=ESTIMATE_POSE`).
inline constexpr const char kEstimatePose[] = "ESTIMATE_POSE";
/// target_t: one waypoint measurement per processed frame. alight-vision → autonomy, ground
/// station.
inline constexpr const char kVisionTarget[] = "VISION_TARGET";
/// vision_timing_t: per processed frame, the vision's wait, processing time and frame counters
/// (wall and steady clocks, so apart from VISION_TARGET). alight-vision → logs, alight-score.
inline constexpr const char kVisionTiming[] = "VISION_TIMING";
/// platform_motion_t: per landing frame, the moving platform's measured position, velocity,
/// yaw and covariances. alight-vision → autonomy, logs.
inline constexpr const char kVisionPlatform[] = "VISION_PLATFORM";
/// image_t (JPEG): diagnostic image. alight-vision → ground station.
inline constexpr const char kVisionDiag[] = "VISION_DIAG";
/// operator_cmd_t: signed operator commands. alight-ground-station → autonomy.
inline constexpr const char kOperatorCmd[] = "OPERATOR_CMD";
/// autonomy_status_t: phase, measurements, estimate. alight-autonomy → ground station,
/// alight-monitor.
inline constexpr const char kAutonomyStatus[] = "AUTONOMY_STATUS";
/// position_setpoint_t: position + yaw setpoint. alight-autonomy → outer loop.
inline constexpr const char kPositionSetpoint[] = "POSITION_SETPOINT";
/// attitude_cmd_t: roll, pitch, yaw rate, thrust, armed. alight-outer-loop → alight-sim (or the
/// autopilot).
inline constexpr const char kAttitudeCmd[] = "ATTITUDE_CMD";
/// sim_truth_t: true geometry and contact state. alight-sim → tests, scoring (never flight code).
inline constexpr const char kSimTruth[] = "SIM_TRUTH";
/// platform_truth_t: a moving platform's true pose and velocities, with each SIM_TRUTH.
/// alight-sim → tests, scoring (never flight code).
inline constexpr const char kSimPlatform[] = "SIM_PLATFORM";
/// sim_control_t: sensor dropouts for the fault campaign. alight-inject → alight-sim.
inline constexpr const char kSimControl[] = "SIM_CONTROL";
/// process_status_t: each onboard process's state. alight-launch → ground station.
inline constexpr const char kProcessStatus[] = "PROCESS_STATUS";
/// node_status_t: per-input counters, 1 Hz. every alight::Node → logs, fault referee.
inline constexpr const char kNodeStatus[] = "NODE_STATUS";
/// pose_t: the autopilot's own attitude and local position. alight-mavlink → logs, ground
/// station.
inline constexpr const char kAutopilotPose[] = "AUTOPILOT_POSE";
/// autopilot_status_t: link, mode, arming, bridge state, 5 Hz. alight-mavlink → ground station.
inline constexpr const char kAutopilotStatus[] = "AUTOPILOT_STATUS";

/// Every channel above.
inline constexpr std::array<const char*, 23> kAll = {kCamera,          kFlowCamera,
                                                     kMocapPose,       kImu,
                                                     kRange,           kBaro,
                                                     kStateEstimate,   kEstimatePose,
                                                     kVisionTarget,    kVisionTiming,
                                                     kVisionDiag,      kOperatorCmd,
                                                     kAutonomyStatus,  kPositionSetpoint,
                                                     kAttitudeCmd,     kSimTruth,
                                                     kSimControl,      kProcessStatus,
                                                     kNodeStatus,      kAutopilotPose,
                                                     kAutopilotStatus, kSimPlatform,
                                                     kVisionPlatform};

/// True when `name` is one of kAll.
/// True for channels one process publishes on (all but NODE_STATUS, which every node publishes,
/// and OPERATOR_CMD, which any ground station may sign): a second publisher on one is refused
/// while the first is alive (common/bus_auth.hpp). Takes the name in the code (before --remap).
bool single_publisher(const std::string& name);
bool is_known(const std::string& name);
/// The lcm-gen type a channel of kAll carries ("pose_t"); "" for another name.
std::string message_type(const std::string& name);

}  // namespace alight::channels

namespace alight {

/// A --remap argument that cannot be used; what() names the argument and what is wrong.
class RemapError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Channel renames of one process: FROM (one of channels::kAll) → TO (the name used on LCM).
class ChannelRemap {
 public:
  /// The name to use on LCM for `channel`: its new name when remapped, else itself.
  std::string operator()(const std::string& channel) const {
    const auto it = to_.find(channel);
    return it == to_.end() ? channel : it->second;
  }
  bool empty() const { return to_.empty(); }
  const std::map<std::string, std::string>& map() const { return to_; }

 private:
  friend ChannelRemap parse_remaps(const std::vector<std::string>& args);
  std::map<std::string, std::string> to_;
};

/// Parses --remap arguments, each FROM=TO. Throws RemapError for a form other than FROM=TO, a
/// FROM that is not one of channels::kAll (the message lists them), a TO that is not a usable
/// LCM channel name (letters, digits, '_', '-', '/'; at most 63 characters: LCM subscribes by
/// regular expression and limits names to 63), a FROM given twice with different names, or two
/// channels ending up on one name (also a channel renamed onto another's unchanged name).
ChannelRemap parse_remaps(const std::vector<std::string>& args);

}  // namespace alight

#pragma once
// The LCM channels alight-mavlink reads and writes (docs/ARCHITECTURE.md "Channels").

namespace alight::mavlink::channel {
inline constexpr const char* kAttitudeCmd = "ATTITUDE_CMD";          // attitude_cmd_t, in
inline constexpr const char* kPositionSetpoint = "POSITION_SETPOINT";  // position_setpoint_t, in
inline constexpr const char* kMocapPose = "MOCAP_POSE";              // pose_t, in
inline constexpr const char* kImu = "IMU";                           // imu_t, out
inline constexpr const char* kAutopilotPose = "AUTOPILOT_POSE";      // pose_t, out
inline constexpr const char* kAutopilotStatus = "AUTOPILOT_STATUS";  // autopilot_status_t, out
}  // namespace alight::mavlink::channel

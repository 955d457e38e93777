#pragma once
// The MAVLink side of alight-mavlink (issue 16): alight's setpoints to a PX4 or ArduPilot
// autopilot, its motion capture to the autopilot's estimator, and the autopilot's IMU, attitude,
// mode, arming and link state back. Pure: bytes, messages and both clocks go in through
// update(), bytes to write and samples to publish come out; the node owns the serial port or
// socket, LCM and the clocks.
//
// What it does, and why:
//  - Link: the autopilot is the first HEARTBEAT of target_compid (from target_sysid, when set)
//    with a real MAV_AUTOPILOT; without one for heartbeat_timeout_s the link is down. Frames from
//    other systems or components are counted and ignored. The bridge sends its own HEARTBEAT at
//    1 Hz (an onboard controller) and answers the autopilot's TIMESYNC requests with its wall
//    clock, which PX4 uses to move ATT_POS_MOCAP / ODOMETRY stamps onto its own clock.
//  - Setpoints: the newest ATTITUDE_CMD (control: attitude) or POSITION_SETPOINT (position) is
//    sent at stream_rate_hz while it is younger than setpoint_timeout_s, so a slow or bursty
//    stack still gives PX4's offboard mode its > 2 Hz; when alight goes silent the stream stops
//    and the autopilot's own offboard-loss failsafe (PX4 COM_OF_LOSS_T / COM_OBL_RC_ACT,
//    ArduPilot GUID_TIMEOUT) takes over. Attitude: roll and pitch as given, the heading as the
//    autopilot's heading plus yaw rate x yaw_lead_s (no integrator to wind up when the vehicle
//    lags; the yaw rate also goes as body_yaw_rate), thrust normalised as
//    thrust_N / hover_thrust_N x hover_thrust.
//  - Engaging (engage: auto): once the stack arms and setpoints have streamed for
//    offboard_warmup_s, DO_SET_MODE to OFFBOARD (PX4) or GUIDED_NOGPS / GUIDED (ArduPilot), then
//    ARM. Each COMMAND_LONG waits for its COMMAND_ACK, is resent (confirmation + 1) after
//    command_timeout_s up to command_retries times, and after a refusal or no answer the bridge
//    waits command_backoff_s. After an accepted command it waits for the next HEARTBEAT (which
//    shows the result) before deciding again. It engages from the ground only: an autopilot armed
//    in another mode (the pilot's switch, its own failsafe, also one entered while the link was
//    down) is left alone until it has been disarmed: the pilot's override wins. A KILL
//    (POSITION_SETPOINT motors KILL) is a forced disarm at once; the stack's motors-off in the
//    offboard mode (the outer loop's land detector said down) is a normal disarm, which the
//    autopilot refuses in the air.
//  - Telemetry: HIGHRES_IMU becomes IMU (FRD -> FLU), ATTITUDE_QUATERNION with
//    LOCAL_POSITION_NED the autopilot's pose (NED -> ENU). time_usec in the Unix epoch (> 2001)
//    is kept; boot time is moved onto the wall clock by the smallest receipt delay seen (which
//    tracks 100 ppm of drift). A boot time that jumps back is a reboot: the mapping, the
//    requested message rates and the engage state start again. Non-finite or absurd values are
//    refused and counted.
//
// All bad input is counted and survivable: the parser resynchronises after noise, unknown or
// corrupt frames; the bridge never asserts on anything that came over the link.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/geometry.hpp"
#include "common/pose_buffer.hpp"
#include "mavlink/autopilot_modes.hpp"
#include "mavlink/bridge_params.hpp"
#include "mavlink/frame.hpp"
#include "mavlink/messages.hpp"
#include "mavlink/parser.hpp"

namespace alight::mavlink {

/// Both of the node's clocks: steady for every interval and timeout, wall for stamps.
struct BridgeClock {
  int64_t steady_us = 0;  ///< monotonic [us]
  int64_t wall_us = 0;    ///< Unix time [us]
};

/// ATTITUDE_CMD (attitude_cmd_t) in the bridge's terms: alight's ENU world, FLU body.
struct AttitudeTarget {
  int64_t utime = 0;
  double roll_rad = 0, pitch_rad = 0;  ///< Z-Y-X Euler of the desired attitude
  double yaw_rate_radps = 0;           ///< about world z (up)
  double thrust_N = 0;                 ///< collective thrust
  bool armed = false;
};

enum class Motors { kOff, kOn, kKill };

/// POSITION_SETPOINT (position_setpoint_t): world ENU.
struct PositionTarget {
  int64_t utime = 0;
  Vector3d p_W = Vector3d::Zero();
  Vector3d v_W = Vector3d::Zero();
  double yaw_rad = 0;  ///< heading from east, counter-clockwise
  Motors motors = Motors::kOff;
};

struct BridgeInput {
  std::span<const uint8_t> link_bytes;     ///< read from the autopilot's link
  std::optional<AttitudeTarget> attitude;  ///< a new ATTITUDE_CMD
  std::optional<PositionTarget> position;  ///< a new POSITION_SETPOINT
  std::optional<PoseSample> mocap;         ///< a new MOCAP_POSE
  bool link_reopened = false;              ///< the node reopened the device / socket
};

/// One IMU sample from the autopilot, in alight's body frame.
struct ImuOut {
  int64_t utime = 0;  ///< on the wall clock
  Vector3d accel_B = Vector3d::Zero();
  Vector3d gyro_B = Vector3d::Zero();
};

struct BridgeEvent {
  bool warning = false;
  std::string text;
};

struct BridgeOutput {
  std::vector<uint8_t> link_bytes;         ///< write these to the autopilot
  std::vector<ImuOut> imu;                 ///< publish as IMU
  std::vector<PoseSample> autopilot_pose;  ///< publish as AUTOPILOT_POSE
  std::vector<BridgeEvent> events;         ///< log them
};

/// What the bridge asks of the autopilot, or that it has stopped asking.
enum class EngageState {
  kNoLink,     ///< no autopilot heard
  kIdle,       ///< the stack does not want the motors on
  kStreaming,  ///< streaming, not yet long enough to ask for the offboard mode
  kModeWait,   ///< asking for the offboard mode
  kArmWait,    ///< in the offboard mode, asking to arm
  kFlying,     ///< armed in the offboard mode
  kOverride,   ///< armed, but the autopilot left the offboard mode: hands off until disarmed
  kOperator,   ///< engage: operator; the pilot decides mode and arming
};
const char* engage_state_name(EngageState s);

struct BridgeStats {
  uint64_t heartbeats = 0;
  uint64_t link_losses = 0;
  uint64_t reboots = 0;
  uint64_t foreign_frames = 0;   ///< from other systems / components, ignored
  uint64_t rejected_values = 0;  ///< telemetry with non-finite or absurd values
  uint64_t rejected_stamps = 0;  ///< telemetry stamped backwards or implausibly
  uint64_t setpoints_sent = 0;
  uint64_t setpoints_not_sent = 0;  ///< due, but no heading known yet (attitude)
  uint64_t mocap_sent = 0;
  uint64_t imu_out = 0;
  uint64_t commands_sent = 0;    ///< COMMAND_LONG frames, resends included
  uint64_t commands_failed = 0;  ///< refused, or never answered
  uint64_t acks_unexpected = 0;  ///< COMMAND_ACK for nothing pending
  uint64_t frames_sent = 0;
};

/// AUTOPILOT_STATUS's content.
struct AutopilotStatus {
  bool link_up = false;
  double heartbeat_age_s = -1;  ///< -1: never heard
  Flavour flavour = Flavour::kPx4;
  ControlMode control = ControlMode::kAttitude;
  uint8_t sysid = 0;
  uint8_t autopilot_type = 0;  ///< MAV_AUTOPILOT of the heartbeat
  uint32_t custom_mode = 0;
  uint8_t base_mode = 0;
  uint8_t system_status = 0;
  std::string mode;  ///< mode_name()
  bool armed = false;
  bool offboard = false;  ///< in the mode alight flies in
  EngageState engage = EngageState::kNoLink;
  bool streaming = false;
  double setpoint_age_s = -1;  ///< of the stack's newest setpoint; -1: none
  std::string last_command;    ///< "offboard", "arm", "disarm", "force disarm", "interval"
  int last_result = -2;        ///< MAV_RESULT; -1: no answer; -2: none yet
  std::string last_statustext;
  double battery_V = -1;  ///< -1: not reported
  BridgeStats stats;
  ParserStats parser;
};

class Bridge {
 public:
  /// `hover_thrust_N`: the weight the normalised hover_thrust holds up (mass x g of the vehicle
  /// file's outer loop), for attitude control.
  Bridge(const BridgeParams& params, double hover_thrust_N);

  BridgeOutput update(const BridgeInput& in, const BridgeClock& now);
  AutopilotStatus status(const BridgeClock& now) const;

  const ParserStats& parser_stats() const { return parser_.stats(); }
  const BridgeStats& stats() const { return stats_; }
  bool link_up() const { return link_up_; }
  EngageState engage_state() const { return engage_; }

 private:
  struct Pending {
    CommandLong cmd;
    std::string name;
    int attempts = 0;
    int64_t sent_steady_us = 0;
  };
  void handle_frame(const Frame& f, const BridgeClock& now, BridgeOutput& out);
  void on_heartbeat(const Frame& f, const Heartbeat& m, const BridgeClock& now, BridgeOutput& out);
  void on_ack(const CommandAck& m, const BridgeClock& now, BridgeOutput& out);
  void on_boot_time(uint64_t boot_us, BridgeOutput& out);
  std::optional<int64_t> wall_stamp(uint64_t autopilot_us, const BridgeClock& now);
  void reset_autopilot_state();
  void check_link(const BridgeClock& now, BridgeOutput& out);
  void stream(const BridgeClock& now, BridgeOutput& out);
  void decide_commands(const BridgeClock& now, BridgeOutput& out);
  void service_pending(const BridgeClock& now, BridgeOutput& out);
  void send_command(uint16_t command, const std::string& name, float p1, float p2, float p3,
                    const BridgeClock& now, BridgeOutput& out);
  void command_finished(bool ok, int result, const BridgeClock& now, BridgeOutput& out);
  void forward_mocap(const PoseSample& pose, const BridgeClock& now, BridgeOutput& out);
  std::optional<double> heading_enu(const BridgeClock& now) const;
  bool setpoint_fresh(const BridgeClock& now) const;
  template <class M>
  void send(const M& m, const BridgeClock& now, BridgeOutput& out);

  BridgeParams params_;
  Flavour flavour_;
  ControlMode control_;
  double hover_thrust_N_;
  Parser parser_;
  Sender sender_;
  BridgeStats stats_;

  // The autopilot.
  std::optional<uint8_t> sysid_;
  std::optional<Heartbeat> heartbeat_;
  int64_t last_heartbeat_steady_ = 0;
  bool link_up_ = false;
  std::optional<uint64_t> last_boot_us_;
  std::optional<int64_t> boot_offset_us_;  // wall - boot time, smallest seen
  int64_t boot_offset_steady_us_ = 0;
  int64_t last_imu_utime_ = 0;
  std::optional<Quaterniond> q_NED_FRD_;
  Vector3d omega_FRD_ = Vector3d::Zero();
  int64_t attitude_steady_us_ = 0;
  int64_t attitude_utime_ = 0;
  std::optional<LocalPositionNed> local_position_;
  int64_t local_position_steady_us_ = 0;
  std::string last_statustext_;
  double battery_V_ = -1;

  // The stack.
  std::optional<AttitudeTarget> attitude_;
  int64_t attitude_rx_steady_us_ = 0;
  std::optional<PositionTarget> position_;
  int64_t position_rx_steady_us_ = 0;
  std::optional<PoseSample> mocap_;
  int64_t mocap_rx_steady_us_ = 0;
  int64_t mocap_sent_steady_us_ = INT64_MIN / 2;

  // Streaming and commands.
  int64_t next_stream_us_ = 0;
  std::optional<int64_t> streaming_since_us_;
  int64_t next_heartbeat_us_ = 0;
  std::optional<Pending> pending_;
  int64_t backoff_until_us_ = 0;
  bool await_heartbeat_ = false;
  int64_t settle_until_us_ = 0;
  std::vector<std::pair<uint32_t, double>> intervals_to_ask_;  // message id, rate
  bool was_armed_in_fly_mode_ = false;
  bool override_ = false;
  EngageState engage_ = EngageState::kNoLink;
  std::string last_command_;
  int last_result_ = -2;
};

}  // namespace alight::mavlink

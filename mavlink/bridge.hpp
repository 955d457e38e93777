#pragma once
// The MAVLink side of alight-mavlink (what a real ArduCopter and PX4 need):
// alight's setpoints to a PX4 or ArduPilot autopilot, its motion capture to the autopilot's
// estimator, and the autopilot's IMU, attitude, mode, arming and link state back. Pure: bytes,
// messages and both clocks go in through update(), bytes to write and samples to publish come
// out; the node owns the serial port or socket, LCM, the clocks and the operator's key.
//
// What it does, and why:
//  - Link: the autopilot is the first HEARTBEAT of target_compid (from target_sysid, when set)
//    with a real MAV_AUTOPILOT; without one for heartbeat_timeout_s the link is down. Frames from
//    other systems or components are counted and ignored. The bridge sends its own HEARTBEAT at
//    1 Hz (an onboard controller; ArduPilot's GCS failsafe watches it when MAV_GCS_SYSID is the
//    bridge's own_sysid) and answers the autopilot's TIMESYNC requests with its wall clock. With
//    a signing key every frame out is signed and only correctly signed frames are taken in.
//  - Setpoints: the newest ATTITUDE_CMD (control: attitude) or POSITION_SETPOINT (position) is
//    sent at stream_rate_hz while it is younger than setpoint_timeout_s. Attitude: roll and pitch
//    as given, the heading as the autopilot's heading plus yaw rate x yaw_lead_s, thrust
//    normalised as thrust_N / hover_thrust_N x hover_thrust. The body rates are flagged the way
//    each autopilot reads them: PX4 takes the yaw rate alone as a feed-forward (roll and pitch
//    rates ignored), ArduCopter takes all three body rates or none and drops anything else, so
//    it gets none. Position targets carry position, velocity and, only to firmware whose version
//    (AUTOPILOT_VERSION, asked at link-up) is known to take it, the feed-forward acceleration:
//    an ArduCopter older than 4.1 drops a target that has one (autopilot_firmware.hpp).
//  - Engaging (engage: auto): once the stack arms and setpoints have streamed for
//    offboard_warmup_s, DO_SET_MODE to OFFBOARD (PX4) or GUIDED_NOGPS / GUIDED (ArduPilot), then
//    ARM. Each COMMAND_LONG waits for its COMMAND_ACK, is resent (confirmation + 1) after
//    command_timeout_s up to command_retries times, and after a refusal or no answer the bridge
//    waits command_backoff_s. After an accepted command it waits for the next HEARTBEAT before
//    deciding again. ArduCopter's GUIDED leaves the ground only through MAV_CMD_NAV_TAKEOFF: with
//    position setpoints the bridge sends it once armed on the ground (to the setpoint's height)
//    and holds its setpoints until the autopilot reports the vehicle in the air.
//  - Never taking a vehicle back: an autopilot armed in another mode (the pilot's switch, its own
//    failsafe) is left alone until it has been disarmed. A bridge that comes up (a restart, the
//    link back) to find the vehicle armed in the offboard mode streams nothing and asks for LAND:
//    it did not put the vehicle there. After a flight's disarm it arms again only once the stack
//    has said motors off since, and never within rearm_cooldown_s of the disarm.
//  - Stopping: an authorised KILL (the operator's signed CMD_KILL, checked by the node: position
//    motors KILL or attitude armed = false with kill_authorised) is a forced disarm at once. Any
//    other motors-off in the offboard mode is a plain disarm, which the autopilot refuses in the
//    air; still refused while the autopilot reports the vehicle in the air after
//    kInAirDisarmWaitUs, it becomes LAND. When the stack's setpoints stop while the bridge flies
//    the vehicle, the stream stops after setpoint_timeout_s and silence_action land asks for LAND
//    after silence_land_s (ArduCopter has no offboard-loss failsafe of its own: GUID_TIMEOUT only
//    levels an attitude target and holds a position target forever); the bridge's own death is
//    the autopilot's to notice (PX4 COM_OF_LOSS_T / COM_OBL_RC_ACT, ArduPilot FS_GCS_ENABLE on
//    the bridge's heartbeat).
//  - Telemetry: HIGHRES_IMU (or SCALED_IMU where the autopilot has no HIGHRES_IMU) becomes IMU
//    (FRD -> FLU); ATTITUDE_QUATERNION with LOCAL_POSITION_NED the autopilot's pose (NED -> ENU),
//    attitude alone while the autopilot has no local position; EXTENDED_SYS_STATE its landed
//    state. time_usec in the Unix epoch (> 2001) is kept; boot time is moved onto the wall clock
//    by the smallest recent receipt delay (a SITL's clock may run 10% slow). A boot time that
//    jumps back is a reboot: the mapping, the
//    requested message rates and the engage state start again. Non-finite or absurd values are
//    refused and counted. Without GPS the autopilot's local frame needs a geodetic origin: with
//    set_ekf_origin the bridge sends SET_GPS_GLOBAL_ORIGIN until GPS_GLOBAL_ORIGIN comes back.
//  - Frames: position setpoints go out in the autopilot's local frame, which need not be motion
//    capture's (ArduCopter SITL's EKF3 read 0.2 m above it): with align_frames the bridge
//    measures the offset (LOCAL_POSITION_NED minus motion capture, at rest on the ground) and
//    adds it. In the air it keeps following it slowly (the estimate drifts from motion capture:
//    PX4 SIH's EKF2 by 2 to 5 cm in height after take-off), both poses taken at the same instant,
//    within kFrameOffsetAirBoundM of the offset measured at rest.
//  - Parameters: at link-up the bridge reads the autopilot parameters its behaviour relies on
//    (autopilot_params.hpp) and reports each one that is missing or set otherwise.
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
#include "mavlink/autopilot_firmware.hpp"
#include "mavlink/autopilot_modes.hpp"
#include "mavlink/autopilot_params.hpp"
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
  /// armed = false carries the operator's signed CMD_KILL, verified by the node: a forced disarm.
  bool kill_authorised = false;
};

enum class Motors { kOff, kOn, kKill };

/// POSITION_SETPOINT (position_setpoint_t): world ENU.
struct PositionTarget {
  int64_t utime = 0;
  Vector3d p_W = Vector3d::Zero();
  Vector3d v_W = Vector3d::Zero();
  /// Feed-forward acceleration [m/s^2]: sent only to firmware known to take it
  /// (takes_position_target_accel), else left out.
  Vector3d a_W = Vector3d::Zero();
  double yaw_rad = 0;  ///< heading from east, counter-clockwise
  /// Feed-forward turn of the heading [rad/s] (a turning platform's), counter-clockwise. PX4
  /// takes it as the yaw controller's feed-forward; ArduCopter since its yaw modes' rework
  /// (ArduCopter/mode_guided.cpp, feae762e64, 2021-07) as the rate its yaw target advances at,
  /// and before it keeps the yaw alone (ModeGuided::set_yaw_state).
  double yaw_rate_radps = 0;
  Motors motors = Motors::kOff;
  /// motors KILL carries the operator's signed CMD_KILL, verified by the node: a forced disarm.
  /// A KILL without it is a plain motors-off.
  bool kill_authorised = false;
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

/// The autopilot's own estimate (AUTOPILOT_POSE).
struct AutopilotPose {
  PoseSample pose;
  /// false: the autopilot sends no local position (no origin, no aiding source yet); only the
  /// attitude and the body rates are its.
  bool position_known = true;
};

struct BridgeOutput {
  std::vector<uint8_t> link_bytes;            ///< write these to the autopilot
  std::vector<ImuOut> imu;                    ///< publish as IMU
  std::vector<AutopilotPose> autopilot_pose;  ///< publish as AUTOPILOT_POSE
  std::vector<BridgeEvent> events;            ///< log them
};

/// What the bridge asks of the autopilot, or that it has stopped asking.
enum class EngageState {
  kNoLink,      ///< no autopilot heard
  kIdle,        ///< the stack does not want the motors on
  kStreaming,   ///< streaming, not yet long enough to ask for the offboard mode
  kModeWait,    ///< asking for the offboard mode
  kArmWait,     ///< in the offboard mode, asking to arm
  kFlying,      ///< armed in the offboard mode
  kTakeoff,     ///< ArduPilot GUIDED: armed on the ground, NAV_TAKEOFF asked, setpoints held
  kOverride,    ///< armed, but the autopilot left the offboard mode: hands off until disarmed
  kOperator,    ///< engage: operator; the pilot decides mode and arming
  kNoTakeover,  ///< found armed in the offboard mode at link-up: no setpoints, LAND asked
  kLanding,     ///< the bridge asked for LAND (stack silent, or motors off in the air)
  kCooldown,    ///< disarmed after a flight: waiting for the cool-down and the stack's motors off
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
  uint64_t lands_requested = 0;   ///< DO_SET_MODE LAND sent (first attempts)
  uint64_t kills_refused = 0;     ///< KILLs without a valid authority, flown as motors-off
  uint64_t takeover_refused = 0;  ///< link-ups that found the vehicle armed in the offboard mode
  uint64_t origin_sent = 0;       ///< SET_GPS_GLOBAL_ORIGIN frames
  uint64_t param_problems = 0;    ///< autopilot parameters missing or set otherwise
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
  /// MAV_LANDED_STATE from EXTENDED_SYS_STATE (ArduPilot without it: from the heartbeat); 0
  /// (undefined): not known.
  uint8_t landed_state = 0;
  std::string imu_source;     ///< "HIGHRES_IMU", "SCALED_IMU" or "" (none yet)
  bool origin_known = false;  ///< GPS_GLOBAL_ORIGIN received
  /// The autopilot's local frame minus motion capture's (NED) [m], when measured.
  std::optional<Vector3d> frame_offset_NED;
  /// The autopilot could arm: ArduPilot's pre-arm checks pass (SYS_STATUS); PX4 has had a
  /// local position for 2 s (its own checks are per mode, and fail without GPS).
  bool prearm_ok = false;
  /// The firmware's version from AUTOPILOT_VERSION ("4.5.7", "1.15.0-rc"); "" not known yet.
  std::string firmware;
  /// Position targets carry the stack's acceleration (the firmware takes it).
  bool accel_feedforward = false;
  BridgeStats stats;
  ParserStats parser;
};

class Bridge {
 public:
  /// `hover_thrust_N`: the weight the normalised hover_thrust holds up (mass x g of the vehicle
  /// file's outer loop), for attitude control. `signing`: the link's MAVLink 2 signing key and
  /// link id (the node reads signing_key_file).
  Bridge(const BridgeParams& params, double hover_thrust_N,
         std::optional<SigningConfig> signing = std::nullopt);

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
  struct ParamRead {
    ParamExpectation expect;
    int attempts = 0;
    int64_t sent_steady_us = 0;
  };
  void handle_frame(const Frame& f, const BridgeClock& now, BridgeOutput& out);
  void on_heartbeat(const Frame& f, const Heartbeat& m, const BridgeClock& now, BridgeOutput& out);
  void on_ack(const CommandAck& m, const BridgeClock& now, BridgeOutput& out);
  void on_boot_time(uint64_t boot_us, BridgeOutput& out);
  void on_imu(int64_t utime, const Vector3d& accel_FRD, const Vector3d& gyro_FRD,
              BridgeOutput& out);
  void on_param(const ParamValue& m, BridgeOutput& out);
  void on_version(const AutopilotVersion& m, BridgeOutput& out);
  void update_frame_offset(const BridgeClock& now, BridgeOutput& out);
  void follow_frame_offset(const Vector3d& sample, double tau_s, const BridgeClock& now,
                           BridgeOutput& out);
  void set_prearm(bool ok, BridgeOutput& out);
  std::optional<int64_t> wall_stamp(uint64_t autopilot_us, const BridgeClock& now);
  void reset_autopilot_state();
  void check_link(const BridgeClock& now, BridgeOutput& out);
  void stream(const BridgeClock& now, BridgeOutput& out);
  /// The position target to send: the stack's; after its motors-off while the autopilot is
  /// still armed, no higher than the last MOTORS_ON one and pressed down (kTouchdownPushMps).
  PositionTarget position_to_stream() const;
  bool hold_setpoints() const;
  void decide_commands(const BridgeClock& now, BridgeOutput& out);
  bool decide_engage(const BridgeClock& now, BridgeOutput& out);
  bool decide_housekeeping(const BridgeClock& now, BridgeOutput& out);
  void service_pending(const BridgeClock& now, BridgeOutput& out);
  void service_params(const BridgeClock& now, BridgeOutput& out);
  void service_origin(const BridgeClock& now, BridgeOutput& out);
  void send_command(uint16_t command, const std::string& name, float p1, float p2, float p3,
                    const BridgeClock& now, BridgeOutput& out, float p7 = 0);
  void request_land(const std::string& why, const BridgeClock& now, BridgeOutput& out);
  void command_finished(bool ok, int result, const BridgeClock& now, BridgeOutput& out);
  void forward_mocap(const PoseSample& pose, const BridgeClock& now, BridgeOutput& out);
  std::optional<double> heading_enu(const BridgeClock& now) const;
  std::optional<double> height_up(const BridgeClock& now) const;
  bool setpoint_fresh(const BridgeClock& now) const;
  bool stack_wants_armed(const BridgeClock& now) const;
  bool authorised_kill(const BridgeClock& now) const;
  /// MAV_LANDED_STATE as known now (kUndefined when not).
  uint8_t landed_state(const BridgeClock& now) const;
  bool in_air(const BridgeClock& now) const;
  /// Position targets carry the acceleration: the firmware is known to take it.
  bool accel_feedforward() const;
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
  std::optional<int64_t> local_position_since_us_;
  std::optional<ExtendedSysState> ext_state_;
  std::optional<Vector3d> frame_offset_NED_;   // autopilot's local position - motion capture's
  std::optional<Vector3d> ground_offset_NED_;  // ... as last measured at rest on the ground
  Vector3d reported_offset_NED_ = Vector3d::Zero();
  int64_t frame_offset_steady_us_ = 0;
  int64_t ext_state_steady_us_ = 0;
  std::string last_statustext_;
  double battery_V_ = -1;
  std::string imu_source_;
  bool origin_known_ = false;
  bool prearm_ok_ = false;
  std::optional<FirmwareVersion> firmware_;

  // The stack.
  std::optional<AttitudeTarget> attitude_;
  int64_t attitude_rx_steady_us_ = 0;
  std::optional<PositionTarget> position_;
  int64_t position_rx_steady_us_ = 0;
  std::optional<double> last_on_z_m_;  ///< the height of the stack's newest MOTORS_ON target [m]
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
  std::optional<int64_t> highres_accepted_us_;                 // HIGHRES_IMU's interval accepted at
  bool scaled_imu_asked_ = false;
  std::vector<ParamRead> params_to_read_;
  int64_t next_origin_us_ = 0;
  int origin_attempts_ = 0;
  int version_asks_ = 0;  // AUTOPILOT_VERSION requests sent (REQUEST_MESSAGE, then the older one)
  int64_t next_version_ask_us_ = 0;

  // Engage state.
  bool was_armed_ = false;
  bool was_armed_in_fly_mode_ = false;
  bool override_ = false;
  bool refuse_takeover_ = false;  // found armed in the fly mode at link-up
  bool landing_asked_ = false;    // LAND accepted; until the vehicle leaves the fly mode
  bool flew_ = false;             // in the air since arming (or not known not to be)
  bool need_motors_off_ = false;  // after a flight's disarm: until the stack says motors off
  std::optional<int64_t> disarmed_at_us_;
  bool engaged_stream_ = false;  // streamed fresh setpoints to the armed vehicle in fly mode
  std::optional<int64_t> off_in_air_since_us_;  // stack's motors-off while the vehicle flies
  bool takeoff_accepted_ = false;  // ArduPilot GUIDED: NAV_TAKEOFF accepted, not yet in the air
  int64_t takeoff_accepted_us_ = 0;
  double takeoff_start_up_m_ = 0;
  double takeoff_alt_m_ = 0;
  bool takeoff_done_ = false;  // since arming
  EngageState engage_ = EngageState::kNoLink;
  std::string last_command_;
  int last_result_ = -2;
};

}  // namespace alight::mavlink

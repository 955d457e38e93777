#pragma once
// Parameters of alight-mavlink: the `mavlink:` section of an autopilot file
// (config/autopilot/*.yaml). Which autopilot over which link, how alight flies it (attitude or
// position setpoints), how fast setpoints stream and when they stop (so that the autopilot's own
// failsafe takes over), who engages the offboard mode, what goes to the autopilot's estimator and
// what telemetry comes back.

#include <string>
#include <vector>

#include "common/param_schema.hpp"
#include "mavlink/autopilot_modes.hpp"

namespace alight::mavlink {

struct BridgeParams {
  std::string autopilot = "px4";                  ///< "px4" or "ardupilot"
  std::string link = "udp-listen:0.0.0.0:14540";  ///< link_address.hpp
  int target_sysid = 0;   ///< autopilot's system id (0: the first autopilot heard)
  int target_compid = 1;  ///< autopilot's component id (MAV_COMP_ID_AUTOPILOT1)
  int own_sysid = 1;      ///< ours: the vehicle's system id (a companion computer shares it)
  int own_compid = 191;   ///< MAV_COMP_ID_ONBOARD_COMPUTER
  double heartbeat_timeout_s = 3.0;  ///< no autopilot HEARTBEAT this long: link down [s]
  double reopen_delay_s = 0.5;       ///< wait before reopening a failed device / socket [s]

  std::string control = "attitude";  ///< "attitude" (SET_ATTITUDE_TARGET) or "position"
  /// "auto": ask for the offboard mode and arm when the stack arms (ATTITUDE_CMD.armed or
  /// POSITION_SETPOINT.motors); "operator": the pilot switches mode and arms (RC / QGC), the
  /// bridge only streams setpoints and disarms on KILL or after touch-down in the offboard mode.
  std::string engage = "auto";
  double stream_rate_hz = 50.0;     ///< setpoints to the autopilot (PX4 needs > 2 Hz) [Hz]
  double setpoint_timeout_s = 0.5;  ///< stack's setpoint older: stop streaming [s]
  double offboard_warmup_s = 1.0;   ///< stream this long before asking for OFFBOARD [s]
  double command_timeout_s = 0.5;   ///< COMMAND_LONG unanswered this long: sent again [s]
  int command_retries = 4;          ///< resends before a command counts as failed
  double command_backoff_s = 1.0;   ///< after a refused / failed command, wait this long [s]
  /// The stack's setpoints stop while the bridge flies the vehicle: "land" asks for the
  /// autopilot's LAND mode at once, "autopilot" leaves it to the autopilot's own failsafe.
  std::string silence_action = "land";
  /// ... after the setpoints have been silent this long (the stream stops at setpoint_timeout_s).
  double silence_land_s = 1.5;
  double rearm_cooldown_s = 5.0;  ///< no ARM this long after a disarm [s]

  double hover_thrust = 0.5;  ///< normalised thrust (0..1) that hovers (PX4 MPC_THR_HOVER) [-]
  double yaw_lead_s = 0.35;   ///< attitude: heading setpoint = heading + yaw rate x this [s]

  std::string mocap_message =
      "att_pos_mocap";          ///< MOCAP_POSE as "att_pos_mocap", "odometry", "none"
  double mocap_rate_hz = 50.0;  ///< at most this many poses forwarded [Hz]

  double imu_rate_hz = 200.0;         ///< HIGHRES_IMU asked of the autopilot (0: leave it) [Hz]
  double attitude_rate_hz = 100.0;    ///< ATTITUDE_QUATERNION asked (0: leave it) [Hz]
  double position_rate_hz = 30.0;     ///< LOCAL_POSITION_NED asked (0: leave it) [Hz]
  double landed_state_rate_hz = 4.0;  ///< EXTENDED_SYS_STATE asked (0: leave it) [Hz]
  double sys_status_rate_hz = 2.0;    ///< SYS_STATUS asked (0: leave it) [Hz]
  double status_rate_hz = 5.0;        ///< AUTOPILOT_STATUS published [Hz]

  /// Without GPS: SET_GPS_GLOBAL_ORIGIN (latitude [deg], longitude [deg], altitude [m above mean
  /// sea level]) until the autopilot reports an origin.
  bool set_ekf_origin = false;
  std::vector<double> ekf_origin = {0.0, 0.0, 0.0};
  /// MAVLink 2 signing on the link (empty: none): 64 hex digits, or a passphrase whose SHA-256
  /// is the key (as Mission Planner and QGroundControl derive it).
  std::string signing_key_file;
  int signing_link_id = 1;   ///< our link id in signed frames
  bool check_params = true;  ///< read and report the autopilot parameters alight relies on
  /// Position control: measure the autopilot's local frame against motion capture and send
  /// setpoints in it.
  bool align_frames = true;

  static const ParamSchema<BridgeParams>& schema();
  void validate() const;  ///< throws ParamError naming the field and its value

  Flavour flavour() const { return autopilot == "ardupilot" ? Flavour::kArdupilot : Flavour::kPx4; }
  ControlMode control_mode() const {
    return control == "position" ? ControlMode::kPosition : ControlMode::kAttitude;
  }
  bool auto_engage() const { return engage == "auto"; }
  /// Bytes per second the configured streams put on the link (setpoints, mocap, heartbeat).
  double uplink_bytes_per_s() const;
};

/// Reads the `mavlink:` section of a file whose only top-level key it is.
BridgeParams load_bridge_params(const std::string& file);
BridgeParams load_bridge_params(const ParamNode& root);

}  // namespace alight::mavlink

#include "mavlink/bridge_params.hpp"

#include <cmath>

#include "mavlink/frame.hpp"
#include "mavlink/link_address.hpp"

namespace alight::mavlink {

double BridgeParams::uplink_bytes_per_s() const {
  // Frame overhead: 10 header + 2 checksum bytes (unsigned); payloads at their full length.
  constexpr double kOverhead = kHeaderLengthV2 + kChecksumLength;
  const double setpoint = control_mode() == ControlMode::kAttitude
                              ? SetAttitudeTarget::kBaseLength
                              : SetPositionTargetLocalNed::kBaseLength;
  double mocap = 0;
  if (mocap_message == "att_pos_mocap") mocap = AttPosMocap::kMaxLength;
  if (mocap_message == "odometry") mocap = Odometry::kMaxLength;
  return stream_rate_hz * (setpoint + kOverhead) + mocap_rate_hz * (mocap + kOverhead) +
         1.0 * (Heartbeat::kMaxLength + kOverhead);
}

const ParamSchema<BridgeParams>& BridgeParams::schema() {
  using P = BridgeParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("autopilot", &P::autopilot, Range::any(), "", "the autopilot's firmware")
        .one_of({"px4", "ardupilot"});
    s.add("link", &P::link, Range::any(), "",
          "serial:DEVICE:BAUD (57600..921600), udp-listen:HOST:PORT (reply to the sender) or "
          "udp:HOST:PORT[:LOCAL_PORT]")
        .check_with([](const P& p) {
          std::string why;
          return parse_link_address(p.link, &why) ? std::string() : why;
        });
    s.add("target_sysid", &P::target_sysid, Range::closed(0, 255), "",
          "the autopilot's MAVLink system id (0: the first autopilot heard)");
    s.add("target_compid", &P::target_compid, Range::closed(1, 255), "",
          "the autopilot's component id (1: MAV_COMP_ID_AUTOPILOT1)");
    s.add("own_sysid", &P::own_sysid, Range::closed(1, 255), "",
          "alight's system id (a companion computer shares the vehicle's)");
    s.add("own_compid", &P::own_compid, Range::closed(1, 255), "",
          "alight's component id (191: MAV_COMP_ID_ONBOARD_COMPUTER)");
    s.add("heartbeat_timeout_s", &P::heartbeat_timeout_s, Range::closed(0.5, 30), "s",
          "no HEARTBEAT from the autopilot this long: the link is down (it sends 1 Hz)");
    s.add("reopen_delay_s", &P::reopen_delay_s, Range::closed(0.05, 30), "s",
          "wait before reopening a serial device or socket that failed");
    s.add("control", &P::control, Range::any(), "",
          "attitude: the outer loop's ATTITUDE_CMD as SET_ATTITUDE_TARGET; position: autonomy's "
          "POSITION_SETPOINT as SET_POSITION_TARGET_LOCAL_NED to the autopilot's controller")
        .one_of({"attitude", "position"});
    s.add("engage", &P::engage, Range::any(), "",
          "auto: ask for OFFBOARD / GUIDED(_NOGPS) and arm when the stack arms; operator: the "
          "pilot switches the mode and arms, alight only streams (and disarms on KILL)")
        .one_of({"auto", "operator"});
    s.add("stream_rate_hz", &P::stream_rate_hz, Range::closed(5, 200), "Hz",
          "setpoints sent to the autopilot (PX4's offboard mode needs more than 2 Hz)")
        .check_with([](const P& p) {
          // The uplink must fit in a serial link with room to spare (8N1: 10 bits a byte).
          std::string why;
          if (const auto a = parse_link_address(p.link, nullptr);
              a && a->kind == LinkAddress::Kind::kSerial) {
            const double capacity = a->baud / 10.0;
            if (p.uplink_bytes_per_s() > 0.8 * capacity)
              why = "stream_rate_hz and mocap_rate_hz need " +
                    std::to_string(static_cast<int>(p.uplink_bytes_per_s())) +
                    " B/s, more than 80% of the " + std::to_string(a->baud) +
                    " baud link: lower them or raise the baud rate";
          }
          return why;
        });
    s.add("setpoint_timeout_s", &P::setpoint_timeout_s, Range::closed(0.05, 2), "s",
          "the stack's last setpoint older than this: stop streaming, so that the autopilot's "
          "own offboard-loss failsafe takes over")
        .check([](const P& p) { return p.setpoint_timeout_s * p.stream_rate_hz >= 1; },
               "must cover at least one stream period");
    s.add("offboard_warmup_s", &P::offboard_warmup_s, Range::closed(0, 10), "s",
          "stream setpoints this long before asking for the offboard mode (PX4 refuses it "
          "without a stream)");
    s.add("command_timeout_s", &P::command_timeout_s, Range::closed(0.05, 10), "s",
          "a COMMAND_LONG without COMMAND_ACK this long is sent again");
    s.add("command_retries", &P::command_retries, Range::closed(0, 20), "",
          "resends before a command counts as failed");
    s.add("command_backoff_s", &P::command_backoff_s, Range::closed(0, 60), "s",
          "after a refused or failed command, wait this long before asking again");
    s.add("silence_action", &P::silence_action, Range::any(), "",
          "the stack's setpoints stop while alight flies the vehicle: land (ask for the "
          "autopilot's LAND at once; ArduCopter has no offboard-loss failsafe) or autopilot "
          "(leave it to the autopilot's own failsafe, PX4 COM_OBL_RC_ACT)")
        .one_of({"land", "autopilot"});
    s.add("silence_land_s", &P::silence_land_s, Range::closed(0.1, 10), "s",
          "silence_action land: the stack's setpoints silent this long (a process stalled for "
          "0.8 s on a loaded SITL machine) before the bridge asks for LAND")
        .check([](const P& p) { return p.silence_land_s >= p.setpoint_timeout_s; },
               "must be at least setpoint_timeout_s");
    s.add("rearm_cooldown_s", &P::rearm_cooldown_s, Range::closed(0, 600), "s",
          "no ARM this long after the vehicle disarmed (after a flight the stack must also have "
          "said motors off since)");
    s.add("hover_thrust", &P::hover_thrust, Range::open(0, 1), "",
          "attitude: normalised thrust that hovers the vehicle (PX4: MPC_THR_HOVER); ATTITUDE_CMD "
          "thrust_N is scaled by it over the vehicle's weight");
    s.add("yaw_lead_s", &P::yaw_lead_s, Range::closed(0, 5), "s",
          "attitude: the heading sent is the autopilot's heading plus the commanded yaw rate "
          "times this (about 1 / the autopilot's yaw gain, MC_YAW_P)");
    s.add("mocap_message", &P::mocap_message, Range::any(), "",
          "MOCAP_POSE to the autopilot's estimator as ATT_POS_MOCAP, ODOMETRY, or not at all")
        .one_of({"att_pos_mocap", "odometry", "none"});
    s.add("mocap_rate_hz", &P::mocap_rate_hz, Range::closed(1, 250), "Hz",
          "at most this many poses forwarded per second");
    s.add("imu_rate_hz", &P::imu_rate_hz, Range::closed(0, 1000), "Hz",
          "HIGHRES_IMU asked of the autopilot (SET_MESSAGE_INTERVAL; 0: leave its rate)");
    s.add("attitude_rate_hz", &P::attitude_rate_hz, Range::closed(0, 1000), "Hz",
          "ATTITUDE_QUATERNION asked of the autopilot (0: leave its rate)");
    s.add("position_rate_hz", &P::position_rate_hz, Range::closed(0, 1000), "Hz",
          "LOCAL_POSITION_NED asked of the autopilot (0: leave its rate)");
    s.add("landed_state_rate_hz", &P::landed_state_rate_hz, Range::closed(0, 50), "Hz",
          "EXTENDED_SYS_STATE (the autopilot's landed state) asked (0: leave its rate)");
    s.add("sys_status_rate_hz", &P::sys_status_rate_hz, Range::closed(0, 50), "Hz",
          "SYS_STATUS (pre-arm checks, battery) asked (0: leave its rate)");
    s.add("set_ekf_origin", &P::set_ekf_origin, Range::any(), "",
          "without GPS: send SET_GPS_GLOBAL_ORIGIN (ekf_origin) until the autopilot reports an "
          "origin (ArduPilot needs one for GUIDED, take-off and LOCAL_POSITION_NED)");
    s.add("ekf_origin", &P::ekf_origin, Range::any(), "",
          "latitude [deg], longitude [deg], altitude above mean sea level [m] of the local "
          "frame's origin (the motion-capture room's, roughly)")
        .check_with([](const P& p) -> std::string {
          if (p.ekf_origin.size() != 3) return "must be [latitude, longitude, altitude]";
          if (std::abs(p.ekf_origin[0]) > 90 || std::abs(p.ekf_origin[1]) > 180)
            return "latitude must be within 90 deg, longitude within 180 deg";
          if (p.ekf_origin[2] < -500 || p.ekf_origin[2] > 10000)
            return "altitude must be within -500 .. 10000 m";
          if (p.set_ekf_origin && p.ekf_origin[0] == 0 && p.ekf_origin[1] == 0)
            return "set_ekf_origin needs a real origin (ArduPilot refuses 0, 0)";
          return "";
        });
    s.add("signing_key_file", &P::signing_key_file, Range::any(), "",
          "MAVLink 2 signing key (64 hex digits, or a passphrase: SHA-256 of it); empty: the "
          "link is not signed")
        .path();
    s.add("signing_link_id", &P::signing_link_id, Range::closed(0, 255), "",
          "alight's link id in signed frames");
    s.add("check_params", &P::check_params, Range::any(), "",
          "read the autopilot parameters alight relies on at link-up and report those set "
          "otherwise (mavlink/autopilot_params.hpp)");
    s.add("align_frames", &P::align_frames, Range::any(), "",
          "position control: measure the offset of the autopilot's local frame from motion "
          "capture (at rest) and send setpoints in the autopilot's frame");
    s.add("status_rate_hz", &P::status_rate_hz, Range::closed(0.5, 50), "Hz",
          "AUTOPILOT_STATUS published");
    return s;
  }();
  return schema;
}

void BridgeParams::validate() const { schema().validate(*this); }

BridgeParams load_bridge_params(const ParamNode& root) {
  BridgeParams p;
  BridgeParams::schema().read(root.child("mavlink"), p);
  root.finish();
  return p;
}

BridgeParams load_bridge_params(const std::string& file) {
  return load_bridge_params(ParamNode::load_file(file));
}

}  // namespace alight::mavlink

#pragma once
// The simulated vehicle's autopilot as a MAVLink peer, the way PX4's offboard interface behaves:
// alight-sim --mavlink ADDRESS puts it between alight-mavlink and the dynamics, so
// setpoints, mode changes, arming and telemetry cross the link as MAVLink bytes. Pure: bytes,
// the simulated state and the sim time go in; bytes and the command for the dynamics come out.
//
// What it does, as PX4 does (docs.px4.io, "Offboard Mode"; the parameters named are PX4's):
//  - HEARTBEAT at 1 Hz as a PX4 quadrotor: custom_mode (main mode << 16 | sub mode << 24),
//    base_mode with SAFETY_ARMED; it boots in AUTO.LOITER, disarmed.
//  - OFFBOARD is accepted only while setpoints stream (at least offboard_min_rate_hz over the
//    last second); otherwise COMMAND_ACK TEMPORARILY_REJECTED and a STATUSTEXT.
//  - ARM by COMMAND_LONG 400; disarm only on the ground unless forced (param2 21196).
//  - In OFFBOARD and armed: SET_ATTITUDE_TARGET becomes the inner loop's command (roll and pitch
//    of the quaternion, yaw rate = yaw_p x heading error as PX4's attitude controller, which
//    ignores the body rates when an attitude is given; thrust x weight / hover_thrust), and
//    SET_POSITION_TARGET_LOCAL_NED a position target for the autopilot's position controller
//    (the sim node runs one).
//  - Failsafe (COM_OF_LOSS_T, COM_OBL_RC_ACT = Land): no setpoint for offboard_loss_timeout_s in
//    OFFBOARD while armed: AUTO.LAND, a STATUSTEXT, no more commands; the simulator's own
//    command-loss descent flies the landing and disarms on the ground, and the endpoint follows.
//  - Telemetry: ATTITUDE_QUATERNION and LOCAL_POSITION_NED (the estimate: the true state), and
//    HIGHRES_IMU from the simulated IMU samples, stamped in Unix time (sim time); rates as set by
//    SET_MESSAGE_INTERVAL. TIMESYNC requests answered with the boot clock.
//  - MAV_CMD_REQUEST_MESSAGE for AUTOPILOT_VERSION (and the older
//    MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES): acknowledged, then AUTOPILOT_VERSION as a PX4 of
//    kFlightSwVersion, whose position targets take a feed-forward acceleration.
//  - ATT_POS_MOCAP / ODOMETRY are counted (the estimate is the truth here).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/geometry.hpp"
#include "mavlink/autopilot_modes.hpp"
#include "mavlink/frame.hpp"
#include "mavlink/messages.hpp"
#include "mavlink/parser.hpp"
#include "sim/dynamics.hpp"
#include "sim/sensors.hpp"

namespace alight::sim {

struct OffboardEndpointParams {
  uint8_t sysid = 1;
  uint8_t compid = 1;
  double offboard_loss_timeout_s = 1.0;  ///< COM_OF_LOSS_T [s]
  double offboard_min_rate_hz = 2.0;     ///< setpoints needed before OFFBOARD [Hz]
  double hover_thrust = 0.5;             ///< MPC_THR_HOVER: normalised thrust that hovers [-]
  double yaw_p_per_s = 2.8;              ///< MC_YAW_P: heading error to yaw rate [1/s]
  double max_yaw_rate_radps = 3.49;      ///< MC_YAWRATE_MAX (200 deg/s) [rad/s]
  double attitude_rate_hz = 50.0;        ///< ATTITUDE_QUATERNION until asked otherwise [Hz]
  double position_rate_hz = 30.0;        ///< LOCAL_POSITION_NED [Hz]
  double imu_rate_hz = 50.0;             ///< HIGHRES_IMU [Hz]
};

/// A position target in alight's world (ENU), for the autopilot's position controller.
struct EndpointPositionTarget {
  int64_t utime = 0;
  Vector3d p_W = Vector3d::Zero();
  Vector3d v_W = Vector3d::Zero();
  Vector3d a_W = Vector3d::Zero();  ///< feed-forward; zero when the target gave none
  double yaw_rad = 0;
};

struct EndpointInput {
  std::span<const uint8_t> bytes;  ///< from alight-mavlink
  int64_t now_utime = 0;           ///< sim time (Unix epoch)
  VehicleState state;              ///< the vehicle now (the estimate the autopilot reports)
  bool on_ground = false;          ///< resting on the floor or platform (land detector)
  std::vector<ImuSample> imu;      ///< IMU samples since the last call
};

struct EndpointOutput {
  std::vector<uint8_t> bytes;                      ///< to alight-mavlink
  std::optional<AttitudeCommand> command;          ///< for Simulator::command()
  std::optional<EndpointPositionTarget> position;  ///< for the position controller
  bool disarm = false;                             ///< the motors stop now (disarm accepted)
  std::vector<std::string> events;                 ///< log lines
};

struct EndpointStats {
  uint64_t setpoints = 0;
  uint64_t mocap = 0;
  uint64_t commands = 0;
  uint64_t rejected_commands = 0;
  uint64_t failsafes = 0;
};

class OffboardEndpoint {
 public:
  /// `hover_thrust_N`: the simulated vehicle's weight.
  OffboardEndpoint(const OffboardEndpointParams& params, double hover_thrust_N, int64_t boot_utime);

  EndpointOutput update(const EndpointInput& in);

  bool armed() const { return armed_; }
  uint32_t custom_mode() const { return custom_mode_; }
  bool offboard() const;
  const EndpointStats& stats() const { return stats_; }
  const mavlink::ParserStats& parser_stats() const { return parser_.stats(); }

 private:
  void handle(const mavlink::Frame& f, const EndpointInput& in, EndpointOutput& out);
  void on_command(const mavlink::CommandLong& c, const EndpointInput& in, EndpointOutput& out);
  void ack(const mavlink::CommandLong& c, uint8_t result, uint8_t to_sys, uint8_t to_comp,
           EndpointOutput& out);
  void text(uint8_t severity, const std::string& s, EndpointOutput& out);
  bool stream_ok(int64_t now) const;
  void set_mode(uint32_t mode, EndpointOutput& out);
  template <class M>
  void send(const M& m, EndpointOutput& out);
  uint32_t boot_ms(int64_t now) const;

  OffboardEndpointParams params_;
  double hover_thrust_N_;
  int64_t boot_utime_;
  mavlink::Parser parser_;
  mavlink::Sender sender_;
  EndpointStats stats_;
  uint32_t custom_mode_;
  bool armed_ = false;
  std::vector<int64_t> setpoint_times_;  // the last second's
  int64_t last_setpoint_utime_ = 0;
  int64_t next_heartbeat_ = 0, next_attitude_ = 0, next_position_ = 0, last_imu_sent_ = 0;
  double attitude_rate_hz_, position_rate_hz_, imu_rate_hz_;
  uint8_t peer_sysid_ = 0, peer_compid_ = 0;
};

}  // namespace alight::sim

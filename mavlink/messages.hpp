#pragma once
// The MAVLink messages alight speaks, written from the published definitions (message
// definitions common.xml and minimal.xml of github.com/mavlink/mavlink; field semantics at
// mavlink.io/en/messages/common.html). Members are declared in the XML's order, with the XML's
// names and units; `fields()` lists them in wire order (wire.hpp) and marks where the MAVLink 2
// extensions begin. kCrcExtra, kBaseLength and kMaxLength are the published values; the
// static_asserts at the end recompute them from the field lists.
//
// Frames as the XML defines them: positions and velocities in a local NED frame, attitudes and
// body rates in FRD (see ned_frd.hpp for alight's ENU / FLU).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "mavlink/wire.hpp"

namespace alight::mavlink {

// --- Enumerations (the values alight uses) ------------------------------------------------------

namespace mav_type {
inline constexpr uint8_t kGeneric = 0, kQuadrotor = 2, kGcs = 6, kOnboardController = 18;
}
namespace mav_autopilot {
inline constexpr uint8_t kGeneric = 0, kArdupilotmega = 3, kInvalid = 8, kPx4 = 12;
}
namespace mav_mode_flag {  // HEARTBEAT.base_mode bits
inline constexpr uint8_t kCustomModeEnabled = 1, kTestEnabled = 2, kAutoEnabled = 4,
                         kGuidedEnabled = 8, kStabilizeEnabled = 16, kHilEnabled = 32,
                         kManualInputEnabled = 64, kSafetyArmed = 128;
}
namespace mav_state {
inline constexpr uint8_t kUninit = 0, kBoot = 1, kCalibrating = 2, kStandby = 3, kActive = 4,
                         kCritical = 5, kEmergency = 6, kPoweroff = 7, kFlightTermination = 8;
}
namespace mav_component {
inline constexpr uint8_t kAutopilot1 = 1, kOnboardComputer = 191, kVisualInertialOdometry = 197;
}
namespace mav_frame {
inline constexpr uint8_t kLocalNed = 1, kBodyNed = 8, kBodyOffsetNed = 9, kBodyFrd = 12,
                         kLocalFrd = 20, kLocalFlu = 21;
}
namespace mav_cmd {
inline constexpr uint16_t kNavLand = 21, kNavTakeoff = 22, kDoSetMode = 176,
                          kComponentArmDisarm = 400, kSetMessageInterval = 511,
                          kRequestMessage = 512, kRequestAutopilotCapabilities = 520;
}
namespace mav_result {
inline constexpr uint8_t kAccepted = 0, kTemporarilyRejected = 1, kDenied = 2, kUnsupported = 3,
                         kFailed = 4, kInProgress = 5, kCancelled = 6;
}
namespace mav_landed_state {
inline constexpr uint8_t kUndefined = 0, kOnGround = 1, kInAir = 2, kTakeoff = 3, kLanding = 4;
}
namespace mav_severity {
inline constexpr uint8_t kEmergency = 0, kAlert = 1, kCritical = 2, kError = 3, kWarning = 4,
                         kNotice = 5, kInfo = 6, kDebug = 7;
}
namespace mav_estimator_type {
inline constexpr uint8_t kUnknown = 0, kVision = 2, kVio = 3, kMocap = 6;
}
namespace firmware_version_type {  // AUTOPILOT_VERSION.flight_sw_version's low byte
inline constexpr uint8_t kDev = 0, kAlpha = 64, kBeta = 128, kRc = 192, kOfficial = 255;
}
namespace attitude_target_typemask {  // SET_ATTITUDE_TARGET.type_mask: set bit = ignore
inline constexpr uint8_t kBodyRollRateIgnore = 1, kBodyPitchRateIgnore = 2, kBodyYawRateIgnore = 4,
                         kThrustBodySet = 32, kThrottleIgnore = 64, kAttitudeIgnore = 128;
}
namespace position_target_typemask {  // SET_POSITION_TARGET_LOCAL_NED.type_mask: set bit = ignore
inline constexpr uint16_t kXIgnore = 1, kYIgnore = 2, kZIgnore = 4, kVxIgnore = 8, kVyIgnore = 16,
                          kVzIgnore = 32, kAxIgnore = 64, kAyIgnore = 128, kAzIgnore = 256,
                          kForceSet = 512, kYawIgnore = 1024, kYawRateIgnore = 2048;
/// The acceleration's three bits; ArduCopter reads any one of them set as all ignored
/// (ArduCopter/GCS_MAVLink_Copter.cpp, acc_ignore).
inline constexpr uint16_t kAccelIgnore = kAxIgnore | kAyIgnore | kAzIgnore;
}  // namespace position_target_typemask

// --- Messages ---------------------------------------------------------------------------------

/// HEARTBEAT (0, minimal.xml): the sender exists, what it is and its state.
struct Heartbeat {
  static constexpr uint32_t kId = 0;
  static constexpr std::string_view kName = "HEARTBEAT";
  static constexpr uint8_t kCrcExtra = 50, kBaseLength = 9, kMaxLength = 9;

  uint8_t type = 0;             ///< MAV_TYPE
  uint8_t autopilot = 0;        ///< MAV_AUTOPILOT
  uint8_t base_mode = 0;        ///< MAV_MODE_FLAG bits
  uint32_t custom_mode = 0;     ///< autopilot-specific mode (PX4: main/sub mode; ArduPilot: mode)
  uint8_t system_status = 0;    ///< MAV_STATE
  uint8_t mavlink_version = 3;  ///< uint8_t_mavlink_version: the version of minimal.xml (3)

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("custom_mode", m.custom_mode);
    v("type", m.type);
    v("autopilot", m.autopilot);
    v("base_mode", m.base_mode);
    v("system_status", m.system_status);
    v("mavlink_version", m.mavlink_version);
  }
  bool operator==(const Heartbeat&) const = default;
};

/// SYS_STATUS (1): sensors present / enabled / healthy, battery, communication errors.
struct SysStatus {
  static constexpr uint32_t kId = 1;
  static constexpr std::string_view kName = "SYS_STATUS";
  static constexpr uint8_t kCrcExtra = 124, kBaseLength = 31, kMaxLength = 43;

  uint32_t onboard_control_sensors_present = 0;  ///< MAV_SYS_STATUS_SENSOR bits
  uint32_t onboard_control_sensors_enabled = 0;
  uint32_t onboard_control_sensors_health = 0;
  uint16_t load = 0;             ///< main loop load [d%] (0..1000)
  uint16_t voltage_battery = 0;  ///< [mV], UINT16_MAX: not sent
  int16_t current_battery = 0;   ///< [cA], -1: not sent
  int8_t battery_remaining = 0;  ///< [%], -1: not sent
  uint16_t drop_rate_comm = 0;   ///< [c%]
  uint16_t errors_comm = 0;
  uint16_t errors_count1 = 0;
  uint16_t errors_count2 = 0;
  uint16_t errors_count3 = 0;
  uint16_t errors_count4 = 0;
  // extensions
  uint32_t onboard_control_sensors_present_extended = 0;  ///< MAV_SYS_STATUS_SENSOR_EXTENDED
  uint32_t onboard_control_sensors_enabled_extended = 0;
  uint32_t onboard_control_sensors_health_extended = 0;

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("onboard_control_sensors_present", m.onboard_control_sensors_present);
    v("onboard_control_sensors_enabled", m.onboard_control_sensors_enabled);
    v("onboard_control_sensors_health", m.onboard_control_sensors_health);
    v("load", m.load);
    v("voltage_battery", m.voltage_battery);
    v("current_battery", m.current_battery);
    v("drop_rate_comm", m.drop_rate_comm);
    v("errors_comm", m.errors_comm);
    v("errors_count1", m.errors_count1);
    v("errors_count2", m.errors_count2);
    v("errors_count3", m.errors_count3);
    v("errors_count4", m.errors_count4);
    v("battery_remaining", m.battery_remaining);
    v.extensions();
    v("onboard_control_sensors_present_extended", m.onboard_control_sensors_present_extended);
    v("onboard_control_sensors_enabled_extended", m.onboard_control_sensors_enabled_extended);
    v("onboard_control_sensors_health_extended", m.onboard_control_sensors_health_extended);
  }
  bool operator==(const SysStatus&) const = default;
};

/// ATTITUDE_QUATERNION (31): attitude of the FRD body in the local NED frame, body rates.
struct AttitudeQuaternion {
  static constexpr uint32_t kId = 31;
  static constexpr std::string_view kName = "ATTITUDE_QUATERNION";
  static constexpr uint8_t kCrcExtra = 246, kBaseLength = 32, kMaxLength = 48;

  uint32_t time_boot_ms = 0;             ///< [ms] since the sender's boot
  float q1 = 1, q2 = 0, q3 = 0, q4 = 0;  ///< w, x, y, z
  float rollspeed = 0;                   ///< [rad/s] about FRD x
  float pitchspeed = 0;                  ///< [rad/s] about FRD y
  float yawspeed = 0;                    ///< [rad/s] about FRD z
  // extensions
  std::array<float, 4> repr_offset_q{};  ///< display offset [w, x, y, z]; zeros: not supported

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_boot_ms", m.time_boot_ms);
    v("q1", m.q1);
    v("q2", m.q2);
    v("q3", m.q3);
    v("q4", m.q4);
    v("rollspeed", m.rollspeed);
    v("pitchspeed", m.pitchspeed);
    v("yawspeed", m.yawspeed);
    v.extensions();
    v("repr_offset_q", m.repr_offset_q);
  }
  bool operator==(const AttitudeQuaternion&) const = default;
};

/// LOCAL_POSITION_NED (32): the autopilot's filtered local position and velocity (NED).
struct LocalPositionNed {
  static constexpr uint32_t kId = 32;
  static constexpr std::string_view kName = "LOCAL_POSITION_NED";
  static constexpr uint8_t kCrcExtra = 185, kBaseLength = 28, kMaxLength = 28;

  uint32_t time_boot_ms = 0;     ///< [ms]
  float x = 0, y = 0, z = 0;     ///< [m] NED
  float vx = 0, vy = 0, vz = 0;  ///< [m/s] NED

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_boot_ms", m.time_boot_ms);
    v("x", m.x);
    v("y", m.y);
    v("z", m.z);
    v("vx", m.vx);
    v("vy", m.vy);
    v("vz", m.vz);
  }
  bool operator==(const LocalPositionNed&) const = default;
};

/// COMMAND_LONG (76): a command with up to seven float parameters (arm, mode, ...).
struct CommandLong {
  static constexpr uint32_t kId = 76;
  static constexpr std::string_view kName = "COMMAND_LONG";
  static constexpr uint8_t kCrcExtra = 152, kBaseLength = 33, kMaxLength = 33;

  uint8_t target_system = 0;
  uint8_t target_component = 0;  ///< 0: all components
  uint16_t command = 0;          ///< MAV_CMD
  uint8_t confirmation = 0;      ///< 0 first transmission, then 1..255
  float param1 = 0, param2 = 0, param3 = 0, param4 = 0, param5 = 0, param6 = 0, param7 = 0;

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("param1", m.param1);
    v("param2", m.param2);
    v("param3", m.param3);
    v("param4", m.param4);
    v("param5", m.param5);
    v("param6", m.param6);
    v("param7", m.param7);
    v("command", m.command);
    v("target_system", m.target_system);
    v("target_component", m.target_component);
    v("confirmation", m.confirmation);
  }
  bool operator==(const CommandLong&) const = default;
};

/// COMMAND_ACK (77): the result of a command.
struct CommandAck {
  static constexpr uint32_t kId = 77;
  static constexpr std::string_view kName = "COMMAND_ACK";
  static constexpr uint8_t kCrcExtra = 143, kBaseLength = 3, kMaxLength = 10;

  uint16_t command = 0;  ///< MAV_CMD acknowledged
  uint8_t result = 0;    ///< MAV_RESULT
  // extensions
  uint8_t progress = 0;       ///< [%] with MAV_RESULT_IN_PROGRESS
  int32_t result_param2 = 0;  ///< command-specific detail
  uint8_t target_system = 0;  ///< the system that sent the command
  uint8_t target_component = 0;

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("command", m.command);
    v("result", m.result);
    v.extensions();
    v("progress", m.progress);
    v("result_param2", m.result_param2);
    v("target_system", m.target_system);
    v("target_component", m.target_component);
  }
  bool operator==(const CommandAck&) const = default;
};

/// SET_ATTITUDE_TARGET (82): attitude (LOCAL_NED to BODY_FRD), body rates and thrust setpoint.
struct SetAttitudeTarget {
  static constexpr uint32_t kId = 82;
  static constexpr std::string_view kName = "SET_ATTITUDE_TARGET";
  static constexpr uint8_t kCrcExtra = 49, kBaseLength = 39, kMaxLength = 51;

  uint32_t time_boot_ms = 0;  ///< [ms]
  uint8_t target_system = 0;
  uint8_t target_component = 0;
  uint8_t type_mask = 0;               ///< attitude_target_typemask bits (set = ignore)
  std::array<float, 4> q{1, 0, 0, 0};  ///< w, x, y, z: FRD body in the local NED frame
  float body_roll_rate = 0;            ///< [rad/s]
  float body_pitch_rate = 0;           ///< [rad/s]
  float body_yaw_rate = 0;             ///< [rad/s]
  float thrust = 0;                    ///< collective thrust, normalised 0..1
  // extensions
  std::array<float, 3> thrust_body{};  ///< 3D thrust in FRD, normalised -1..1

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_boot_ms", m.time_boot_ms);
    v("q", m.q);
    v("body_roll_rate", m.body_roll_rate);
    v("body_pitch_rate", m.body_pitch_rate);
    v("body_yaw_rate", m.body_yaw_rate);
    v("thrust", m.thrust);
    v("target_system", m.target_system);
    v("target_component", m.target_component);
    v("type_mask", m.type_mask);
    v.extensions();
    v("thrust_body", m.thrust_body);
  }
  bool operator==(const SetAttitudeTarget&) const = default;
};

/// SET_POSITION_TARGET_LOCAL_NED (84): position / velocity / acceleration / yaw setpoint.
struct SetPositionTargetLocalNed {
  static constexpr uint32_t kId = 84;
  static constexpr std::string_view kName = "SET_POSITION_TARGET_LOCAL_NED";
  static constexpr uint8_t kCrcExtra = 143, kBaseLength = 53, kMaxLength = 53;

  uint32_t time_boot_ms = 0;  ///< [ms]
  uint8_t target_system = 0;
  uint8_t target_component = 0;
  uint8_t coordinate_frame = mav_frame::kLocalNed;  ///< MAV_FRAME
  uint16_t type_mask = 0;           ///< position_target_typemask bits (set = ignore)
  float x = 0, y = 0, z = 0;        ///< [m] NED
  float vx = 0, vy = 0, vz = 0;     ///< [m/s] NED
  float afx = 0, afy = 0, afz = 0;  ///< [m/s^2] NED (or [N] with kForceSet)
  float yaw = 0;                    ///< [rad] NED heading
  float yaw_rate = 0;               ///< [rad/s]

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_boot_ms", m.time_boot_ms);
    v("x", m.x);
    v("y", m.y);
    v("z", m.z);
    v("vx", m.vx);
    v("vy", m.vy);
    v("vz", m.vz);
    v("afx", m.afx);
    v("afy", m.afy);
    v("afz", m.afz);
    v("yaw", m.yaw);
    v("yaw_rate", m.yaw_rate);
    v("type_mask", m.type_mask);
    v("target_system", m.target_system);
    v("target_component", m.target_component);
    v("coordinate_frame", m.coordinate_frame);
  }
  bool operator==(const SetPositionTargetLocalNed&) const = default;
};

/// HIGHRES_IMU (105): IMU in SI units, FRD body.
struct HighresImu {
  static constexpr uint32_t kId = 105;
  static constexpr std::string_view kName = "HIGHRES_IMU";
  static constexpr uint8_t kCrcExtra = 93, kBaseLength = 62, kMaxLength = 63;

  uint64_t time_usec = 0;                 ///< [us] Unix epoch or since boot
  float xacc = 0, yacc = 0, zacc = 0;     ///< [m/s^2]
  float xgyro = 0, ygyro = 0, zgyro = 0;  ///< [rad/s]
  float xmag = 0, ymag = 0, zmag = 0;     ///< [gauss]
  float abs_pressure = 0;                 ///< [hPa]
  float diff_pressure = 0;                ///< [hPa]
  float pressure_alt = 0;                 ///< [m]
  float temperature = 0;                  ///< [degC]
  uint16_t fields_updated = 0;            ///< HIGHRES_IMU_UPDATED_FLAGS
  // extensions
  uint8_t id = 0;  ///< IMU index (0 = IMU1)

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_usec", m.time_usec);
    v("xacc", m.xacc);
    v("yacc", m.yacc);
    v("zacc", m.zacc);
    v("xgyro", m.xgyro);
    v("ygyro", m.ygyro);
    v("zgyro", m.zgyro);
    v("xmag", m.xmag);
    v("ymag", m.ymag);
    v("zmag", m.zmag);
    v("abs_pressure", m.abs_pressure);
    v("diff_pressure", m.diff_pressure);
    v("pressure_alt", m.pressure_alt);
    v("temperature", m.temperature);
    v("fields_updated", m.fields_updated);
    v.extensions();
    v("id", m.id);
  }
  bool operator==(const HighresImu&) const = default;
};

/// TIMESYNC (111): request (tc1 = 0) and response of a round-trip clock offset estimate.
struct Timesync {
  static constexpr uint32_t kId = 111;
  static constexpr std::string_view kName = "TIMESYNC";
  static constexpr uint8_t kCrcExtra = 34, kBaseLength = 16, kMaxLength = 18;

  int64_t tc1 = 0;  ///< [ns] responder's time (0 in a request)
  int64_t ts1 = 0;  ///< [ns] requester's time, mirrored in the response
  // extensions
  uint8_t target_system = 0;  ///< request: 0 or a system; response: the requester
  uint8_t target_component = 0;

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("tc1", m.tc1);
    v("ts1", m.ts1);
    v.extensions();
    v("target_system", m.target_system);
    v("target_component", m.target_component);
  }
  bool operator==(const Timesync&) const = default;
};

/// ATT_POS_MOCAP (138): motion-capture pose for the autopilot's estimator (NED, FRD).
struct AttPosMocap {
  static constexpr uint32_t kId = 138;
  static constexpr std::string_view kName = "ATT_POS_MOCAP";
  static constexpr uint8_t kCrcExtra = 109, kBaseLength = 36, kMaxLength = 120;

  uint64_t time_usec = 0;              ///< [us]
  std::array<float, 4> q{1, 0, 0, 0};  ///< w, x, y, z
  float x = 0, y = 0, z = 0;           ///< [m] NED
  // extensions
  std::array<float, 21> covariance{};  ///< upper triangle of the 6x6 pose covariance, row-major
                                       ///< (x, y, z, roll, pitch, yaw); NaN first: unknown

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_usec", m.time_usec);
    v("q", m.q);
    v("x", m.x);
    v("y", m.y);
    v("z", m.z);
    v.extensions();
    v("covariance", m.covariance);
  }
  bool operator==(const AttPosMocap&) const = default;
};

/// STATUSTEXT (253): a text line for the operator.
struct Statustext {
  static constexpr uint32_t kId = 253;
  static constexpr std::string_view kName = "STATUSTEXT";
  static constexpr uint8_t kCrcExtra = 83, kBaseLength = 51, kMaxLength = 54;

  uint8_t severity = 0;         ///< MAV_SEVERITY
  std::array<char, 50> text{};  ///< UTF-8, NUL-terminated only when shorter than 50
  // extensions
  uint16_t id = 0;        ///< groups the chunks of a long text; 0: single chunk
  uint8_t chunk_seq = 0;  ///< chunk index

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("severity", m.severity);
    v("text", m.text);
    v.extensions();
    v("id", m.id);
    v("chunk_seq", m.chunk_seq);
  }
  bool operator==(const Statustext&) const = default;
};

/// ODOMETRY (331): pose, twist and their covariances in named frames (REP 147).
struct Odometry {
  static constexpr uint32_t kId = 331;
  static constexpr std::string_view kName = "ODOMETRY";
  static constexpr uint8_t kCrcExtra = 91, kBaseLength = 230, kMaxLength = 233;

  uint64_t time_usec = 0;                             ///< [us]
  uint8_t frame_id = 0;                               ///< MAV_FRAME of the pose
  uint8_t child_frame_id = 0;                         ///< MAV_FRAME of the twist
  float x = 0, y = 0, z = 0;                          ///< [m]
  std::array<float, 4> q{1, 0, 0, 0};                 ///< w, x, y, z
  float vx = 0, vy = 0, vz = 0;                       ///< [m/s]
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  ///< [rad/s]
  std::array<float, 21> pose_covariance{};      ///< upper triangle, row-major; NaN first: unknown
  std::array<float, 21> velocity_covariance{};  ///< upper triangle, row-major; NaN first: unknown
  // extensions
  uint8_t reset_counter = 0;   ///< incremented at every estimate reset
  uint8_t estimator_type = 0;  ///< MAV_ESTIMATOR_TYPE
  int8_t quality = 0;          ///< [%] -1 failed, 0 unknown, 1..100

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_usec", m.time_usec);
    v("x", m.x);
    v("y", m.y);
    v("z", m.z);
    v("q", m.q);
    v("vx", m.vx);
    v("vy", m.vy);
    v("vz", m.vz);
    v("rollspeed", m.rollspeed);
    v("pitchspeed", m.pitchspeed);
    v("yawspeed", m.yawspeed);
    v("pose_covariance", m.pose_covariance);
    v("velocity_covariance", m.velocity_covariance);
    v("frame_id", m.frame_id);
    v("child_frame_id", m.child_frame_id);
    v.extensions();
    v("reset_counter", m.reset_counter);
    v("estimator_type", m.estimator_type);
    v("quality", m.quality);
  }
  bool operator==(const Odometry&) const = default;
};

/// SCALED_IMU (26): the first IMU in integer units (mG, mrad/s), FRD body. Every ArduPilot board
/// can send it; HIGHRES_IMU only those with more than 1 MB of flash.
struct ScaledImu {
  static constexpr uint32_t kId = 26;
  static constexpr std::string_view kName = "SCALED_IMU";
  static constexpr uint8_t kCrcExtra = 170, kBaseLength = 22, kMaxLength = 24;

  uint32_t time_boot_ms = 0;                ///< [ms]
  int16_t xacc = 0, yacc = 0, zacc = 0;     ///< [mG]
  int16_t xgyro = 0, ygyro = 0, zgyro = 0;  ///< [mrad/s]
  int16_t xmag = 0, ymag = 0, zmag = 0;     ///< [mgauss]
  // extensions
  int16_t temperature = 0;  ///< [cdegC], 0: not provided

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_boot_ms", m.time_boot_ms);
    v("xacc", m.xacc);
    v("yacc", m.yacc);
    v("zacc", m.zacc);
    v("xgyro", m.xgyro);
    v("ygyro", m.ygyro);
    v("zgyro", m.zgyro);
    v("xmag", m.xmag);
    v("ymag", m.ymag);
    v("zmag", m.zmag);
    v.extensions();
    v("temperature", m.temperature);
  }
  bool operator==(const ScaledImu&) const = default;
};

/// SET_GPS_GLOBAL_ORIGIN (48): the geodetic origin of the autopilot's local frame (its EKF), for
/// a vehicle without GPS.
struct SetGpsGlobalOrigin {
  static constexpr uint32_t kId = 48;
  static constexpr std::string_view kName = "SET_GPS_GLOBAL_ORIGIN";
  static constexpr uint8_t kCrcExtra = 41, kBaseLength = 13, kMaxLength = 21;

  uint8_t target_system = 0;
  int32_t latitude = 0;   ///< [degE7]
  int32_t longitude = 0;  ///< [degE7]
  int32_t altitude = 0;   ///< [mm] above mean sea level
  // extensions
  uint64_t time_usec = 0;  ///< [us]

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("latitude", m.latitude);
    v("longitude", m.longitude);
    v("altitude", m.altitude);
    v("target_system", m.target_system);
    v.extensions();
    v("time_usec", m.time_usec);
  }
  bool operator==(const SetGpsGlobalOrigin&) const = default;
};

/// GPS_GLOBAL_ORIGIN (49): the origin the autopilot's local frame has (sent once it is set).
struct GpsGlobalOrigin {
  static constexpr uint32_t kId = 49;
  static constexpr std::string_view kName = "GPS_GLOBAL_ORIGIN";
  static constexpr uint8_t kCrcExtra = 39, kBaseLength = 12, kMaxLength = 20;

  int32_t latitude = 0;   ///< [degE7]
  int32_t longitude = 0;  ///< [degE7]
  int32_t altitude = 0;   ///< [mm] above mean sea level
  // extensions
  uint64_t time_usec = 0;  ///< [us]

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("latitude", m.latitude);
    v("longitude", m.longitude);
    v("altitude", m.altitude);
    v.extensions();
    v("time_usec", m.time_usec);
  }
  bool operator==(const GpsGlobalOrigin&) const = default;
};

/// SIM_STATE (108): a simulator's true state (ArduPilot SITL): attitude FRD in NED, body rates,
/// geodetic position, NED velocity.
struct SimState {
  static constexpr uint32_t kId = 108;
  static constexpr std::string_view kName = "SIM_STATE";
  static constexpr uint8_t kCrcExtra = 32, kBaseLength = 84, kMaxLength = 92;

  float q1 = 1, q2 = 0, q3 = 0, q4 = 0;   ///< w, x, y, z
  float roll = 0, pitch = 0, yaw = 0;     ///< [rad]
  float xacc = 0, yacc = 0, zacc = 0;     ///< [m/s^2]
  float xgyro = 0, ygyro = 0, zgyro = 0;  ///< [rad/s] FRD body
  float lat = 0, lon = 0;                 ///< [deg] (ArduPilot fills degE7 here: use lat_int)
  float alt = 0;                          ///< [m] above mean sea level
  float std_dev_horz = 0, std_dev_vert = 0;
  float vn = 0, ve = 0, vd = 0;  ///< [m/s] NED
  // extensions
  int32_t lat_int = 0, lon_int = 0;  ///< [degE7]; 0: use lat / lon

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("q1", m.q1);
    v("q2", m.q2);
    v("q3", m.q3);
    v("q4", m.q4);
    v("roll", m.roll);
    v("pitch", m.pitch);
    v("yaw", m.yaw);
    v("xacc", m.xacc);
    v("yacc", m.yacc);
    v("zacc", m.zacc);
    v("xgyro", m.xgyro);
    v("ygyro", m.ygyro);
    v("zgyro", m.zgyro);
    v("lat", m.lat);
    v("lon", m.lon);
    v("alt", m.alt);
    v("std_dev_horz", m.std_dev_horz);
    v("std_dev_vert", m.std_dev_vert);
    v("vn", m.vn);
    v("ve", m.ve);
    v("vd", m.vd);
    v.extensions();
    v("lat_int", m.lat_int);
    v("lon_int", m.lon_int);
  }
  bool operator==(const SimState&) const = default;
};

/// HIL_STATE_QUATERNION (115): PX4 SIH's true state (its ground truth topics).
struct HilStateQuaternion {
  static constexpr uint32_t kId = 115;
  static constexpr std::string_view kName = "HIL_STATE_QUATERNION";
  static constexpr uint8_t kCrcExtra = 4, kBaseLength = 64, kMaxLength = 64;

  uint64_t time_usec = 0;                                ///< [us] (PX4 leaves it 0)
  std::array<float, 4> attitude_quaternion{1, 0, 0, 0};  ///< w, x, y, z: FRD body in NED
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;     ///< [rad/s] FRD body
  int32_t lat = 0, lon = 0;                              ///< [degE7]
  int32_t alt = 0;                                       ///< [mm]
  int16_t vx = 0, vy = 0, vz = 0;                        ///< [cm/s] north, east, down
  uint16_t ind_airspeed = 0, true_airspeed = 0;          ///< [cm/s]
  int16_t xacc = 0, yacc = 0, zacc = 0;                  ///< [mG]

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("time_usec", m.time_usec);
    v("attitude_quaternion", m.attitude_quaternion);
    v("rollspeed", m.rollspeed);
    v("pitchspeed", m.pitchspeed);
    v("yawspeed", m.yawspeed);
    v("lat", m.lat);
    v("lon", m.lon);
    v("alt", m.alt);
    v("vx", m.vx);
    v("vy", m.vy);
    v("vz", m.vz);
    v("ind_airspeed", m.ind_airspeed);
    v("true_airspeed", m.true_airspeed);
    v("xacc", m.xacc);
    v("yacc", m.yacc);
    v("zacc", m.zacc);
  }
  bool operator==(const HilStateQuaternion&) const = default;
};

/// EXTENDED_SYS_STATE (245): whether the autopilot thinks the vehicle is on the ground.
struct ExtendedSysState {
  static constexpr uint32_t kId = 245;
  static constexpr std::string_view kName = "EXTENDED_SYS_STATE";
  static constexpr uint8_t kCrcExtra = 130, kBaseLength = 2, kMaxLength = 2;

  uint8_t vtol_state = 0;    ///< MAV_VTOL_STATE
  uint8_t landed_state = 0;  ///< MAV_LANDED_STATE

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("vtol_state", m.vtol_state);
    v("landed_state", m.landed_state);
  }
  bool operator==(const ExtendedSysState&) const = default;
};

/// SETUP_SIGNING (256): gives an autopilot the signing key (sent over a secure link).
struct SetupSigning {
  static constexpr uint32_t kId = 256;
  static constexpr std::string_view kName = "SETUP_SIGNING";
  static constexpr uint8_t kCrcExtra = 71, kBaseLength = 42, kMaxLength = 42;

  uint8_t target_system = 0;
  uint8_t target_component = 0;
  std::array<uint8_t, 32> secret_key{};
  uint64_t initial_timestamp = 0;  ///< signing timestamp (10 us since 2015)

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("initial_timestamp", m.initial_timestamp);
    v("target_system", m.target_system);
    v("target_component", m.target_component);
    v("secret_key", m.secret_key);
  }
  bool operator==(const SetupSigning&) const = default;
};

/// PARAM_REQUEST_READ (20): asks for one parameter by name (param_index -1).
struct ParamRequestRead {
  static constexpr uint32_t kId = 20;
  static constexpr std::string_view kName = "PARAM_REQUEST_READ";
  static constexpr uint8_t kCrcExtra = 214, kBaseLength = 20, kMaxLength = 20;

  uint8_t target_system = 0;
  uint8_t target_component = 0;
  std::array<char, 16> param_id{};  ///< NUL-terminated only when shorter than 16
  int16_t param_index = -1;         ///< -1: by param_id

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("param_index", m.param_index);
    v("target_system", m.target_system);
    v("target_component", m.target_component);
    v("param_id", m.param_id);
  }
  bool operator==(const ParamRequestRead&) const = default;
};

/// PARAM_VALUE (22): one parameter's value (as a float whatever its type).
struct ParamValue {
  static constexpr uint32_t kId = 22;
  static constexpr std::string_view kName = "PARAM_VALUE";
  static constexpr uint8_t kCrcExtra = 220, kBaseLength = 25, kMaxLength = 25;

  std::array<char, 16> param_id{};
  float param_value = 0;
  uint8_t param_type = 0;  ///< MAV_PARAM_TYPE
  uint16_t param_count = 0;
  uint16_t param_index = 0;

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("param_value", m.param_value);
    v("param_count", m.param_count);
    v("param_index", m.param_index);
    v("param_id", m.param_id);
    v("param_type", m.param_type);
  }
  bool operator==(const ParamValue&) const = default;
};

/// AUTOPILOT_VERSION (148, standard.xml): the firmware's version and capabilities, sent when asked
/// (MAV_CMD_REQUEST_MESSAGE, or MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES on older firmware).
struct AutopilotVersion {
  static constexpr uint32_t kId = 148;
  static constexpr std::string_view kName = "AUTOPILOT_VERSION";
  static constexpr uint8_t kCrcExtra = 178, kBaseLength = 60, kMaxLength = 78;

  uint64_t capabilities = 0;  ///< MAV_PROTOCOL_CAPABILITY bits
  uint32_t flight_sw_version =
      0;  ///< bytes from the top: major, minor, patch, FIRMWARE_VERSION_TYPE
  uint32_t middleware_sw_version = 0;
  uint32_t os_sw_version = 0;
  uint32_t board_version = 0;
  std::array<uint8_t, 8> flight_custom_version{};  ///< commonly the git hash's first 8 bytes
  std::array<uint8_t, 8> middleware_custom_version{};
  std::array<uint8_t, 8> os_custom_version{};
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  uint64_t uid = 0;
  // extensions
  std::array<uint8_t, 18> uid2{};

  template <class S, class V>
  static constexpr void fields(S& m, V& v) {
    v("capabilities", m.capabilities);
    v("uid", m.uid);
    v("flight_sw_version", m.flight_sw_version);
    v("middleware_sw_version", m.middleware_sw_version);
    v("os_sw_version", m.os_sw_version);
    v("board_version", m.board_version);
    v("vendor_id", m.vendor_id);
    v("product_id", m.product_id);
    v("flight_custom_version", m.flight_custom_version);
    v("middleware_custom_version", m.middleware_custom_version);
    v("os_custom_version", m.os_custom_version);
    v.extensions();
    v("uid2", m.uid2);
  }
  bool operator==(const AutopilotVersion&) const = default;
};

// --- The set, and what the parser needs to know of each --------------------------------------

template <class... Ms>
struct MessageList {};
using KnownMessages =
    MessageList<Heartbeat, SysStatus, AttitudeQuaternion, LocalPositionNed, CommandLong, CommandAck,
                SetAttitudeTarget, SetPositionTargetLocalNed, HighresImu, Timesync, AttPosMocap,
                Statustext, Odometry, ScaledImu, SetGpsGlobalOrigin, GpsGlobalOrigin, SimState,
                HilStateQuaternion, ExtendedSysState, SetupSigning, ParamRequestRead, ParamValue,
                AutopilotVersion>;

/// Calls f(M{}) for every known message type M.
template <class F, class... Ms>
constexpr void for_each_message_type(MessageList<Ms...>, F&& f) {
  (f(Ms{}), ...);
}
template <class F>
constexpr void for_each_message_type(F&& f) {
  for_each_message_type(KnownMessages{}, f);
}

struct MessageInfo {
  uint32_t id;
  std::string_view name;
  uint8_t crc_extra;
  uint8_t base_length;  ///< payload bytes without extensions (a MAVLink 1 frame's length)
  uint8_t max_length;   ///< payload bytes with every extension alight knows
};

/// The message with this id, or nullptr when alight does not know it.
const MessageInfo* find_message(uint32_t msgid);

// --- Payload encoding ----------------------------------------------------------------------

/// Writes the untruncated payload of `m` (M::kMaxLength bytes) to `out` and returns the length
/// MAVLink 2 sends: trailing zero bytes dropped, never less than one byte.
template <class M>
uint8_t encode_payload(const M& m, uint8_t* out) {
  detail::PayloadWriter w(out);
  M::fields(m, w);
  size_t n = w.size();
  while (n > 1 && out[n - 1] == 0) --n;
  return static_cast<uint8_t>(n);
}

/// Reads a payload; `payload` must hold at least M::kMaxLength bytes, zero past the received
/// length (Frame::payload is zero-filled to 255 bytes). Bytes beyond M::kMaxLength are fields of a
/// newer definition and are ignored.
template <class M>
M decode_payload(const uint8_t* payload) {
  M m{};
  detail::PayloadReader r(payload);
  M::fields(m, r);
  return m;
}

/// STATUSTEXT text as a string (up to the first NUL or 50 bytes).
std::string statustext_string(const Statustext& m);
/// Fills STATUSTEXT text, cut to 50 bytes.
void set_statustext(Statustext& m, std::string_view text);
/// A parameter's name (PARAM_VALUE, PARAM_REQUEST_READ: up to the first NUL or 16 bytes).
std::string param_id_string(const std::array<char, 16>& id);
/// Fills a parameter name, cut to 16 bytes.
void set_param_id(std::array<char, 16>& id, std::string_view name);

// The published lengths and CRC_EXTRA values agree with the field lists (and so with the wire
// order: CRC_EXTRA hashes the base fields' types and names in the order they are sent).
namespace detail {
template <class M>
constexpr bool layout_matches() {
  constexpr auto l = layout_of<M>();
  return l.wire_order_ok() && l.crc_extra() == M::kCrcExtra && l.base_length() == M::kBaseLength &&
         l.max_length() == M::kMaxLength;
}
}  // namespace detail
static_assert(detail::layout_matches<Heartbeat>());
static_assert(detail::layout_matches<SysStatus>());
static_assert(detail::layout_matches<AttitudeQuaternion>());
static_assert(detail::layout_matches<LocalPositionNed>());
static_assert(detail::layout_matches<CommandLong>());
static_assert(detail::layout_matches<CommandAck>());
static_assert(detail::layout_matches<SetAttitudeTarget>());
static_assert(detail::layout_matches<SetPositionTargetLocalNed>());
static_assert(detail::layout_matches<HighresImu>());
static_assert(detail::layout_matches<Timesync>());
static_assert(detail::layout_matches<AttPosMocap>());
static_assert(detail::layout_matches<Statustext>());
static_assert(detail::layout_matches<Odometry>());
static_assert(detail::layout_matches<ScaledImu>());
static_assert(detail::layout_matches<SetGpsGlobalOrigin>());
static_assert(detail::layout_matches<GpsGlobalOrigin>());
static_assert(detail::layout_matches<SimState>());
static_assert(detail::layout_matches<HilStateQuaternion>());
static_assert(detail::layout_matches<ExtendedSysState>());
static_assert(detail::layout_matches<SetupSigning>());
static_assert(detail::layout_matches<ParamRequestRead>());
static_assert(detail::layout_matches<ParamValue>());
static_assert(detail::layout_matches<AutopilotVersion>());

}  // namespace alight::mavlink

#pragma once
// A scripted ArduCopter or PX4 for the bridge's tests (issue 38): what each autopilot does with the
// messages and commands alight-mavlink sends, rule by rule as their sources do it (each rule names
// the file it was read from: ArduPilot 4.7.0-dev 90700977c5, PX4 release/1.18 83c4f4e580; no code
// of theirs is copied), on a vehicle that moves only up and down. What alight did wrong against a
// real ArduCopter (issue 38) shows here the same way: a SET_ATTITUDE_TARGET dropped for its
// type_mask, a GUIDED vehicle that never leaves the ground without NAV_TAKEOFF, no
// LOCAL_POSITION_NED without an origin, a position target held forever when alight stops.
//
// Deliberately simple where the bridge cannot tell: no lateral motion, attitude taken as
// commanded, the land detectors as a height and speed test held for their time.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mavlink/autopilot_modes.hpp"
#include "mavlink/frame.hpp"
#include "mavlink/messages.hpp"
#include "mavlink/parser.hpp"

namespace alight::mavlink::testing {

struct ScriptedConfig {
  Flavour flavour = Flavour::kArdupilot;
  uint8_t sysid = 1;
  std::optional<SigningKey> signing;  ///< signs what it sends, refuses unsigned frames
  /// ArduPilot: the bridge's link is MAVLink channel 0, where unsigned frames are accepted
  /// anyway (libraries/GCS_MAVLink/GCS_Signing.cpp, accept_unsigned_callback).
  bool channel0 = false;

  /// AUTOPILOT_VERSION.flight_sw_version (major, minor, patch, FIRMWARE_VERSION_TYPE from the top
  /// byte); 0: the sources' own (ArduCopter 4.7.0-dev, PX4 1.18.0-dev). An ArduCopter older
  /// than 4.1.0-rc handles SET_POSITION_TARGET_LOCAL_NED as before the Guided rework of 2021-05
  /// (ArduCopter/GCS_Mavlink.cpp before 635d13a106: a target with any acceleration dropped).
  uint32_t flight_sw_version = 0;
  /// Answers MAV_CMD_REQUEST_MESSAGE (ArduPilot from 4.0, libraries/GCS_MAVLink/GCS_Common.cpp,
  /// handle_command_request_message); without it only MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES.
  bool request_message = true;

  // ArduCopter (ArduCopter/Parameters.cpp, libraries/GCS_MAVLink/GCS.cpp).
  double guid_options = 8;  ///< GUID_OPTIONS (bit 3: SET_ATTITUDE_TARGET thrust is thrust)
  double guid_timeout_s = 3.0;
  double disarm_delay_s = 10.0;  ///< DISARM_DELAY
  double fs_gcs_enable = 5;      ///< FS_GCS_ENABLE (5: Land)
  double fs_gcs_timeout_s = 2.0;
  double mav_gcs_sysid = 250;
  double atc_angle_boost = 0;
  double viso_type = 1;
  double mot_thst_hover = 0.39;
  /// Its estimate's height minus the true one [m]: with external navigation ArduCopter SITL's
  /// LOCAL_POSITION_NED read 0.2 m above motion capture (EKF3 keeps its own height datum,
  /// libraries/AP_NavEKF3/AP_NavEKF3_PosVelFusion.cpp).
  double estimate_offset_up_m = 0.0;
  /// Added to it once airborne [m]: PX4 SIH's EKF2, fusing motion capture as vision with the
  /// barometer still fused (EKF2_BARO_CTRL 1, its bias learnt only slowly:
  /// src/modules/ekf2/EKF/aid_sources/barometer/baro_height_control.cpp), read 2 to 5 cm above
  /// motion capture for tens of seconds after take-off.
  double estimate_offset_in_air_up_m = 0.0;
  /// HIGHRES_IMU compiled in: boards with more than 1 MB of flash
  /// (libraries/GCS_MAVLink/GCS_config.h, AP_MAVLINK_MSG_HIGHRES_IMU_ENABLED).
  bool highres_imu = true;

  // PX4 (src/modules/commander/commander_params.yaml, src/modules/ekf2/*.yaml).
  double com_of_loss_t = 1.0;
  double com_obl_rc_act = 4;  ///< 4: Land
  double com_disarm_land_s = 2.0;
  double com_disarm_prflt_s = 10.0;
  double mpc_thr_hover = 0.5;
  double ekf2_ev_ctrl = 15;
};

class ScriptedAutopilot {
 public:
  explicit ScriptedAutopilot(ScriptedConfig config);

  /// Takes the bridge's bytes at `now_us` (steps the vehicle up to then) and returns its answer.
  std::vector<uint8_t> step(std::span<const uint8_t> from_bridge, int64_t now_us);

  /// Starts the vehicle flying in `custom_mode` at `height_m` (a bridge that restarts finds it
  /// so), with an origin and motion capture already.
  void start_flying(uint32_t custom_mode, double height_m, int64_t now_us);

  bool armed() const { return armed_; }
  uint32_t custom_mode() const { return mode_; }
  std::string mode() const { return mode_name(c_.flavour, mode_); }
  double height_m() const { return z_; }
  bool on_ground() const { return landed_; }
  bool origin_set() const { return origin_set_; }

  int arms = 0;              ///< accepted ARMs
  int forced_disarms = 0;    ///< accepted forced DISARMs
  int refused_disarms = 0;   ///< plain DISARMs refused in the air
  int attitude_used = 0;     ///< SET_ATTITUDE_TARGET taken as a target
  int attitude_ignored = 0;  ///< ... outside the modes that take it
  int attitude_dropped = 0;  ///< ... refused for its content (type_mask, quaternion)
  int position_used = 0;     ///< SET_POSITION_TARGET_LOCAL_NED stored as a target
  int position_dropped = 0;  ///< ... refused for its content (type_mask)
  /// The newest position target's acceleration as the controller takes it (NED) [m/s^2]: none
  /// when the target had none.
  std::optional<std::array<float, 3>> target_accel_NED;
  int version_sent = 0;             ///< AUTOPILOT_VERSION sent
  int takeoffs = 0;                 ///< NAV_TAKEOFF accepted
  int fs_gcs_triggers = 0;          ///< ArduCopter's GCS failsafe fired
  int offboard_losses = 0;          ///< PX4's offboard-loss failsafe fired
  std::vector<std::string> events;  ///< what it did, with the time

 private:
  enum class Sub { kNone, kAngle, kPos, kTakeoff };
  template <class M>
  void send(const M& m);
  void ack(uint16_t command, uint8_t result, uint8_t to_sys, uint8_t to_comp);
  void text(const std::string& t);
  void on_frame(const Frame& f);
  void on_command(const CommandLong& c, const Frame& f);
  void send_version();
  uint8_t set_mode(uint32_t mode);
  uint8_t arm(bool on, bool forced);
  void disarm(const std::string& why);
  void physics(double dt);
  void telemetry();
  bool guided() const;
  bool in_offboard() const;
  bool local_position_valid() const;
  uint8_t landed_state() const;
  double param(const std::string& name, bool* found) const;
  double estimate_up_m() const;  ///< the height its estimator reports

  ScriptedConfig c_;
  Parser parser_;
  Sender sender_;
  std::vector<uint8_t> out_;
  int64_t now_ = 0, last_step_ = 0;
  double t_s() const { return now_ * 1e-6; }

  uint32_t mode_;
  bool armed_ = false;
  double z_ = 0, vz_ = 0;
  bool landed_ = true;       // ArduCopter land_complete / PX4 landed
  bool auto_armed_ = false;  // ArduCopter ap.auto_armed
  double land_timer_s_ = 0, disarm_timer_s_ = 0, spool_s_ = 0;
  bool took_off_ = false;  // PX4 _have_taken_off_since_arming
  Sub sub_ = Sub::kNone;
  // The guided / offboard target.
  double thrust_ = 0;  // SET_ATTITUDE_TARGET thrust (or climb-rate request)
  bool use_thrust_ = false;
  int64_t angle_update_ = 0;
  double target_z_ = 0;
  double target_vz_down_ = 0;  // PX4: the position target's commanded descent (NED vz) [m/s]
  int64_t offboard_signal_ = INT64_MIN / 2;  // PX4: the last offboard_control_mode
  bool offboard_attitude_ = false;
  // ArduCopter GCS failsafe.
  int64_t gcs_seen_ = 0;
  bool fs_gcs_ = false;
  // Estimator.
  bool origin_set_ = false;
  int64_t ext_nav_ = INT64_MIN / 2;
  // Streams.
  std::map<uint32_t, int64_t> interval_us_, next_send_;
  int64_t next_heartbeat_ = 0;
};

}  // namespace alight::mavlink::testing

#include "scripted_autopilot.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "mavlink/ned_frd.hpp"

namespace alight::mavlink::testing {

namespace {
constexpr double kG = 9.81;
/// ArduCopter's land detector: 1 s of no climb on the ground (ArduCopter/land_detector.cpp,
/// LAND_DETECTOR_TRIGGER_SEC); PX4's maybe-landed then landed, about as long
/// (src/modules/land_detector/MulticopterLandDetector.cpp).
constexpr double kLandDetectS = 1.0;
/// PX4's LNDMC_Z_VEL_MAX (src/modules/land_detector/land_detector_params_mc.yaml) [m/s].
constexpr double kLndmcZVelMax = 0.25;
/// Motors spooling up before a take-off clears the landed state (ArduCopter/mode_guided.cpp,
/// angle_control_run; libraries/AC_AutoTakeoff).
constexpr double kSpoolS = 0.5;
/// ArduCopter LAND_SPEED 50 cm/s; PX4 MPC_LAND_SPEED 0.7 m/s.
constexpr double kCopterLandSpeed = 0.5, kPx4LandSpeed = 0.7;
/// Take-off climb and the position controller's speed limit here [m/s].
constexpr double kClimb = 1.0;
}  // namespace

ScriptedAutopilot::ScriptedAutopilot(ScriptedConfig config)
    : c_(config),
      parser_(ParserOptions{config.signing, !config.signing || config.channel0}),
      sender_(config.sysid, mav_component::kAutopilot1,
              config.signing ? std::optional<SigningConfig>(SigningConfig{*config.signing, 0})
                             : std::nullopt) {
  // ArduCopter boots in STABILIZE (mode 0, SITL's RC); PX4 in AUTO.LOITER (Hold).
  mode_ = c_.flavour == Flavour::kArdupilot
              ? copter_mode::kStabilize
              : px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kLoiter);
  if (c_.flight_sw_version == 0)
    c_.flight_sw_version = c_.flavour == Flavour::kArdupilot ? 0x04070000u : 0x01120000u;
  if (c_.flavour == Flavour::kPx4) {
    // The onboard link's default streams (src/modules/mavlink/mavlink_main.cpp,
    // configure_streams_to_default, MAVLINK_MODE_ONBOARD).
    interval_us_[HighresImu::kId] = 20'000;
    interval_us_[AttitudeQuaternion::kId] = 20'000;
    interval_us_[LocalPositionNed::kId] = 33'333;
    interval_us_[ExtendedSysState::kId] = 200'000;
    interval_us_[GpsGlobalOrigin::kId] = 1'000'000;
  }
}

template <class M>
void ScriptedAutopilot::send(const M& m) {
  const FrameBytes f = sender_.pack(m, 1'700'000'000'000'000 + now_);
  out_.insert(out_.end(), f.bytes().begin(), f.bytes().end());
}

void ScriptedAutopilot::ack(uint16_t command, uint8_t result, uint8_t to_sys, uint8_t to_comp) {
  CommandAck a;
  a.command = command;
  a.result = result;
  a.target_system = to_sys;
  a.target_component = to_comp;
  send(a);
}

void ScriptedAutopilot::text(const std::string& t) {
  events.push_back(std::to_string(t_s()).substr(0, 6) + " s: " + t);
  Statustext s;
  s.severity = mav_severity::kInfo;
  set_statustext(s, t);
  send(s);
}

bool ScriptedAutopilot::guided() const {
  return mode_ == copter_mode::kGuided || mode_ == copter_mode::kGuidedNoGps;
}

bool ScriptedAutopilot::in_offboard() const {
  return px4_mode::main_mode(mode_) == px4_mode::kOffboard;
}

bool ScriptedAutopilot::local_position_valid() const {
  const bool aided = now_ - ext_nav_ < 1'000'000;
  // ArduPilot: LOCAL_POSITION_NED only with an origin and an aiding source
  // (libraries/GCS_MAVLink/GCS_Common.cpp, send_local_position; libraries/AP_NavEKF3/
  // AP_NavEKF3_Outputs.cpp, getPosNE). PX4's EKF2 has a local frame without a global origin.
  if (c_.flavour == Flavour::kArdupilot) return origin_set_ && aided;
  return aided;
}

uint8_t ScriptedAutopilot::landed_state() const {
  // ArduCopter/GCS_MAVLink_Copter.cpp, landed_state.
  if (landed_) return mav_landed_state::kOnGround;
  if (c_.flavour == Flavour::kArdupilot) {
    if (mode_ == copter_mode::kLand) return mav_landed_state::kLanding;
    if (guided() && sub_ == Sub::kTakeoff && z_ < target_z_ - 0.05)
      return mav_landed_state::kTakeoff;
    return mav_landed_state::kInAir;
  }
  if (is_land_mode(c_.flavour, mode_)) return mav_landed_state::kLanding;
  return mav_landed_state::kInAir;
}

double ScriptedAutopilot::param(const std::string& name, bool* found) const {
  const std::map<std::string, double> ap = {
      {"GUID_OPTIONS", c_.guid_options},       {"GUID_TIMEOUT", c_.guid_timeout_s},
      {"DISARM_DELAY", c_.disarm_delay_s},     {"FS_GCS_ENABLE", c_.fs_gcs_enable},
      {"FS_GCS_TIMEOUT", c_.fs_gcs_timeout_s}, {"MAV_GCS_SYSID", c_.mav_gcs_sysid},
      {"ATC_ANGLE_BOOST", c_.atc_angle_boost}, {"VISO_TYPE", c_.viso_type},
      {"MOT_THST_HOVER", c_.mot_thst_hover},   {"GPS1_TYPE", 0}};
  const std::map<std::string, double> px4 = {{"COM_OF_LOSS_T", c_.com_of_loss_t},
                                             {"COM_OBL_RC_ACT", c_.com_obl_rc_act},
                                             {"COM_DISARM_LAND", c_.com_disarm_land_s},
                                             {"MPC_THR_HOVER", c_.mpc_thr_hover},
                                             {"EKF2_EV_CTRL", c_.ekf2_ev_ctrl}};
  const auto& table = c_.flavour == Flavour::kArdupilot ? ap : px4;
  const auto it = table.find(name);
  *found = it != table.end();
  return *found ? it->second : 0;
}

std::vector<uint8_t> ScriptedAutopilot::step(std::span<const uint8_t> from_bridge, int64_t now_us) {
  out_.clear();
  now_ = now_us;
  const double dt = last_step_ ? std::clamp((now_us - last_step_) * 1e-6, 0.0, 0.1) : 0.0;
  last_step_ = now_us;
  if (!from_bridge.empty()) {
    parser_.observe_time(1'700'000'000'000'000 + now_);
    parser_.push(from_bridge);
    Frame f;
    while (parser_.next(f)) on_frame(f);
  }
  physics(dt);
  telemetry();
  return out_;
}

void ScriptedAutopilot::start_flying(uint32_t custom_mode, double height_m, int64_t now_us) {
  now_ = last_step_ = now_us;
  mode_ = custom_mode;
  armed_ = true;
  landed_ = false;
  auto_armed_ = true;
  took_off_ = true;
  z_ = target_z_ = height_m;
  sub_ =
      c_.flavour == Flavour::kArdupilot && mode_ == copter_mode::kGuided ? Sub::kPos : Sub::kAngle;
  angle_update_ = now_us;
  offboard_signal_ = now_us;
  origin_set_ = true;
  ext_nav_ = now_us;
}

void ScriptedAutopilot::on_frame(const Frame& f) {
  dispatch(f, [&](const auto& m) {
    using M = std::decay_t<decltype(m)>;
    if constexpr (std::is_same_v<M, Heartbeat>) {
      // ArduPilot: only MAV_GCS_SYSID's heartbeat keeps its GCS failsafe quiet, from any
      // component (libraries/GCS_MAVLink/GCS_Common.cpp, handle_heartbeat).
      if (c_.flavour == Flavour::kArdupilot && f.sysid == c_.mav_gcs_sysid) {
        gcs_seen_ = now_;
        fs_gcs_ = false;
      }
    } else if constexpr (std::is_same_v<M, CommandLong>) {
      if (m.target_system == c_.sysid) on_command(m, f);
    } else if constexpr (std::is_same_v<M, SetAttitudeTarget>) {
      using namespace attitude_target_typemask;
      const bool roll = m.type_mask & kBodyRollRateIgnore,
                 pitch = m.type_mask & kBodyPitchRateIgnore, yaw = m.type_mask & kBodyYawRateIgnore;
      const bool att_ignored = m.type_mask & kAttitudeIgnore;
      if (c_.flavour == Flavour::kArdupilot) {
        // ArduCopter/GCS_MAVLink_Copter.cpp, handle_message_set_attitude_target: guided modes
        // only; thrust required; all three body rates or none; a unit quaternion.
        if (!guided()) return void(++attitude_ignored);
        if (m.type_mask & kThrottleIgnore) return void(++attitude_dropped);
        if (!(roll && pitch && yaw) && (roll || pitch || yaw)) return void(++attitude_dropped);
        const double n =
            std::sqrt(m.q[0] * m.q[0] + m.q[1] * m.q[1] + m.q[2] * m.q[2] + m.q[3] * m.q[3]);
        if (!att_ignored && std::abs(n - 1) > 1e-3) return void(++attitude_dropped);
        // ArduCopter/mode_guided.cpp: GUID_OPTIONS bit 3, thrust as thrust; else a climb rate
        // (0.5 holds) up to WPNAV_SPEED_UP 2.5 / WPNAV_SPEED_DN 1.5 m/s.
        use_thrust_ = (static_cast<long>(c_.guid_options) >> 3) & 1;
        thrust_ =
            use_thrust_ ? std::clamp<double>(m.thrust, -1, 1) : std::clamp<double>(m.thrust, 0, 1);
        angle_update_ = now_;
        sub_ = Sub::kAngle;
        ++attitude_used;
      } else {
        // src/modules/mavlink/mavlink_receiver.cpp, handle_message_set_attitude_target: rates
        // count only with both roll and pitch given; without thrust the message is dropped;
        // the setpoint is used only in OFFBOARD, the offboard signal in any mode.
        const bool rates = !roll && !pitch;
        const bool thrust = !(m.type_mask & kThrottleIgnore) || (m.type_mask & kThrustBodySet);
        if (!thrust || (att_ignored && !rates)) return void(++attitude_dropped);
        offboard_signal_ = now_;
        offboard_attitude_ = true;
        if (!in_offboard()) return;
        thrust_ = m.thrust;
        ++attitude_used;
      }
    } else if constexpr (std::is_same_v<M, SetPositionTargetLocalNed>) {
      const bool pos_given =
          !(m.type_mask & (position_target_typemask::kXIgnore | position_target_typemask::kYIgnore |
                           position_target_typemask::kZIgnore));
      const uint16_t accel_bits = m.type_mask & position_target_typemask::kAccelIgnore;
      if (c_.flavour == Flavour::kArdupilot) {
        // ArduCopter/GCS_MAVLink_Copter.cpp, handle_message_set_position_target_local_ned: guided
        // modes only, no armed or landed check; a position target switches the submode
        // (ModeGuided::set_destination), also out of a take-off.
        if (!guided() || !pos_given || m.coordinate_frame != mav_frame::kLocalNed) return;
        // Before the Guided rework (ArduCopter/GCS_Mavlink.cpp before 635d13a106, Copter 4.0):
        // "exit immediately if acceleration provided".
        // Any one of the acceleration's bits set ignores all three (acc_ignore).
        const bool accel_given = accel_bits == 0;
        if (accel_given && c_.flight_sw_version < 0x040100C0u) return void(++position_dropped);
        // Since: set_destination_posvelaccel, an ignored acceleration read as zero.
        target_accel_NED = std::array<float, 3>{0, 0, 0};
        if (accel_given) target_accel_NED = std::array<float, 3>{m.afx, m.afy, m.afz};
        target_z_ = -m.z;
        sub_ = Sub::kPos;
        ++position_used;
      } else {
        offboard_signal_ = now_;
        offboard_attitude_ = false;
        if (!in_offboard() || !pos_given) return;
        // src/modules/mavlink/mavlink_receiver.cpp: an ignored axis is NaN in the trajectory
        // setpoint, which the position controller's feed-forward skips.
        target_accel_NED.reset();
        if (accel_bits != position_target_typemask::kAccelIgnore)
          target_accel_NED = std::array<float, 3>{m.afx, m.afy, m.afz};
        target_z_ = -m.z;
        target_vz_down_ = (m.type_mask & position_target_typemask::kVzIgnore) ? 0.0 : m.vz;
        ++position_used;
      }
    } else if constexpr (std::is_same_v<M, Odometry>) {
      if (c_.flavour == Flavour::kArdupilot) {
        // libraries/GCS_MAVLink/GCS_Common.cpp, handle_odometry: LOCAL_FRD / BODY_FRD only; the
        // estimator type is not read.
        if (c_.viso_type == 1 && m.frame_id == mav_frame::kLocalFrd &&
            m.child_frame_id == mav_frame::kBodyFrd)
          ext_nav_ = now_;
      } else {
        // src/modules/mavlink/mavlink_receiver.cpp, handle_message_odometry: MOCAP goes to
        // vehicle_mocap_odometry, which EKF2 does not read.
        if (m.estimator_type != mav_estimator_type::kMocap && c_.ekf2_ev_ctrl != 0) ext_nav_ = now_;
      }
    } else if constexpr (std::is_same_v<M, AttPosMocap>) {
      // ArduPilot: external navigation (handle_att_pos_mocap); PX4: vehicle_mocap_odometry.
      if (c_.flavour == Flavour::kArdupilot && c_.viso_type == 1) ext_nav_ = now_;
    } else if constexpr (std::is_same_v<M, SetGpsGlobalOrigin>) {
      // ArduPilot refuses a second origin (GCS_Common.cpp, handle_set_gps_global_origin) and
      // answers a set one with GPS_GLOBAL_ORIGIN; PX4 streams GPS_GLOBAL_ORIGIN.
      if (m.latitude == 0 && m.longitude == 0) return;
      if (c_.flavour == Flavour::kArdupilot && origin_set_) return;
      origin_set_ = true;
      text("origin set");
      if (c_.flavour == Flavour::kArdupilot) {
        GpsGlobalOrigin o;
        o.latitude = m.latitude;
        o.longitude = m.longitude;
        o.altitude = m.altitude;
        send(o);
      }
    } else if constexpr (std::is_same_v<M, ParamRequestRead>) {
      bool found = false;
      const std::string name = param_id_string(m.param_id);
      const double v = param(name, &found);
      if (!found) return;  // no PARAM_VALUE for a name the autopilot does not have
      ParamValue p;
      set_param_id(p.param_id, name);
      const bool is_int = name != "COM_OF_LOSS_T" && name != "MPC_THR_HOVER" &&
                          name != "GUID_TIMEOUT" && name != "MOT_THST_HOVER" &&
                          name != "FS_GCS_TIMEOUT" && name != "COM_DISARM_LAND";
      p.param_type = is_int ? 6 : 9;
      if (c_.flavour == Flavour::kPx4 && is_int) {
        const auto i = static_cast<int32_t>(v);
        std::memcpy(&p.param_value, &i, sizeof i);  // PX4 sends INT32 bytewise
      } else {
        p.param_value = static_cast<float>(v);
      }
      send(p);
    }
  });
}

void ScriptedAutopilot::send_version() {
  AutopilotVersion v;
  v.flight_sw_version = c_.flight_sw_version;
  v.capabilities = 0x80;  // MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED, and more
  send(v);
  ++version_sent;
}

void ScriptedAutopilot::on_command(const CommandLong& c, const Frame& f) {
  uint8_t result = mav_result::kUnsupported;
  switch (c.command) {
    case mav_cmd::kDoSetMode: {
      const uint32_t mode = c_.flavour == Flavour::kArdupilot
                                ? static_cast<uint32_t>(c.param2)
                                : px4_mode::custom_mode(static_cast<uint8_t>(c.param2),
                                                        static_cast<uint8_t>(c.param3));
      result = set_mode(mode);
      break;
    }
    case mav_cmd::kComponentArmDisarm:
      result = arm(c.param1 == 1.0f, c.param2 == 21196.0f);
      break;
    case mav_cmd::kNavTakeoff:
      // ArduCopter/GCS_MAVLink_Copter.cpp handle_MAV_CMD_NAV_TAKEOFF, Mode::do_user_takeoff
      // (ArduCopter/takeoff.cpp): armed, landed, a mode with a user take-off, above the vehicle.
      if (c_.flavour == Flavour::kArdupilot && mode_ == copter_mode::kGuided && armed_ && landed_ &&
          c.param7 > z_) {
        sub_ = Sub::kTakeoff;
        target_z_ = c.param7;
        auto_armed_ = true;
        ++takeoffs;
        text("takeoff to " + std::to_string(c.param7) + " m");
        result = mav_result::kAccepted;
      } else {
        result = mav_result::kFailed;
      }
      break;
    case mav_cmd::kRequestMessage:
      if (!c_.request_message || static_cast<uint32_t>(c.param1) != AutopilotVersion::kId) break;
      ack(c.command, mav_result::kAccepted, f.sysid, f.compid);
      send_version();
      return;
    case mav_cmd::kRequestAutopilotCapabilities:
      if (c.param1 != 1) break;
      ack(c.command, mav_result::kAccepted, f.sysid, f.compid);
      send_version();
      return;
    case mav_cmd::kSetMessageInterval: {
      const auto id = static_cast<uint32_t>(c.param1);
      if (c_.flavour == Flavour::kArdupilot && id == HighresImu::kId && !c_.highres_imu) {
        // GCS_Common.cpp, set_message_interval: no ap_message for the id.
        result = mav_result::kDenied;
        text("No ap_message for mavlink id (105)");
        break;
      }
      if (c.param2 > 0) interval_us_[id] = static_cast<int64_t>(c.param2);
      if (c.param2 == -1) interval_us_.erase(id);
      result = mav_result::kAccepted;
      break;
    }
    default:
      break;
  }
  ack(c.command, result, f.sysid, f.compid);
}

uint8_t ScriptedAutopilot::set_mode(uint32_t mode) {
  if (c_.flavour == Flavour::kArdupilot) {
    // ArduCopter/mode.cpp, Copter::set_mode: GUIDED needs a position (requires_GPS,
    // position_ok); GUIDED_NOGPS and LAND do not.
    if (mode == copter_mode::kGuided && !local_position_valid()) {
      text("Flight mode change failed: requires position");
      return mav_result::kFailed;
    }
    if (mode == mode_) return mav_result::kAccepted;
    mode_ = mode;
    // ModeGuided::init holds where it is; ModeGuidedNoGPS::init levels with no climb.
    if (mode == copter_mode::kGuided) {
      sub_ = Sub::kPos;
      target_z_ = z_;
    } else if (mode == copter_mode::kGuidedNoGps) {
      sub_ = Sub::kAngle;
      use_thrust_ = false;
      thrust_ = 0.5;
      angle_update_ = now_;
    } else {
      sub_ = Sub::kNone;
    }
    text("mode " + mode_name(c_.flavour, mode));
    return mav_result::kAccepted;
  }
  // PX4 (src/modules/commander/Commander.cpp, UserModeIntention::change): any mode while
  // disarmed; armed, OFFBOARD only with the offboard signal (offboardCheck.cpp).
  if (armed_ && px4_mode::main_mode(mode) == px4_mode::kOffboard &&
      now_ - offboard_signal_ > c_.com_of_loss_t * 1e6)
    return mav_result::kTemporarilyRejected;
  mode_ = mode;
  if (px4_mode::main_mode(mode) == px4_mode::kOffboard) target_z_ = z_;
  text("mode " + mode_name(c_.flavour, mode));
  return mav_result::kAccepted;
}

uint8_t ScriptedAutopilot::arm(bool on, bool forced) {
  if (on) {
    if (armed_) return mav_result::kAccepted;
    if (c_.flavour == Flavour::kArdupilot) {
      // Mode::allows_arming (ArduCopter/mode.h: LAND false; GUIDED from a GCS); GUIDED needs
      // a position estimate (AP_Arming_Copter::mandatory_gps_checks).
      if (mode_ == copter_mode::kLand) return mav_result::kFailed;
      if (mode_ == copter_mode::kGuided && !local_position_valid()) return mav_result::kFailed;
      auto_armed_ = false;
    } else {
      // PX4: OFFBOARD cannot run without its signal (offboardCheck.cpp): arming refused.
      if (in_offboard() && now_ - offboard_signal_ > c_.com_of_loss_t * 1e6)
        return mav_result::kTemporarilyRejected;
      took_off_ = false;
    }
    armed_ = true;
    landed_ = true;
    disarm_timer_s_ = 0;
    ++arms;
    text("Arming motors");
    return mav_result::kAccepted;
  }
  if (!armed_) return mav_result::kAccepted;
  if (!forced && !landed_) {
    // ArduCopter/AP_Arming_Copter.cpp disarm: not via MAVLink while !land_complete (FAILED);
    // PX4 Commander::disarm: "Disarming denied: not landed" (TEMPORARILY_REJECTED).
    ++refused_disarms;
    return c_.flavour == Flavour::kArdupilot ? mav_result::kFailed
                                             : mav_result::kTemporarilyRejected;
  }
  if (forced) ++forced_disarms;
  disarm(forced ? "forced disarm" : "disarm");
  return mav_result::kAccepted;
}

void ScriptedAutopilot::disarm(const std::string& why) {
  armed_ = false;
  auto_armed_ = false;
  spool_s_ = 0;
  text("Disarming motors (" + why + ")");
}

double ScriptedAutopilot::estimate_up_m() const {
  return z_ + c_.estimate_offset_up_m + (landed_ ? 0.0 : c_.estimate_offset_in_air_up_m);
}

void ScriptedAutopilot::physics(double dt) {
  if (dt <= 0) return;
  double vz_cmd = 0;
  bool hold_ground = true;  // motors at idle on the ground (or off)
  if (c_.flavour == Flavour::kArdupilot) {
    // GCS failsafe (ArduCopter/events.cpp, failsafe_gcs_check / failsafe_gcs_on_event): only
    // after the GCS was seen; disarmed: nothing; landed in GUIDED: disarm; else the action.
    if (c_.fs_gcs_enable > 0 && gcs_seen_ > 0 && !fs_gcs_ &&
        now_ - gcs_seen_ > c_.fs_gcs_timeout_s * 1e6) {
      fs_gcs_ = true;
      if (armed_) {
        ++fs_gcs_triggers;
        if (landed_ && guided()) {
          disarm("GCS failsafe on the ground");
        } else if (c_.fs_gcs_enable == 5) {
          mode_ = copter_mode::kLand;
          text("GCS Failsafe: LAND");
        }
      }
    }
    if (armed_ && guided() && sub_ == Sub::kAngle) {
      // ArduCopter/mode_guided.cpp, angle_control_run.
      double climb = 0;
      bool thrust_mode = use_thrust_;
      if (now_ - angle_update_ > c_.guid_timeout_s * 1e6) {
        thrust_mode = false;  // timed out: level, no climb
      } else if (!use_thrust_) {
        climb = thrust_ >= 0.5 ? (thrust_ - 0.5) * 2 * 2.5 : (thrust_ - 0.5) * 2 * 1.5;
      }
      const bool positive = thrust_mode ? thrust_ > 0 : climb > 0;
      if (positive) auto_armed_ = true;
      if (auto_armed_ && !(landed_ && !positive)) {
        if (landed_) {
          spool_s_ += dt;
          if (spool_s_ >= kSpoolS) landed_ = false;
        } else {
          hold_ground = false;
          if (thrust_mode) {
            vz_ += kG * (thrust_ / c_.mot_thst_hover - 1.0) * dt;
            vz_cmd = vz_;
          } else {
            vz_cmd = climb;
          }
        }
      }
    } else if (armed_ && guided() && sub_ == Sub::kPos) {
      // pos_control_run: nothing while is_disarmed_or_landed() (ArduCopter/mode.cpp); it flies
      // its estimate to the target.
      if (auto_armed_ && !landed_) {
        hold_ground = false;
        vz_cmd = std::clamp(target_z_ - estimate_up_m(), -kClimb, kClimb);
      }
    } else if (armed_ && mode_ == copter_mode::kGuided && sub_ == Sub::kTakeoff) {
      // Mode::do_user_takeoff: the altitude above home, home where it armed.
      if (landed_) {
        spool_s_ += dt;
        if (spool_s_ >= kSpoolS) landed_ = false;
      } else {
        hold_ground = false;
        vz_cmd = std::clamp(target_z_ - z_, -kClimb, kClimb);
      }
    } else if (armed_ && mode_ == copter_mode::kLand) {
      // ArduCopter/mode_land.cpp: descends, disarms once landed.
      if (landed_) {
        disarm("LAND: landed");
      } else {
        hold_ground = false;
        vz_cmd = -kCopterLandSpeed;
      }
    }
    // DISARM_DELAY (ArduCopter/motors.cpp, auto_disarm_check): armed, landed, motors at idle.
    if (armed_ && landed_ && spool_s_ == 0) {
      disarm_timer_s_ += dt;
      if (disarm_timer_s_ >= c_.disarm_delay_s) disarm("DISARM_DELAY");
    } else {
      disarm_timer_s_ = 0;
    }
  } else {
    // PX4: offboard loss (src/modules/commander/failsafe/failsafe.cpp): COM_OBL_RC_ACT after
    // COM_OF_LOSS_T; without RC Position / Altitude / Stabilized fall back to Return.
    if (armed_ && in_offboard() && now_ - offboard_signal_ > c_.com_of_loss_t * 1e6) {
      ++offboard_losses;
      const int act = static_cast<int>(c_.com_obl_rc_act);
      mode_ = act == 4   ? px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kLand)
              : act == 5 ? px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kLoiter)
                         : px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kRtl);
      text("Failsafe: offboard lost, " + mode_name(c_.flavour, mode_));
    }
    if (armed_ && in_offboard()) {
      if (offboard_attitude_) {
        const double az = kG * (thrust_ / c_.mpc_thr_hover - 1.0);
        if (!landed_ || az > 0) {
          landed_ = false;
          hold_ground = false;
          vz_ += az * dt;
          vz_cmd = vz_;
        }
      } else {
        // mc_pos_control flies EKF2's estimate to the target.
        vz_cmd = std::clamp(target_z_ - estimate_up_m(), -kClimb, kClimb);
        if (!landed_ || vz_cmd > 0) {
          landed_ = false;
          hold_ground = false;
        }
      }
    } else if (armed_ && !landed_ &&
               (is_land_mode(c_.flavour, mode_) ||
                mode_ == px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kRtl))) {
      hold_ground = false;
      vz_cmd = -kPx4LandSpeed;
    } else if (armed_ && !landed_) {
      hold_ground = false;  // Hold
    }
    if (!landed_) took_off_ = true;
    // Commander::handleAutoDisarm: COM_DISARM_LAND after landing, COM_DISARM_PRFLT (+1 s of
    // spool-up) without a take-off.
    if (armed_ && landed_) {
      disarm_timer_s_ += dt;
      const double limit = took_off_ ? c_.com_disarm_land_s : 1.0 + c_.com_disarm_prflt_s;
      if (disarm_timer_s_ >= limit) disarm(took_off_ ? "landing" : "auto preflight disarming");
    } else {
      disarm_timer_s_ = 0;
    }
  }
  if (!armed_) {
    vz_cmd = z_ > 0 ? vz_ - kG * dt : 0;  // falls
    hold_ground = z_ <= 0;
  }
  if (hold_ground && z_ <= 0) {
    vz_ = 0;
  } else {
    vz_ = vz_cmd;
    z_ += vz_ * dt;
  }
  // PX4 flying a position or velocity target (climb-rate control): ground contact only under a
  // commanded descent faster than 1.1 LNDMC_Z_VEL_MAX (MulticopterLandDetector.cpp,
  // _get_ground_contact_state: "ground contact requires commanded descent until landed").
  const bool climb_rate_control =
      c_.flavour == Flavour::kPx4 && armed_ && in_offboard() && !offboard_attitude_;
  const bool contact_possible = !climb_rate_control || target_vz_down_ >= 1.1 * kLndmcZVelMax;
  if (z_ <= 0) {
    z_ = 0;
    vz_ = std::max(0.0, vz_);
    if (!landed_ && !contact_possible) land_timer_s_ = 0;
    if (!landed_ && contact_possible) {
      land_timer_s_ += dt;
      if (land_timer_s_ >= kLandDetectS) {
        landed_ = true;
        spool_s_ = 0;
        text("Landed");
      }
    }
  } else {
    land_timer_s_ = 0;
  }
}

void ScriptedAutopilot::telemetry() {
  if (now_ >= next_heartbeat_) {
    Heartbeat hb;
    hb.type = mav_type::kQuadrotor;
    hb.autopilot =
        c_.flavour == Flavour::kArdupilot ? mav_autopilot::kArdupilotmega : mav_autopilot::kPx4;
    hb.base_mode = mav_mode_flag::kCustomModeEnabled | (armed_ ? mav_mode_flag::kSafetyArmed : 0);
    hb.custom_mode = mode_;
    // ArduCopter: STANDBY while land_complete (GCS_MAVLink_Copter.cpp, vehicle_system_status);
    // PX4: ACTIVE when armed.
    if (c_.flavour == Flavour::kArdupilot)
      hb.system_status = landed_ ? mav_state::kStandby : mav_state::kActive;
    else
      hb.system_status = armed_ ? mav_state::kActive : mav_state::kStandby;
    send(hb);
    next_heartbeat_ = now_ + 1'000'000;
  }
  for (const auto& [id, interval] : interval_us_) {
    int64_t& next = next_send_[id];
    if (now_ < next) continue;
    next = now_ + interval;
    const auto boot_ms = static_cast<uint32_t>(now_ / 1000);
    switch (id) {
      case HighresImu::kId:
        if (c_.flavour == Flavour::kArdupilot && !c_.highres_imu) break;
        {
          HighresImu m;
          m.time_usec = static_cast<uint64_t>(now_);
          m.zacc = static_cast<float>(-kG);
          send(m);
        }
        break;
      case ScaledImu::kId: {
        ScaledImu m;
        m.time_boot_ms = boot_ms;
        m.zacc = -1000;
        send(m);
        break;
      }
      case AttitudeQuaternion::kId: {
        AttitudeQuaternion m;
        m.time_boot_ms = boot_ms;
        send(m);
        break;
      }
      case LocalPositionNed::kId:
        if (local_position_valid()) {
          LocalPositionNed m;
          m.time_boot_ms = boot_ms;
          m.z = static_cast<float>(-estimate_up_m());
          m.vz = static_cast<float>(-vz_);
          send(m);
        }
        break;
      case ExtendedSysState::kId: {
        ExtendedSysState m;
        m.landed_state = landed_state();
        send(m);
        break;
      }
      case GpsGlobalOrigin::kId:
        if (origin_set_) send(GpsGlobalOrigin{});
        break;
      default:
        break;
    }
  }
}

}  // namespace alight::mavlink::testing

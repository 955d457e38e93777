#include "mavlink/bridge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "mavlink/ned_frd.hpp"

namespace alight::mavlink {

namespace {

constexpr int64_t kHeartbeatPeriodUs = 1'000'000;
/// A stamp this large is Unix time (after 2001-09-09), smaller ones are time since boot
/// (HIGHRES_IMU.time_usec: "the receiving end can infer timestamp format ... by checking for the
/// magnitude of the number").
constexpr uint64_t kUnixEpochThresholdUs = 1'000'000'000'000'000ull;
/// A Unix-stamped sample further than this from our wall clock is refused: a simulated
/// autopilot may run seconds behind real time, an unset clock is decades off.
constexpr int64_t kMaxUnixSkewUs = 600'000'000;
/// The boot clock jumping back more than this is a reboot, not reordering.
constexpr int64_t kRebootJumpUs = 1'000'000;
/// The smallest-delay offset may rise this fast [us per us]: a crystal drifts by 1e-4, but a SITL
/// on a loaded machine runs its clock slower than the wall clock (PX4 SIH's lockstep clock ran
/// at 0.93 of it), and with 1e-4 its IMU stamps fell seconds behind motion capture's within a
/// minute. A single late sample still leaves no mark: the offset is the smallest over the last
/// few samples.
constexpr double kDriftAllowance = 0.1;
/// Plausible telemetry: beyond these an IMU or estimate is broken, not flying.
constexpr double kMaxAccelMps2 = 2000, kMaxGyroRadps = 100, kMaxPositionM = 1e5,
                 kMaxVelocityMps = 1e3;
/// After an accepted mode or arm command, the next heartbeat shows its effect; decide again
/// after it, or after this long without one.
constexpr int64_t kSettleUs = 1'500'000;
/// The autopilot's attitude is used for the heading while this fresh; then motion capture's.
constexpr int64_t kHeadingFreshUs = 500'000;
/// EXTENDED_SYS_STATE older than this says nothing about the landed state any more.
constexpr int64_t kLandedStateFreshUs = 3'000'000;
/// The stack's motors-off while the autopilot still reports the vehicle in the air: plain disarms
/// (refused in the air) this long, then LAND. Covers the autopilots' land detectors at a real
/// touch-down (ArduCopter: 1 s, ArduCopter/land_detector.cpp; PX4 maybe-landed then landed,
/// about 1.5 s, src/modules/land_detector/MulticopterLandDetector.cpp).
constexpr int64_t kInAirDisarmWaitUs = 2'000'000;
/// The stack's motors-off with the vehicle still armed in the offboard mode: the position target
/// keeps it pressed down where the stack last flew it, commanding this descent. PX4 counts ground
/// contact, and so a landing it will disarm on, only under a commanded descent faster than
/// 1.1 x LNDMC_Z_VEL_MAX (0.25 m/s; src/modules/land_detector/MulticopterLandDetector.cpp,
/// _get_ground_contact_state); ArduCopter's LAND_SPEED is 0.5 m/s as well.
constexpr double kTouchdownPushMps = 0.5;
/// ArduCopter's NAV_TAKEOFF: at least this far above the vehicle (it refuses a target below it).
constexpr double kMinTakeoffAltM = 0.3;
/// Setpoints held after NAV_TAKEOFF until the autopilot reports the vehicle in the air; without a
/// landed state, until half the climb is done or this long has passed.
constexpr int64_t kTakeoffHoldMaxUs = 15'000'000;
/// An AUTOPILOT_VERSION request's answer: the acknowledgement's wait and retries, then the message.
constexpr int64_t kVersionWaitUs = 3'000'000;
/// HIGHRES_IMU asked and accepted, but none this long after: SCALED_IMU instead.
constexpr int64_t kHighresWaitUs = 3'000'000;
/// One parameter read: resent after this long, given up after kParamAttempts.
constexpr int64_t kParamTimeoutUs = 1'000'000;
constexpr int kParamAttempts = 3;
/// SET_GPS_GLOBAL_ORIGIN resent this often until GPS_GLOBAL_ORIGIN comes, at most this often.
constexpr int64_t kOriginPeriodUs = 2'000'000;
constexpr int kOriginAttempts = 10;
/// The offset of the autopilot's local frame from motion capture's: sampled while slower than
/// this, with a motion-capture pose at most this old, followed with this time constant, and
/// reported again when it moved this far.
constexpr double kFrameOffsetMaxSpeedMps = 0.1;
constexpr int64_t kFrameOffsetMocapAgeUs = 50'000;
constexpr double kFrameOffsetTauS = 2.0;
constexpr double kFrameOffsetReportM = 0.05;
/// In the air the offset is followed more slowly (the two poses' residual timing error averages
/// out over a few of the hover's oscillations; PX4 SIH's EKF2 heights drifted 2 to 5 cm from
/// motion capture's over tens of seconds after take-off), and never further than this from the
/// offset last measured on the ground (a glitch of either pose cannot move the setpoints far).
constexpr double kFrameOffsetAirTauS = 4.0;
constexpr double kFrameOffsetAirBoundM = 0.1;
/// Motion capture is moved to the local position's stamp by its velocity over at most this.
constexpr double kFrameOffsetMaxShiftS = 0.1;
/// PX4 counts as ready this long after its local position appeared.
constexpr int64_t kPx4ReadyUs = 2'000'000;
/// SCALED_IMU's units.
constexpr double kMilliG = 9.80665e-3, kMilliRad = 1e-3;

bool finite3(float a, float b, float c) {
  return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
}
std::string vector_text(const Vector3d& v) {
  char b[64];
  std::snprintf(b, sizeof b, "(%.3f, %.3f, %.3f)", v.x(), v.y(), v.z());
  return b;
}
bool within(float a, float b, float c, double limit) {
  return finite3(a, b, c) && std::abs(a) <= limit && std::abs(b) <= limit && std::abs(c) <= limit;
}

}  // namespace

const char* engage_state_name(EngageState s) {
  switch (s) {
    case EngageState::kNoLink:
      return "NO_LINK";
    case EngageState::kIdle:
      return "IDLE";
    case EngageState::kStreaming:
      return "STREAMING";
    case EngageState::kModeWait:
      return "MODE_WAIT";
    case EngageState::kArmWait:
      return "ARM_WAIT";
    case EngageState::kFlying:
      return "FLYING";
    case EngageState::kOverride:
      return "OVERRIDE";
    case EngageState::kOperator:
      return "OPERATOR";
    case EngageState::kTakeoff:
      return "TAKEOFF";
    case EngageState::kNoTakeover:
      return "NO_TAKEOVER";
    case EngageState::kLanding:
      return "LANDING";
    case EngageState::kCooldown:
      return "COOLDOWN";
  }
  return "?";
}

Bridge::Bridge(const BridgeParams& params, double hover_thrust_N,
               std::optional<SigningConfig> signing)
    : params_(params),
      flavour_(params.flavour()),
      control_(params.control_mode()),
      hover_thrust_N_(hover_thrust_N),
      parser_(ParserOptions{signing ? std::optional<SigningKey>(signing->key) : std::nullopt}),
      sender_(static_cast<uint8_t>(params.own_sysid), static_cast<uint8_t>(params.own_compid),
              signing) {
  params_.validate();
  if (!(hover_thrust_N > 0) || !std::isfinite(hover_thrust_N))
    throw ParamError("", "mass_kg", std::to_string(hover_thrust_N),
                     "the vehicle's weight must be > 0 N");
  reset_autopilot_state();
}

void Bridge::reset_autopilot_state() {
  last_boot_us_.reset();
  boot_offset_us_.reset();
  last_imu_utime_ = 0;
  q_NED_FRD_.reset();
  local_position_.reset();
  ext_state_.reset();
  frame_offset_NED_.reset();
  ground_offset_NED_.reset();
  local_position_since_us_.reset();
  pending_.reset();
  await_heartbeat_ = false;
  override_ = false;
  refuse_takeover_ = false;
  landing_asked_ = false;
  was_armed_in_fly_mode_ = false;
  engaged_stream_ = false;
  off_in_air_since_us_.reset();
  takeoff_accepted_ = false;
  highres_accepted_us_.reset();
  scaled_imu_asked_ = false;
  imu_source_.clear();
  origin_known_ = false;
  prearm_ok_ = false;
  origin_attempts_ = 0;
  next_origin_us_ = 0;
  firmware_.reset();
  version_asks_ = 0;
  next_version_ask_us_ = 0;
  intervals_to_ask_.clear();
  const std::pair<uint32_t, double> asks[] = {{HighresImu::kId, params_.imu_rate_hz},
                                              {AttitudeQuaternion::kId, params_.attitude_rate_hz},
                                              {LocalPositionNed::kId, params_.position_rate_hz},
                                              {ExtendedSysState::kId, params_.landed_state_rate_hz},
                                              {SysStatus::kId, params_.sys_status_rate_hz}};
  for (const auto& a : asks)
    if (a.second > 0) intervals_to_ask_.push_back(a);
  params_to_read_.clear();
  if (params_.check_params) {
    ParamContext c;
    c.flavour = flavour_;
    c.control = control_;
    c.own_sysid = params_.own_sysid;
    c.mocap = params_.mocap_message != "none";
    c.hover_thrust = params_.hover_thrust;
    for (auto& e : expected_params(c)) params_to_read_.push_back({std::move(e)});
  }
}

template <class M>
void Bridge::send(const M& m, const BridgeClock& now, BridgeOutput& out) {
  const FrameBytes f = sender_.pack(m, now.wall_us);
  out.link_bytes.insert(out.link_bytes.end(), f.bytes().begin(), f.bytes().end());
  ++stats_.frames_sent;
}

BridgeOutput Bridge::update(const BridgeInput& in, const BridgeClock& now) {
  BridgeOutput out;
  if (in.link_reopened) parser_.clear();
  if (!in.link_bytes.empty()) {
    parser_.observe_time(now.wall_us);
    parser_.push(in.link_bytes);
    Frame f;
    while (parser_.next(f)) handle_frame(f, now, out);
  }
  if (in.attitude) {
    attitude_ = in.attitude;
    attitude_rx_steady_us_ = now.steady_us;
    if (!in.attitude->armed) need_motors_off_ = false;
  }
  if (in.position) {
    position_ = in.position;
    position_rx_steady_us_ = now.steady_us;
    if (in.position->motors == Motors::kOn) last_on_z_m_ = in.position->p_W.z();
    if (in.position->motors != Motors::kOn) need_motors_off_ = false;
    if (in.position->motors == Motors::kKill && !in.position->kill_authorised)
      ++stats_.kills_refused;
  }
  if (in.mocap) {
    mocap_ = in.mocap;
    mocap_rx_steady_us_ = now.steady_us;
    forward_mocap(*in.mocap, now, out);
  }
  check_link(now, out);
  if (now.steady_us >= next_heartbeat_us_) {
    Heartbeat hb;
    hb.type = mav_type::kOnboardController;
    hb.autopilot = mav_autopilot::kInvalid;
    hb.system_status = mav_state::kActive;
    send(hb, now, out);
    next_heartbeat_us_ = now.steady_us + kHeartbeatPeriodUs;
  }
  stream(now, out);
  service_pending(now, out);
  decide_commands(now, out);
  service_params(now, out);
  service_origin(now, out);
  return out;
}

// --- From the autopilot ---------------------------------------------------------------------

void Bridge::handle_frame(const Frame& f, const BridgeClock& now, BridgeOutput& out) {
  if (f.msgid == Heartbeat::kId) {
    if (const auto hb = decode<Heartbeat>(f)) on_heartbeat(f, *hb, now, out);
    return;
  }
  if (!sysid_ || f.sysid != *sysid_ || f.compid != params_.target_compid) {
    ++stats_.foreign_frames;
    return;
  }
  dispatch(f, [&](const auto& m) {
    using M = std::decay_t<decltype(m)>;
    if constexpr (std::is_same_v<M, CommandAck>) {
      // Acknowledgements addressed to someone else (a ground station's command) are not ours.
      if ((m.target_system == 0 || m.target_system == params_.own_sysid) &&
          (m.target_component == 0 || m.target_component == params_.own_compid))
        on_ack(m, now, out);
    } else if constexpr (std::is_same_v<M, Timesync>) {
      if (m.tc1 == 0) {  // a request: answer with our clock [ns]
        Timesync r;
        r.tc1 = now.wall_us * 1000;
        r.ts1 = m.ts1;
        r.target_system = f.sysid;
        r.target_component = f.compid;
        send(r, now, out);
      }
    } else if constexpr (std::is_same_v<M, HighresImu>) {
      if (!within(m.xacc, m.yacc, m.zacc, kMaxAccelMps2) ||
          !within(m.xgyro, m.ygyro, m.zgyro, kMaxGyroRadps)) {
        ++stats_.rejected_values;
        return;
      }
      if (m.time_usec < kUnixEpochThresholdUs) on_boot_time(m.time_usec, out);
      const auto utime = wall_stamp(m.time_usec, now);
      if (!utime) {
        ++stats_.rejected_stamps;
        return;
      }
      if (imu_source_ != "HIGHRES_IMU") imu_source_ = "HIGHRES_IMU";
      on_imu(*utime, Vector3d(m.xacc, m.yacc, m.zacc), Vector3d(m.xgyro, m.ygyro, m.zgyro), out);
    } else if constexpr (std::is_same_v<M, ScaledImu>) {
      // Only when HIGHRES_IMU does not come: one IMU, one source.
      if (imu_source_ == "HIGHRES_IMU") return;
      on_boot_time(uint64_t{m.time_boot_ms} * 1000, out);
      const auto utime = wall_stamp(uint64_t{m.time_boot_ms} * 1000, now);
      if (!utime) {
        ++stats_.rejected_stamps;
        return;
      }
      imu_source_ = "SCALED_IMU";
      on_imu(*utime, Vector3d(m.xacc, m.yacc, m.zacc) * kMilliG,
             Vector3d(m.xgyro, m.ygyro, m.zgyro) * kMilliRad, out);
    } else if constexpr (std::is_same_v<M, AttitudeQuaternion>) {
      const auto q = quat_from_wxyz_float({m.q1, m.q2, m.q3, m.q4});
      if (!q || !within(m.rollspeed, m.pitchspeed, m.yawspeed, kMaxGyroRadps)) {
        ++stats_.rejected_values;
        return;
      }
      on_boot_time(uint64_t{m.time_boot_ms} * 1000, out);
      const auto utime = wall_stamp(uint64_t{m.time_boot_ms} * 1000, now);
      if (!utime) {
        ++stats_.rejected_stamps;
        return;
      }
      q_NED_FRD_ = *q;
      omega_FRD_ = Vector3d(m.rollspeed, m.pitchspeed, m.yawspeed);
      attitude_steady_us_ = now.steady_us;
      attitude_utime_ = *utime;
      AutopilotPose p;
      p.pose.utime = *utime;
      p.pose.q_WB = q_enu_flu_from_ned_frd(*q);
      p.pose.omega_B = flu_from_frd(omega_FRD_);
      if (local_position_ && now.steady_us - local_position_steady_us_ < 1'000'000) {
        const LocalPositionNed& lp = *local_position_;
        p.pose.p_W_B = enu_from_ned(Vector3d(lp.x, lp.y, lp.z));
        p.pose.v_W_B = enu_from_ned(Vector3d(lp.vx, lp.vy, lp.vz));
      } else {
        // ArduPilot sends no LOCAL_POSITION_NED before its EKF has an origin and an aiding
        // source (libraries/GCS_MAVLink/GCS_Common.cpp, send_local_position): the attitude is
        // still the autopilot's.
        const double nan = std::numeric_limits<double>::quiet_NaN();
        p.pose.p_W_B = Vector3d::Constant(nan);
        p.pose.v_W_B = Vector3d::Constant(nan);
        p.position_known = false;
      }
      out.autopilot_pose.push_back(p);
    } else if constexpr (std::is_same_v<M, LocalPositionNed>) {
      if (!within(m.x, m.y, m.z, kMaxPositionM) || !within(m.vx, m.vy, m.vz, kMaxVelocityMps)) {
        ++stats_.rejected_values;
        return;
      }
      on_boot_time(uint64_t{m.time_boot_ms} * 1000, out);
      if (!local_position_since_us_ || now.steady_us - local_position_steady_us_ > 1'000'000)
        local_position_since_us_ = now.steady_us;
      local_position_ = m;
      local_position_steady_us_ = now.steady_us;
      update_frame_offset(now, out);
    } else if constexpr (std::is_same_v<M, ExtendedSysState>) {
      if (m.landed_state > mav_landed_state::kLanding) {
        ++stats_.rejected_values;
        return;
      }
      ext_state_ = m;
      ext_state_steady_us_ = now.steady_us;
    } else if constexpr (std::is_same_v<M, GpsGlobalOrigin>) {
      if (!origin_known_)
        out.events.push_back(
            {false, "autopilot's local frame origin: " + std::to_string(m.latitude * 1e-7) + ", " +
                        std::to_string(m.longitude * 1e-7) + ", " +
                        std::to_string(m.altitude * 1e-3) + " m"});
      origin_known_ = true;
    } else if constexpr (std::is_same_v<M, ParamValue>) {
      on_param(m, out);
    } else if constexpr (std::is_same_v<M, AutopilotVersion>) {
      on_version(m, out);
    } else if constexpr (std::is_same_v<M, Statustext>) {
      last_statustext_ = statustext_string(m);
      out.events.push_back(
          {m.severity <= mav_severity::kWarning, "autopilot: " + last_statustext_});
    } else if constexpr (std::is_same_v<M, SysStatus>) {
      battery_V_ = m.voltage_battery == UINT16_MAX ? -1.0 : m.voltage_battery / 1000.0;
      // ArduPilot reports its pre-arm checks in MAV_SYS_STATUS_PREARM_CHECK
      // (libraries/GCS_MAVLink/GCS.cpp); PX4 sets that bit only when it can arm in the mode it is
      // in (src/modules/mavlink/streams/SYS_STATUS.hpp: not in Hold without a global position),
      // so its heartbeat's STANDBY is read instead (on_heartbeat).
      constexpr uint32_t kPrearmCheck = 0x10000000;
      if (flavour_ == Flavour::kArdupilot && (m.onboard_control_sensors_present & kPrearmCheck))
        set_prearm(m.onboard_control_sensors_health & kPrearmCheck, out);
    }
  });
}

void Bridge::update_frame_offset(const BridgeClock& now, BridgeOutput& out) {
  if (!params_.align_frames || !local_position_ || !mocap_ ||
      now.steady_us - mocap_rx_steady_us_ > kFrameOffsetMocapAgeUs)
    return;
  const bool on_ground = !heartbeat_ || !(heartbeat_->base_mode & mav_mode_flag::kSafetyArmed) ||
                         landed_state(now) == mav_landed_state::kOnGround;
  const LocalPositionNed& lp = *local_position_;
  const Vector3d p_lp(lp.x, lp.y, lp.z);
  if (on_ground) {
    // At rest the two poses agree whenever they were sampled.
    if (Vector3d(lp.vx, lp.vy, lp.vz).norm() > kFrameOffsetMaxSpeedMps) return;
    const Vector3d sample = p_lp - ned_from_enu(mocap_->p_W_B);
    follow_frame_offset(sample, kFrameOffsetTauS, now, out);
    ground_offset_NED_ = frame_offset_NED_;
    return;
  }
  // In the air: both at the local position's instant, and only about an offset measured at rest.
  if (!ground_offset_NED_) return;
  const auto stamp = wall_stamp(uint64_t{lp.time_boot_ms} * 1000, now);
  if (!stamp) return;
  const double shift_s =
      std::clamp((*stamp - mocap_->utime) * 1e-6, -kFrameOffsetMaxShiftS, kFrameOffsetMaxShiftS);
  const Vector3d mocap_NED = ned_from_enu(mocap_->p_W_B + mocap_->v_W_B * shift_s);
  Vector3d drift = p_lp - mocap_NED - *ground_offset_NED_;
  if (drift.norm() > kFrameOffsetAirBoundM) drift *= kFrameOffsetAirBoundM / drift.norm();
  follow_frame_offset(*ground_offset_NED_ + drift, kFrameOffsetAirTauS, now, out);
}

void Bridge::follow_frame_offset(const Vector3d& sample, double tau_s, const BridgeClock& now,
                                 BridgeOutput& out) {
  if (!frame_offset_NED_) {
    frame_offset_NED_ = sample;
    reported_offset_NED_ = sample;
    out.events.push_back(
        {false, "the autopilot's local frame (NED) is motion capture's offset by " +
                    vector_text(sample) + " m: position setpoints carry it"});
  } else {
    const double dt = std::max(0.0, (now.steady_us - frame_offset_steady_us_) * 1e-6);
    *frame_offset_NED_ += std::min(1.0, dt / tau_s) * (sample - *frame_offset_NED_);
    if ((*frame_offset_NED_ - reported_offset_NED_).norm() > kFrameOffsetReportM) {
      reported_offset_NED_ = *frame_offset_NED_;
      out.events.push_back({true, "the autopilot's local frame moved: now offset by " +
                                      vector_text(*frame_offset_NED_) + " m"});
    }
  }
  frame_offset_steady_us_ = now.steady_us;
}

void Bridge::set_prearm(bool ok, BridgeOutput& out) {
  if (ok && !prearm_ok_) out.events.push_back({false, "autopilot: pre-arm checks pass"});
  if (!ok && prearm_ok_) out.events.push_back({true, "autopilot: pre-arm checks fail"});
  prearm_ok_ = ok;
}

void Bridge::on_imu(int64_t utime, const Vector3d& accel_FRD, const Vector3d& gyro_FRD,
                    BridgeOutput& out) {
  if (utime <= last_imu_utime_) {
    ++stats_.rejected_stamps;
    return;
  }
  last_imu_utime_ = utime;
  ImuOut s;
  s.utime = utime;
  s.accel_B = flu_from_frd(accel_FRD);
  s.gyro_B = flu_from_frd(gyro_FRD);
  out.imu.push_back(s);
  ++stats_.imu_out;
}

void Bridge::on_param(const ParamValue& m, BridgeOutput& out) {
  if (params_to_read_.empty()) return;
  const std::string name = param_id_string(m.param_id);
  ParamRead& r = params_to_read_.front();
  if (name != r.expect.name) return;  // another's read, or a late duplicate
  const double v = param_number(flavour_, m);
  if (!r.expect.ok(v)) {
    ++stats_.param_problems;
    out.events.push_back({true, "autopilot parameter " + name + " = " + std::to_string(v) +
                                    ", alight needs " + r.expect.want + ": " + r.expect.why});
  }
  params_to_read_.erase(params_to_read_.begin());
}

void Bridge::on_version(const AutopilotVersion& m, BridgeOutput& out) {
  const auto v = FirmwareVersion::from_flight_sw_version(m.flight_sw_version);
  if (firmware_ == v) return;
  firmware_ = v;
  out.events.push_back(
      {false, "autopilot firmware " + v.str() +
                  (accel_feedforward() ? ": position targets carry the feed-forward acceleration"
                                       : ": position targets without acceleration (not known to "
                                         "be taken by this version)")});
}

void Bridge::on_heartbeat(const Frame& f, const Heartbeat& m, const BridgeClock& now,
                          BridgeOutput& out) {
  // Ground stations, cameras and other companions send heartbeats too; only the autopilot's count.
  const bool is_autopilot = m.autopilot != mav_autopilot::kInvalid && m.type != mav_type::kGcs &&
                            f.compid == params_.target_compid &&
                            (params_.target_sysid == 0 || f.sysid == params_.target_sysid);
  if (!is_autopilot || (sysid_ && f.sysid != *sysid_)) {
    ++stats_.foreign_frames;
    return;
  }
  if (!sysid_) {
    sysid_ = f.sysid;
    out.events.push_back({false, "autopilot: system " + std::to_string(f.sysid) + ", " +
                                     (m.autopilot == mav_autopilot::kPx4 ? "PX4"
                                      : m.autopilot == mav_autopilot::kArdupilotmega
                                          ? "ArduPilot"
                                          : "MAV_AUTOPILOT " + std::to_string(m.autopilot))});
  }
  ++stats_.heartbeats;
  const bool armed = m.base_mode & mav_mode_flag::kSafetyArmed;
  if (heartbeat_ && (heartbeat_->custom_mode != m.custom_mode ||
                     bool(heartbeat_->base_mode & mav_mode_flag::kSafetyArmed) != armed))
    out.events.push_back({false, "autopilot: " + mode_name(flavour_, m.custom_mode) +
                                     (armed ? ", armed" : ", disarmed")});
  heartbeat_ = m;
  last_heartbeat_steady_ = now.steady_us;
  await_heartbeat_ = false;
  // PX4 reports its pre-flight checks for the mode it is in (HEARTBEAT STANDBY,
  // src/modules/mavlink/streams/HEARTBEAT.hpp; SYS_STATUS's PREARM_CHECK bit): without GPS they
  // fail for want of a global position, which OFFBOARD does not need, and OFFBOARD itself cannot
  // pass before the setpoints stream. Ready here means a local position from its estimator for
  // kPx4ReadyUs, what OFFBOARD needs (commander/HealthAndArmingChecks/checks/offboardCheck.cpp).
  if (flavour_ == Flavour::kPx4)
    set_prearm(armed || (local_position_since_us_ &&
                         now.steady_us - *local_position_since_us_ >= kPx4ReadyUs &&
                         now.steady_us - local_position_steady_us_ < 1'000'000),
               out);
  const bool in_fly = is_fly_mode(flavour_, control_, m.custom_mode);
  if (!link_up_) {
    link_up_ = true;
    out.events.push_back({false, "link up: " + mode_name(flavour_, m.custom_mode) +
                                     (armed ? ", armed" : ", disarmed")});
    if (armed) {
      // Whoever armed it, it was not this bridge (a restart, or the link was down): alight does
      // not take a flying vehicle back without the operator.
      override_ = true;
      flew_ = true;
      if (in_fly) {
        refuse_takeover_ = true;
        ++stats_.takeover_refused;
        out.events.push_back({true, "found the vehicle armed in " +
                                        mode_name(flavour_, m.custom_mode) +
                                        ": alight will not take it back; asking for LAND"});
      }
    }
    was_armed_ = armed;
  }
  if (armed && !was_armed_) {  // armed now: a new flight
    flew_ = false;
    takeoff_done_ = false;
    takeoff_accepted_ = false;
    disarmed_at_us_.reset();
  }
  if (!armed && was_armed_) {
    disarmed_at_us_ = now.steady_us;
    last_on_z_m_.reset();  // a touch-down's height is this flight's, not the next one's
    if (flew_ || !ext_state_) need_motors_off_ = true;
    out.events.push_back(
        {false, std::string("disarmed") +
                    (need_motors_off_ ? ": no ARM before the stack's motors off" : "") + " and " +
                    std::to_string(params_.rearm_cooldown_s) + " s of cool-down"});
  }
  was_armed_ = armed;
  if (!armed) {
    override_ = false;
    refuse_takeover_ = false;
    landing_asked_ = false;
    engaged_stream_ = false;
  } else if (was_armed_in_fly_mode_ && !in_fly && !override_) {
    override_ = true;
    out.events.push_back({true, "autopilot left " +
                                    mode_name(flavour_, fly_custom_mode(flavour_, control_)) +
                                    " for " + mode_name(flavour_, m.custom_mode) +
                                    " while armed (pilot or failsafe): alight will not take it "
                                    "back before the vehicle is disarmed"});
  }
  if (!in_fly) {
    refuse_takeover_ = false;
    landing_asked_ = false;
  }
  was_armed_in_fly_mode_ = armed && in_fly;
  // ArduCopter without EXTENDED_SYS_STATE: STANDBY while landed (ArduCopter/GCS_MAVLink_Copter.cpp,
  // vehicle_system_status).
  if (armed && in_air(now)) flew_ = true;
}

void Bridge::on_boot_time(uint64_t boot_us, BridgeOutput& out) {
  if (last_boot_us_ &&
      static_cast<int64_t>(boot_us) < static_cast<int64_t>(*last_boot_us_) - kRebootJumpUs) {
    ++stats_.reboots;
    out.events.push_back({true, "autopilot rebooted (its boot time went back)"});
    const auto hb = heartbeat_;
    reset_autopilot_state();
    heartbeat_ = hb;
  }
  if (!last_boot_us_ || boot_us > *last_boot_us_) last_boot_us_ = boot_us;
}

std::optional<int64_t> Bridge::wall_stamp(uint64_t autopilot_us, const BridgeClock& now) {
  if (autopilot_us >= kUnixEpochThresholdUs) {
    if (autopilot_us > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return {};
    const auto t = static_cast<int64_t>(autopilot_us);
    if (t > now.wall_us + kMaxUnixSkewUs || t < now.wall_us - kMaxUnixSkewUs) return {};
    return t;
  }
  // Boot time: the receipt delay is at least zero, so wall - boot at its smallest is the offset
  // (plus the smallest transport delay). Allowed to rise slowly for the clocks' drift.
  const int64_t sample = now.wall_us - static_cast<int64_t>(autopilot_us);
  if (!boot_offset_us_) {
    boot_offset_us_ = sample;
  } else {
    const double elapsed = static_cast<double>(now.steady_us - boot_offset_steady_us_);
    const int64_t drifted = *boot_offset_us_ + static_cast<int64_t>(kDriftAllowance * elapsed);
    boot_offset_us_ = std::min(drifted, sample);
  }
  boot_offset_steady_us_ = now.steady_us;
  return static_cast<int64_t>(autopilot_us) + *boot_offset_us_;
}

void Bridge::on_ack(const CommandAck& m, const BridgeClock& now, BridgeOutput& out) {
  if (!pending_ || pending_->cmd.command != m.command) {
    ++stats_.acks_unexpected;
    return;
  }
  if (m.result == mav_result::kInProgress) {
    pending_->sent_steady_us = now.steady_us;  // the autopilot is working on it
    return;
  }
  command_finished(m.result == mav_result::kAccepted, m.result, now, out);
}

// --- The link and the stream ----------------------------------------------------------------

void Bridge::check_link(const BridgeClock& now, BridgeOutput& out) {
  if (!link_up_) return;
  if (now.steady_us - last_heartbeat_steady_ <= params_.heartbeat_timeout_s * 1e6) return;
  link_up_ = false;
  ++stats_.link_losses;
  out.events.push_back(
      {true, "link lost: no HEARTBEAT for " + std::to_string(params_.heartbeat_timeout_s) + " s"});
  // Whatever comes back (the same autopilot, or one that rebooted) starts from scratch; the
  // heartbeat is kept for the status page, marked stale by its age.
  const auto hb = heartbeat_;
  reset_autopilot_state();
  heartbeat_ = hb;
}

bool Bridge::setpoint_fresh(const BridgeClock& now) const {
  const int64_t limit = static_cast<int64_t>(params_.setpoint_timeout_s * 1e6);
  if (control_ == ControlMode::kAttitude)
    return attitude_ && now.steady_us - attitude_rx_steady_us_ <= limit;
  return position_ && now.steady_us - position_rx_steady_us_ <= limit;
}

bool Bridge::stack_wants_armed(const BridgeClock& now) const {
  if (!setpoint_fresh(now)) return false;
  return control_ == ControlMode::kAttitude ? attitude_->armed : position_->motors == Motors::kOn;
}

bool Bridge::authorised_kill(const BridgeClock& now) const {
  // A KILL is obeyed whichever setpoints the bridge streams: the operator's signed command.
  const int64_t limit = static_cast<int64_t>(params_.setpoint_timeout_s * 1e6);
  if (position_ && position_->motors == Motors::kKill && position_->kill_authorised &&
      now.steady_us - position_rx_steady_us_ <= limit)
    return true;
  return attitude_ && !attitude_->armed && attitude_->kill_authorised &&
         now.steady_us - attitude_rx_steady_us_ <= limit;
}

uint8_t Bridge::landed_state(const BridgeClock& now) const {
  if (ext_state_ && now.steady_us - ext_state_steady_us_ <= kLandedStateFreshUs)
    return ext_state_->landed_state;
  if (flavour_ == Flavour::kArdupilot && heartbeat_ &&
      (heartbeat_->base_mode & mav_mode_flag::kSafetyArmed)) {
    if (heartbeat_->system_status == mav_state::kStandby) return mav_landed_state::kOnGround;
    if (heartbeat_->system_status == mav_state::kActive) return mav_landed_state::kInAir;
  }
  return mav_landed_state::kUndefined;
}

bool Bridge::in_air(const BridgeClock& now) const {
  const uint8_t s = landed_state(now);
  return s == mav_landed_state::kInAir || s == mav_landed_state::kTakeoff ||
         s == mav_landed_state::kLanding;
}

std::optional<double> Bridge::heading_enu(const BridgeClock& now) const {
  if (q_NED_FRD_ && now.steady_us - attitude_steady_us_ <= kHeadingFreshUs)
    return yaw_of(q_enu_flu_from_ned_frd(*q_NED_FRD_).toRotationMatrix());
  if (mocap_ && now.steady_us - mocap_rx_steady_us_ <= kHeadingFreshUs)
    return yaw_of(mocap_->q_WB.toRotationMatrix());
  return std::nullopt;
}

std::optional<double> Bridge::height_up(const BridgeClock& now) const {
  // In the setpoints' frame (motion capture's): the autopilot's own height only less its offset.
  if (mocap_ && now.steady_us - mocap_rx_steady_us_ <= 1'000'000) return mocap_->p_W_B.z();
  if (local_position_ && now.steady_us - local_position_steady_us_ <= 1'000'000)
    return -(static_cast<double>(local_position_->z) -
             frame_offset_NED_.value_or(Vector3d::Zero()).z());
  return std::nullopt;
}

bool Bridge::accel_feedforward() const {
  return firmware_ && takes_position_target_accel(flavour_, *firmware_);
}

bool Bridge::hold_setpoints() const {
  if (!heartbeat_) return false;
  const bool armed = heartbeat_->base_mode & mav_mode_flag::kSafetyArmed;
  const bool in_fly = is_fly_mode(flavour_, control_, heartbeat_->custom_mode);
  // Not this bridge's vehicle to fly; or ArduCopter climbing on NAV_TAKEOFF, which the first
  // position target would cut short while it still counts as landed (ArduCopter/mode_guided.cpp:
  // pos_control_run does nothing while is_disarmed_or_landed()). Held from the command's sending,
  // not its ACK: a target sent while the ACK is on its way arrives after the take-off began.
  const bool takeoff_pending = pending_ && pending_->cmd.command == mav_cmd::kNavTakeoff;
  return (refuse_takeover_ && armed && in_fly) ||
         ((takeoff_accepted_ || takeoff_pending) && armed && in_fly);
}

void Bridge::stream(const BridgeClock& now, BridgeOutput& out) {
  if (!link_up_ || !setpoint_fresh(now) || hold_setpoints()) {
    streaming_since_us_.reset();
    return;
  }
  if (now.steady_us < next_stream_us_) return;
  const auto period = static_cast<int64_t>(1e6 / params_.stream_rate_hz);
  next_stream_us_ = std::max(next_stream_us_ + period, now.steady_us + period / 2);
  const auto boot_ms = static_cast<uint32_t>(now.steady_us / 1000);
  if (control_ == ControlMode::kAttitude) {
    const AttitudeTarget& t = *attitude_;
    const auto heading = heading_enu(now);
    if (!heading) {
      ++stats_.setpoints_not_sent;
      return;
    }
    const double yaw = wrap_angle(*heading + t.yaw_rate_radps * params_.yaw_lead_s);
    const Quaterniond q_ENU_FLU(rotation_from_rpy(t.roll_rad, t.pitch_rad, yaw));
    SetAttitudeTarget m;
    m.time_boot_ms = boot_ms;
    m.target_system = *sysid_;
    m.target_component = static_cast<uint8_t>(params_.target_compid);
    m.q = wxyz_float(q_ned_frd_from_enu_flu(q_ENU_FLU));
    if (flavour_ == Flavour::kPx4) {
      // PX4 (src/modules/mavlink/mavlink_receiver.cpp, handle_message_set_attitude_target): the
      // body rates count only with both roll and pitch rates given; the yaw rate alone is the
      // heading's feed-forward (yaw_sp_move_rate).
      m.type_mask = attitude_target_typemask::kBodyRollRateIgnore |
                    attitude_target_typemask::kBodyPitchRateIgnore;
      m.body_yaw_rate = static_cast<float>(-t.yaw_rate_radps);  // FLU z up -> FRD z down
    } else {
      // ArduCopter (ArduCopter/GCS_MAVLink_Copter.cpp, handle_message_set_attitude_target):
      // all three body rates or none, anything else is dropped (and GUIDED reset to a stop).
      m.type_mask = attitude_target_typemask::kBodyRollRateIgnore |
                    attitude_target_typemask::kBodyPitchRateIgnore |
                    attitude_target_typemask::kBodyYawRateIgnore;
    }
    const double thrust = t.armed ? t.thrust_N / hover_thrust_N_ * params_.hover_thrust : 0.0;
    m.thrust = static_cast<float>(std::clamp(thrust, 0.0, 1.0));
    send(m, now, out);
  } else {
    const PositionTarget t = position_to_stream();
    // In the autopilot's local frame, which need not be motion capture's: ArduCopter SITL's EKF3
    // reported heights 0.2 m above the external navigation it fused, from before arming on.
    const Vector3d p = ned_from_enu(t.p_W) + frame_offset_NED_.value_or(Vector3d::Zero());
    const Vector3d v = ned_from_enu(t.v_W);
    SetPositionTargetLocalNed m;
    m.time_boot_ms = boot_ms;
    m.target_system = *sysid_;
    m.target_component = static_cast<uint8_t>(params_.target_compid);
    m.coordinate_frame = mav_frame::kLocalNed;
    m.type_mask = 0;
    if (accel_feedforward()) {
      const Vector3d a = ned_from_enu(t.a_W);
      m.afx = static_cast<float>(a.x());
      m.afy = static_cast<float>(a.y());
      m.afz = static_cast<float>(a.z());
    } else {
      m.type_mask |= position_target_typemask::kAccelIgnore;
    }
    m.x = static_cast<float>(p.x());
    m.y = static_cast<float>(p.y());
    m.z = static_cast<float>(p.z());
    m.vx = static_cast<float>(v.x());
    m.vy = static_cast<float>(v.y());
    m.vz = static_cast<float>(v.z());
    m.yaw = static_cast<float>(yaw_ned_from_enu(t.yaw_rad));
    m.yaw_rate = static_cast<float>(-t.yaw_rate_radps);  // about z up -> about z down
    send(m, now, out);
  }
  ++stats_.setpoints_sent;
  if (!streaming_since_us_) streaming_since_us_ = now.steady_us;
}

PositionTarget Bridge::position_to_stream() const {
  const bool armed = heartbeat_ && (heartbeat_->base_mode & mav_mode_flag::kSafetyArmed);
  if (position_->motors == Motors::kOn || !last_on_z_m_ || !armed) return *position_;
  // Motors off (a touch-down) while the autopilot still flies: the stack's target follows the
  // vehicle, at its height and with no descent, which holds it on the top at hover thrust, free
  // to slide. Sideways it stays the stack's (where the vehicle rests, riding a moving deck
  // along), but its height is never above the last MOTORS_ON target's and a descent is
  // commanded, pressing the vehicle down until the autopilot's land detector agrees and a
  // disarm is accepted.
  PositionTarget t = *position_;
  t.p_W.z() = std::min(*last_on_z_m_, position_->p_W.z());
  t.v_W.z() = -kTouchdownPushMps;
  t.a_W.setZero();
  return t;
}

void Bridge::forward_mocap(const PoseSample& pose, const BridgeClock& now, BridgeOutput& out) {
  if (params_.mocap_message == "none" || !link_up_) return;
  if (now.steady_us - mocap_sent_steady_us_ < static_cast<int64_t>(1e6 / params_.mocap_rate_hz))
    return;
  mocap_sent_steady_us_ = now.steady_us;
  const Vector3d p = ned_from_enu(pose.p_W_B);
  const auto q = wxyz_float(q_ned_frd_from_enu_flu(pose.q_WB));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (params_.mocap_message == "att_pos_mocap") {
    AttPosMocap m;
    m.time_usec = static_cast<uint64_t>(std::max<int64_t>(pose.utime, 0));
    m.q = q;
    m.x = static_cast<float>(p.x());
    m.y = static_cast<float>(p.y());
    m.z = static_cast<float>(p.z());
    m.covariance[0] = nan;  // unknown
    send(m, now, out);
  } else {
    Odometry m;
    m.time_usec = static_cast<uint64_t>(std::max<int64_t>(pose.utime, 0));
    // MAV_FRAME_LOCAL_FRD: what PX4's EKF2 (external vision) and ArduPilot's EKF3 (ExternalNav)
    // take; the room's NED-from-ENU axes are such a frame, whatever its heading to north.
    m.frame_id = mav_frame::kLocalFrd;
    m.child_frame_id = mav_frame::kBodyFrd;
    m.x = static_cast<float>(p.x());
    m.y = static_cast<float>(p.y());
    m.z = static_cast<float>(p.z());
    m.q = q;
    // The twist is in the child frame: the body's velocity and rates in FRD.
    const Vector3d v_B = frd_from_flu(pose.q_WB.conjugate() * pose.v_W_B);
    const Vector3d w_B = frd_from_flu(pose.omega_B);
    m.vx = static_cast<float>(v_B.x());
    m.vy = static_cast<float>(v_B.y());
    m.vz = static_cast<float>(v_B.z());
    m.rollspeed = static_cast<float>(w_B.x());
    m.pitchspeed = static_cast<float>(w_B.y());
    m.yawspeed = static_cast<float>(w_B.z());
    m.pose_covariance[0] = nan;
    m.velocity_covariance[0] = nan;
    // VISION, not MOCAP: PX4 routes MOCAP odometry to vehicle_mocap_odometry, which EKF2 does
    // not read (src/modules/mavlink/mavlink_receiver.cpp, handle_message_odometry); ArduPilot
    // ignores the type (libraries/GCS_MAVLink/GCS_Common.cpp, handle_odometry).
    m.estimator_type = mav_estimator_type::kVision;
    m.quality = 100;
    send(m, now, out);
  }
  ++stats_.mocap_sent;
}

// --- Commands ------------------------------------------------------------------------------

void Bridge::send_command(uint16_t command, const std::string& name, float p1, float p2, float p3,
                          const BridgeClock& now, BridgeOutput& out, float p7) {
  Pending p;
  p.cmd.target_system = *sysid_;
  p.cmd.target_component = static_cast<uint8_t>(params_.target_compid);
  p.cmd.command = command;
  p.cmd.param1 = p1;
  p.cmd.param2 = p2;
  p.cmd.param3 = p3;
  p.cmd.param7 = p7;
  p.name = name;
  p.attempts = 1;
  p.sent_steady_us = now.steady_us;
  send(p.cmd, now, out);
  ++stats_.commands_sent;
  last_command_ = name;
  pending_ = p;
}

void Bridge::request_land(const std::string& why, const BridgeClock& now, BridgeOutput& out) {
  const uint32_t land = land_custom_mode(flavour_);
  const SetModeParams m = set_mode_params(flavour_, land);
  ++stats_.lands_requested;
  out.events.push_back({true, "asking for " + mode_name(flavour_, land) + ": " + why});
  send_command(mav_cmd::kDoSetMode, "land", m.param1, m.param2, m.param3, now, out);
}

void Bridge::command_finished(bool ok, int result, const BridgeClock& now, BridgeOutput& out) {
  const std::string name = pending_->name;
  const uint16_t command = pending_->cmd.command;
  const auto interval_id = static_cast<uint32_t>(pending_->cmd.param1);
  last_result_ = result;
  pending_.reset();
  const bool housekeeping =
      name == "interval" || name == "origin request" || name == "version request";
  if (ok) {
    if (!housekeeping) {
      await_heartbeat_ = true;
      settle_until_us_ = now.steady_us + kSettleUs;
      out.events.push_back({false, name + ": accepted"});
    }
    if (name == "land") landing_asked_ = true;
    if (command == mav_cmd::kNavTakeoff) {
      takeoff_accepted_ = true;
      takeoff_accepted_us_ = now.steady_us;
    }
    if (name == "interval") {
      if (interval_id == HighresImu::kId) highres_accepted_us_ = now.steady_us;
      if (!intervals_to_ask_.empty()) intervals_to_ask_.erase(intervals_to_ask_.begin());
    }
    return;
  }
  ++stats_.commands_failed;
  backoff_until_us_ = now.steady_us + static_cast<int64_t>(params_.command_backoff_s * 1e6);
  if (housekeeping) {
    // An autopilot that cannot change a rate keeps its own; not worth asking again.
    if (name == "interval" && !intervals_to_ask_.empty()) {
      // ArduPilot boards with 1 MB of flash have no HIGHRES_IMU (libraries/GCS_MAVLink/
      // GCS_config.h, AP_MAVLINK_MSG_HIGHRES_IMU_ENABLED) and refuse its interval.
      if (interval_id == HighresImu::kId && !scaled_imu_asked_) {
        scaled_imu_asked_ = true;
        intervals_to_ask_.push_back({ScaledImu::kId, params_.imu_rate_hz});
      }
      intervals_to_ask_.erase(intervals_to_ask_.begin());
    }
    backoff_until_us_ = now.steady_us;
  }
  out.events.push_back(
      {!housekeeping, name + ": " +
                          (result < 0 ? std::string("no answer")
                                      : "refused, MAV_RESULT " + std::to_string(result))});
}

void Bridge::service_pending(const BridgeClock& now, BridgeOutput& out) {
  if (!pending_) return;
  if (!link_up_) {
    pending_.reset();
    return;
  }
  if (now.steady_us - pending_->sent_steady_us < params_.command_timeout_s * 1e6) return;
  if (pending_->attempts > params_.command_retries) {
    command_finished(false, -1, now, out);
    return;
  }
  ++pending_->attempts;
  pending_->cmd.confirmation = static_cast<uint8_t>(std::min(pending_->attempts - 1, 255));
  pending_->sent_steady_us = now.steady_us;
  send(pending_->cmd, now, out);
  ++stats_.commands_sent;
}

void Bridge::decide_commands(const BridgeClock& now, BridgeOutput& out) {
  if (!link_up_ || !heartbeat_) {
    engage_ = EngageState::kNoLink;
    return;
  }
  const bool armed = heartbeat_->base_mode & mav_mode_flag::kSafetyArmed;
  const bool in_fly = is_fly_mode(flavour_, control_, heartbeat_->custom_mode);
  const bool fresh = setpoint_fresh(now);
  const bool want_armed = stack_wants_armed(now);
  const bool streamed_enough = streaming_since_us_ && now.steady_us - *streaming_since_us_ >=
                                                          params_.offboard_warmup_s * 1e6;
  const bool cooling =
      disarmed_at_us_ && now.steady_us - *disarmed_at_us_ < params_.rearm_cooldown_s * 1e6;
  if (armed && in_fly && fresh && !refuse_takeover_) engaged_stream_ = true;
  if (armed && in_air(now)) flew_ = true;
  // The stack's motors-off while the autopilot says the vehicle flies: since when.
  if (armed && in_fly && fresh && !want_armed && in_air(now)) {
    if (!off_in_air_since_us_) off_in_air_since_us_ = now.steady_us;
  } else {
    off_in_air_since_us_.reset();
  }
  if (takeoff_accepted_) {
    const uint8_t ls = landed_state(now);
    const auto h = height_up(now);
    const bool up = ls == mav_landed_state::kInAir ||
                    (ls == mav_landed_state::kUndefined && h &&
                     *h - takeoff_start_up_m_ >= 0.5 * takeoff_alt_m_) ||
                    now.steady_us - takeoff_accepted_us_ > kTakeoffHoldMaxUs;
    if (up || !armed || !in_fly) {
      takeoff_accepted_ = false;
      if (up && armed) {
        takeoff_done_ = true;
        out.events.push_back({false, "in the air after NAV_TAKEOFF: position setpoints resume"});
      }
    }
  }

  // Armed in another mode: the pilot's, or the autopilot's failsafe (also one that flew while the
  // link was down, when the bridge could not see it leave).
  const bool hands_off = override_ || (armed && !in_fly);
  if (refuse_takeover_ && armed && in_fly)
    engage_ = EngageState::kNoTakeover;
  else if (landing_asked_ && armed)
    engage_ = EngageState::kLanding;
  else if (!params_.auto_engage())
    engage_ = EngageState::kOperator;
  else if (hands_off)
    engage_ = EngageState::kOverride;
  else if (armed && in_fly)
    engage_ = takeoff_accepted_ ? EngageState::kTakeoff : EngageState::kFlying;
  else if (!want_armed)
    engage_ = EngageState::kIdle;
  else if (!armed && (cooling || need_motors_off_))
    engage_ = EngageState::kCooldown;
  else if (!streamed_enough)
    engage_ = EngageState::kStreaming;
  else
    engage_ = in_fly ? EngageState::kArmWait : EngageState::kModeWait;

  if (pending_ || now.steady_us < backoff_until_us_) return;
  // The operator's KILL does not wait for a heartbeat to settle, nor for the mode.
  if (authorised_kill(now) && armed) {
    send_command(mav_cmd::kComponentArmDisarm, "force disarm", 0, kForceDisarmMagic, 0, now, out);
    return;
  }
  if (await_heartbeat_ && now.steady_us < settle_until_us_) return;
  await_heartbeat_ = false;
  if (decide_engage(now, out)) return;
  decide_housekeeping(now, out);
}

bool Bridge::decide_engage(const BridgeClock& now, BridgeOutput& out) {
  const bool armed = heartbeat_->base_mode & mav_mode_flag::kSafetyArmed;
  const bool in_fly = is_fly_mode(flavour_, control_, heartbeat_->custom_mode);
  const bool fresh = setpoint_fresh(now);
  const bool want_armed = stack_wants_armed(now);
  const bool streamed_enough = streaming_since_us_ && now.steady_us - *streaming_since_us_ >=
                                                          params_.offboard_warmup_s * 1e6;
  const bool cooling =
      disarmed_at_us_ && now.steady_us - *disarmed_at_us_ < params_.rearm_cooldown_s * 1e6;
  const bool hands_off = override_ || (armed && !in_fly);

  if (armed && in_fly && !landing_asked_) {
    if (refuse_takeover_) {
      request_land("the vehicle was armed in " + mode_name(flavour_, heartbeat_->custom_mode) +
                       " before this bridge came up",
                   now, out);
      return true;
    }
    const int64_t rx =
        control_ == ControlMode::kAttitude ? attitude_rx_steady_us_ : position_rx_steady_us_;
    if (!fresh && engaged_stream_ && params_.silence_action == "land" &&
        now.steady_us - rx >= static_cast<int64_t>(params_.silence_land_s * 1e6)) {
      request_land(
          "the stack's setpoints stopped " + std::to_string(params_.silence_land_s) + " s ago", now,
          out);
      return true;
    }
    if (off_in_air_since_us_ && now.steady_us - *off_in_air_since_us_ >= kInAirDisarmWaitUs) {
      request_land(
          "the stack said motors off but the autopilot still reports the vehicle in "
          "the air",
          now, out);
      return true;
    }
  }
  if (params_.auto_engage() && want_armed && !hands_off && streamed_enough) {
    if (!in_fly) {
      if (armed) return false;
      if (cooling || need_motors_off_) return false;
      const SetModeParams m = set_mode_params(flavour_, fly_custom_mode(flavour_, control_));
      send_command(mav_cmd::kDoSetMode, mode_name(flavour_, fly_custom_mode(flavour_, control_)),
                   m.param1, m.param2, m.param3, now, out);
      return true;
    }
    if (!armed) {
      if (cooling || need_motors_off_) return false;
      send_command(mav_cmd::kComponentArmDisarm, "arm", 1, 0, 0, now, out);
      return true;
    }
  }
  // ArduCopter's GUIDED stays on the ground under position targets until NAV_TAKEOFF
  // (ArduCopter/mode_guided.cpp: every position run function starts with is_disarmed_or_landed();
  // GCS_MAVLINK_Copter::handle_MAV_CMD_NAV_TAKEOFF and Mode::do_user_takeoff, param7 the
  // altitude above home, refused unless armed and landed).
  if (flavour_ == Flavour::kArdupilot && control_ == ControlMode::kPosition && armed && in_fly &&
      want_armed && !takeoff_accepted_ && !takeoff_done_ && !refuse_takeover_ && !override_ &&
      landed_state(now) != mav_landed_state::kInAir) {
    const auto h = height_up(now);
    takeoff_start_up_m_ = h.value_or(0.0);
    takeoff_alt_m_ = std::max(kMinTakeoffAltM, position_->p_W.z() - takeoff_start_up_m_);
    send_command(mav_cmd::kNavTakeoff, "takeoff", 0, 0, 0, now, out,
                 static_cast<float>(takeoff_alt_m_));
    return true;
  }
  // The stack's motors-off (after touch-down, or a KILL without the operator's authority): a
  // plain disarm, only in the offboard mode, where alight is flying; the autopilot refuses it in
  // the air (ArduCopter/AP_Arming_Copter.cpp, disarm: not while !land_complete; PX4's commander:
  // "not landed"). A pilot flying in another mode is never disarmed from here.
  if (fresh && !want_armed && armed && in_fly) {
    send_command(mav_cmd::kComponentArmDisarm, "disarm", 0, 0, 0, now, out);
    return true;
  }
  return false;
}

bool Bridge::decide_housekeeping(const BridgeClock& now, BridgeOutput& out) {
  if (highres_accepted_us_ && imu_source_.empty() && !scaled_imu_asked_ &&
      now.steady_us - *highres_accepted_us_ > kHighresWaitUs) {
    // Accepted but never sent (a board without it that does not say so): ask the other.
    scaled_imu_asked_ = true;
    intervals_to_ask_.push_back({ScaledImu::kId, params_.imu_rate_hz});
    out.events.push_back({true, "no HIGHRES_IMU " + std::to_string(kHighresWaitUs / 1e6) +
                                    " s after it was asked for: asking SCALED_IMU"});
  }
  if (!intervals_to_ask_.empty()) {
    const auto [id, rate] = intervals_to_ask_.front();
    send_command(mav_cmd::kSetMessageInterval, "interval", static_cast<float>(id),
                 static_cast<float>(1e6 / rate), 0, now, out);
    return true;
  }
  // The firmware's version, for what its position targets may carry: MAV_CMD_REQUEST_MESSAGE,
  // then the older MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES (firmware from before 2019). Each is
  // given kVersionWaitUs for the message to follow its acknowledgement.
  if (!firmware_ && now.steady_us >= next_version_ask_us_) {
    if (version_asks_ == 0) {
      send_command(mav_cmd::kRequestMessage, "version request",
                   static_cast<float>(AutopilotVersion::kId), 0, 0, now, out);
    } else if (version_asks_ == 1) {
      send_command(mav_cmd::kRequestAutopilotCapabilities, "version request", 1, 0, 0, now, out);
    } else {
      out.events.push_back({true,
                            "no AUTOPILOT_VERSION from the autopilot: position targets "
                            "go without acceleration"});
      next_version_ask_us_ = INT64_MAX;
      return false;
    }
    ++version_asks_;
    next_version_ask_us_ = now.steady_us + kVersionWaitUs;
    return true;
  }
  return false;
}

void Bridge::service_params(const BridgeClock& now, BridgeOutput& out) {
  if (!link_up_ || !sysid_ || params_to_read_.empty()) return;
  ParamRead& r = params_to_read_.front();
  if (r.attempts > 0 && now.steady_us - r.sent_steady_us < kParamTimeoutUs) return;
  if (r.attempts >= kParamAttempts) {
    ++stats_.param_problems;
    out.events.push_back({true, "autopilot parameter " + r.expect.name +
                                    " not found (renamed in this firmware?); alight needs " +
                                    r.expect.want + ": " + r.expect.why});
    params_to_read_.erase(params_to_read_.begin());
    return;
  }
  ParamRequestRead m;
  m.target_system = *sysid_;
  m.target_component = static_cast<uint8_t>(params_.target_compid);
  set_param_id(m.param_id, r.expect.name);
  m.param_index = -1;
  send(m, now, out);
  ++r.attempts;
  r.sent_steady_us = now.steady_us;
}

void Bridge::service_origin(const BridgeClock& now, BridgeOutput& out) {
  if (!params_.set_ekf_origin || !link_up_ || !sysid_ || origin_known_) return;
  if (now.steady_us < next_origin_us_ || origin_attempts_ >= kOriginAttempts) return;
  // No acknowledgement: ArduPilot answers with GPS_GLOBAL_ORIGIN once set, and refuses a second
  // origin (libraries/GCS_MAVLink/GCS_Common.cpp, handle_set_gps_global_origin); PX4 streams
  // GPS_GLOBAL_ORIGIN on its onboard link.
  SetGpsGlobalOrigin m;
  m.target_system = *sysid_;
  m.latitude = static_cast<int32_t>(std::llround(params_.ekf_origin[0] * 1e7));
  m.longitude = static_cast<int32_t>(std::llround(params_.ekf_origin[1] * 1e7));
  m.altitude = static_cast<int32_t>(std::llround(params_.ekf_origin[2] * 1e3));
  m.time_usec = static_cast<uint64_t>(now.wall_us);
  send(m, now, out);
  ++stats_.origin_sent;
  if (++origin_attempts_ == kOriginAttempts)
    out.events.push_back({true, "no GPS_GLOBAL_ORIGIN after " + std::to_string(kOriginAttempts) +
                                    " SET_GPS_GLOBAL_ORIGIN: the autopilot has no origin"});
  next_origin_us_ = now.steady_us + kOriginPeriodUs;
}

AutopilotStatus Bridge::status(const BridgeClock& now) const {
  AutopilotStatus s;
  s.link_up = link_up_;
  s.flavour = flavour_;
  s.control = control_;
  if (heartbeat_) {
    s.heartbeat_age_s = (now.steady_us - last_heartbeat_steady_) * 1e-6;
    s.sysid = sysid_.value_or(0);
    s.autopilot_type = heartbeat_->autopilot;
    s.custom_mode = heartbeat_->custom_mode;
    s.base_mode = heartbeat_->base_mode;
    s.system_status = heartbeat_->system_status;
    s.mode = mode_name(flavour_, heartbeat_->custom_mode);
    s.armed = heartbeat_->base_mode & mav_mode_flag::kSafetyArmed;
    s.offboard = is_fly_mode(flavour_, control_, heartbeat_->custom_mode);
  }
  s.engage = engage_;
  s.streaming = streaming_since_us_.has_value();
  if (control_ == ControlMode::kAttitude && attitude_)
    s.setpoint_age_s = (now.steady_us - attitude_rx_steady_us_) * 1e-6;
  if (control_ == ControlMode::kPosition && position_)
    s.setpoint_age_s = (now.steady_us - position_rx_steady_us_) * 1e-6;
  s.last_command = last_command_;
  s.last_result = last_result_;
  s.last_statustext = last_statustext_;
  s.battery_V = battery_V_;
  s.landed_state = landed_state(now);
  s.imu_source = imu_source_;
  s.origin_known = origin_known_;
  s.prearm_ok = prearm_ok_;
  if (firmware_) s.firmware = firmware_->str();
  s.accel_feedforward = accel_feedforward();
  s.frame_offset_NED = frame_offset_NED_;
  s.stats = stats_;
  s.parser = parser_.stats();
  return s;
}

}  // namespace alight::mavlink

#include "mavlink/bridge.hpp"

#include <algorithm>
#include <cmath>
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
/// The smallest-delay offset may rise this fast (clock drift) [us per us].
constexpr double kDriftAllowance = 1e-4;
/// Plausible telemetry: beyond these an IMU or estimate is broken, not flying.
constexpr double kMaxAccelMps2 = 2000, kMaxGyroRadps = 100, kMaxPositionM = 1e5,
                 kMaxVelocityMps = 1e3;
/// After an accepted mode or arm command, the next heartbeat shows its effect; decide again
/// after it, or after this long without one.
constexpr int64_t kSettleUs = 1'500'000;
/// The autopilot's attitude is used for the heading while this fresh; then motion capture's.
constexpr int64_t kHeadingFreshUs = 500'000;

bool finite3(float a, float b, float c) {
  return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
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
  }
  return "?";
}

Bridge::Bridge(const BridgeParams& params, double hover_thrust_N)
    : params_(params),
      flavour_(params.flavour()),
      control_(params.control_mode()),
      hover_thrust_N_(hover_thrust_N),
      sender_(static_cast<uint8_t>(params.own_sysid), static_cast<uint8_t>(params.own_compid)) {
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
  pending_.reset();
  await_heartbeat_ = false;
  override_ = false;
  was_armed_in_fly_mode_ = false;
  intervals_to_ask_.clear();
  const std::pair<uint32_t, double> asks[] = {{HighresImu::kId, params_.imu_rate_hz},
                                              {AttitudeQuaternion::kId, params_.attitude_rate_hz},
                                              {LocalPositionNed::kId, params_.position_rate_hz}};
  for (const auto& a : asks)
    if (a.second > 0) intervals_to_ask_.push_back(a);
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
  }
  if (in.position) {
    position_ = in.position;
    position_rx_steady_us_ = now.steady_us;
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
      if (!utime || *utime <= last_imu_utime_) {
        ++stats_.rejected_stamps;
        return;
      }
      last_imu_utime_ = *utime;
      ImuOut s;
      s.utime = *utime;
      s.accel_B = flu_from_frd(Vector3d(m.xacc, m.yacc, m.zacc));
      s.gyro_B = flu_from_frd(Vector3d(m.xgyro, m.ygyro, m.zgyro));
      out.imu.push_back(s);
      ++stats_.imu_out;
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
      if (local_position_ && now.steady_us - local_position_steady_us_ < 1'000'000) {
        const LocalPositionNed& lp = *local_position_;
        PoseSample p;
        p.utime = *utime;
        p.p_W_B = enu_from_ned(Vector3d(lp.x, lp.y, lp.z));
        p.v_W_B = enu_from_ned(Vector3d(lp.vx, lp.vy, lp.vz));
        p.q_WB = q_enu_flu_from_ned_frd(*q);
        p.omega_B = flu_from_frd(omega_FRD_);
        out.autopilot_pose.push_back(p);
      }
    } else if constexpr (std::is_same_v<M, LocalPositionNed>) {
      if (!within(m.x, m.y, m.z, kMaxPositionM) || !within(m.vx, m.vy, m.vz, kMaxVelocityMps)) {
        ++stats_.rejected_values;
        return;
      }
      on_boot_time(uint64_t{m.time_boot_ms} * 1000, out);
      local_position_ = m;
      local_position_steady_us_ = now.steady_us;
    } else if constexpr (std::is_same_v<M, Statustext>) {
      last_statustext_ = statustext_string(m);
      out.events.push_back(
          {m.severity <= mav_severity::kWarning, "autopilot: " + last_statustext_});
    } else if constexpr (std::is_same_v<M, SysStatus>) {
      battery_V_ = m.voltage_battery == UINT16_MAX ? -1.0 : m.voltage_battery / 1000.0;
    }
  });
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
  if (!link_up_) {
    link_up_ = true;
    out.events.push_back({false, "link up: " + mode_name(flavour_, m.custom_mode) +
                                     (armed ? ", armed" : ", disarmed")});
  }
  const bool in_fly = is_fly_mode(flavour_, control_, m.custom_mode);
  if (!armed) {
    override_ = false;
  } else if (was_armed_in_fly_mode_ && !in_fly && !override_) {
    override_ = true;
    out.events.push_back({true, "autopilot left " +
                                    mode_name(flavour_, fly_custom_mode(flavour_, control_)) +
                                    " for " + mode_name(flavour_, m.custom_mode) +
                                    " while armed (pilot or failsafe): alight will not take it "
                                    "back before the vehicle is disarmed"});
  }
  was_armed_in_fly_mode_ = armed && in_fly;
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

std::optional<double> Bridge::heading_enu(const BridgeClock& now) const {
  if (q_NED_FRD_ && now.steady_us - attitude_steady_us_ <= kHeadingFreshUs)
    return yaw_of(q_enu_flu_from_ned_frd(*q_NED_FRD_).toRotationMatrix());
  if (mocap_ && now.steady_us - mocap_rx_steady_us_ <= kHeadingFreshUs)
    return yaw_of(mocap_->q_WB.toRotationMatrix());
  return std::nullopt;
}

void Bridge::stream(const BridgeClock& now, BridgeOutput& out) {
  if (!link_up_ || !setpoint_fresh(now)) {
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
    m.type_mask = attitude_target_typemask::kBodyRollRateIgnore |
                  attitude_target_typemask::kBodyPitchRateIgnore;
    m.q = wxyz_float(q_ned_frd_from_enu_flu(q_ENU_FLU));
    m.body_yaw_rate = static_cast<float>(-t.yaw_rate_radps);  // FLU z up -> FRD z down
    const double thrust = t.armed ? t.thrust_N / hover_thrust_N_ * params_.hover_thrust : 0.0;
    m.thrust = static_cast<float>(std::clamp(thrust, 0.0, 1.0));
    send(m, now, out);
  } else {
    const PositionTarget& t = *position_;
    const Vector3d p = ned_from_enu(t.p_W), v = ned_from_enu(t.v_W);
    SetPositionTargetLocalNed m;
    m.time_boot_ms = boot_ms;
    m.target_system = *sysid_;
    m.target_component = static_cast<uint8_t>(params_.target_compid);
    m.coordinate_frame = mav_frame::kLocalNed;
    m.type_mask = position_target_typemask::kAxIgnore | position_target_typemask::kAyIgnore |
                  position_target_typemask::kAzIgnore | position_target_typemask::kYawRateIgnore;
    m.x = static_cast<float>(p.x());
    m.y = static_cast<float>(p.y());
    m.z = static_cast<float>(p.z());
    m.vx = static_cast<float>(v.x());
    m.vy = static_cast<float>(v.y());
    m.vz = static_cast<float>(v.z());
    m.yaw = static_cast<float>(yaw_ned_from_enu(t.yaw_rad));
    send(m, now, out);
  }
  ++stats_.setpoints_sent;
  if (!streaming_since_us_) streaming_since_us_ = now.steady_us;
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
    m.estimator_type = mav_estimator_type::kMocap;
    m.quality = 100;
    send(m, now, out);
  }
  ++stats_.mocap_sent;
}

// --- Commands ------------------------------------------------------------------------------

void Bridge::send_command(uint16_t command, const std::string& name, float p1, float p2, float p3,
                          const BridgeClock& now, BridgeOutput& out) {
  Pending p;
  p.cmd.target_system = *sysid_;
  p.cmd.target_component = static_cast<uint8_t>(params_.target_compid);
  p.cmd.command = command;
  p.cmd.param1 = p1;
  p.cmd.param2 = p2;
  p.cmd.param3 = p3;
  p.name = name;
  p.attempts = 1;
  p.sent_steady_us = now.steady_us;
  send(p.cmd, now, out);
  ++stats_.commands_sent;
  last_command_ = name;
  pending_ = p;
}

void Bridge::command_finished(bool ok, int result, const BridgeClock& now, BridgeOutput& out) {
  const std::string name = pending_->name;
  last_result_ = result;
  pending_.reset();
  if (ok) {
    if (name != "interval") {
      await_heartbeat_ = true;
      settle_until_us_ = now.steady_us + kSettleUs;
    } else if (!intervals_to_ask_.empty()) {
      intervals_to_ask_.erase(intervals_to_ask_.begin());
    }
    if (name != "interval") out.events.push_back({false, name + ": accepted"});
    return;
  }
  ++stats_.commands_failed;
  backoff_until_us_ = now.steady_us + static_cast<int64_t>(params_.command_backoff_s * 1e6);
  if (name == "interval" && !intervals_to_ask_.empty()) {
    // An autopilot that cannot change a rate keeps its own; not worth asking again.
    intervals_to_ask_.erase(intervals_to_ask_.begin());
    backoff_until_us_ = now.steady_us;
  }
  out.events.push_back({true, name + ": " +
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
  const int64_t limit = static_cast<int64_t>(params_.setpoint_timeout_s * 1e6);
  const bool kill = position_ && position_->motors == Motors::kKill &&
                    now.steady_us - position_rx_steady_us_ <= limit;
  bool want_armed = false;
  if (fresh)
    want_armed =
        control_ == ControlMode::kAttitude ? attitude_->armed : position_->motors == Motors::kOn;
  const bool streamed_enough = streaming_since_us_ && now.steady_us - *streaming_since_us_ >=
                                                          params_.offboard_warmup_s * 1e6;

  // Armed in another mode: the pilot's, or the autopilot's failsafe (also one that flew while the
  // link was down, when the bridge could not see it leave). alight engages from the ground only.
  const bool hands_off = override_ || (armed && !in_fly);
  if (!params_.auto_engage())
    engage_ = EngageState::kOperator;
  else if (hands_off)
    engage_ = EngageState::kOverride;
  else if (armed && in_fly)
    engage_ = EngageState::kFlying;
  else if (!want_armed)
    engage_ = EngageState::kIdle;
  else if (!streamed_enough)
    engage_ = EngageState::kStreaming;
  else
    engage_ = in_fly ? EngageState::kArmWait : EngageState::kModeWait;

  if (pending_ || now.steady_us < backoff_until_us_) return;
  // A KILL does not wait for a heartbeat to settle.
  if (kill && armed) {
    send_command(mav_cmd::kComponentArmDisarm, "force disarm", 0, kForceDisarmMagic, 0, now, out);
    return;
  }
  if (await_heartbeat_ && now.steady_us < settle_until_us_) return;
  await_heartbeat_ = false;
  if (params_.auto_engage() && want_armed && !hands_off && streamed_enough) {
    if (!in_fly) {
      const SetModeParams m = set_mode_params(flavour_, fly_custom_mode(flavour_, control_));
      send_command(mav_cmd::kDoSetMode, mode_name(flavour_, fly_custom_mode(flavour_, control_)),
                   m.param1, m.param2, m.param3, now, out);
      return;
    }
    if (!armed) {
      send_command(mav_cmd::kComponentArmDisarm, "arm", 1, 0, 0, now, out);
      return;
    }
  }
  // The stack's motors-off after touch-down (its land detector): only in the offboard mode, where
  // alight is flying; a pilot flying in another mode is never disarmed from here.
  if (fresh && !want_armed && armed && in_fly) {
    send_command(mav_cmd::kComponentArmDisarm, "disarm", 0, 0, 0, now, out);
    return;
  }
  if (!intervals_to_ask_.empty()) {
    const auto [id, rate] = intervals_to_ask_.front();
    send_command(mav_cmd::kSetMessageInterval, "interval", static_cast<float>(id),
                 static_cast<float>(1e6 / rate), 0, now, out);
  }
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
  s.stats = stats_;
  s.parser = parser_.stats();
  return s;
}

}  // namespace alight::mavlink

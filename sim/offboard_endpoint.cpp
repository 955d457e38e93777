#include "sim/offboard_endpoint.hpp"

#include <algorithm>
#include <cmath>

#include "mavlink/ned_frd.hpp"

namespace alight::sim {

namespace mav = alight::mavlink;

namespace {
constexpr int64_t kHeartbeatPeriodUs = 1'000'000;
/// The PX4 release whose offboard handling this endpoint follows (v1.15.0, official), as
/// AUTOPILOT_VERSION.flight_sw_version encodes it.
constexpr uint32_t kFlightSwVersion = 0x010F00FFu;
const uint32_t kOffboardMode = mav::px4_mode::custom_mode(mav::px4_mode::kOffboard);
const uint32_t kLandMode =
    mav::px4_mode::custom_mode(mav::px4_mode::kAuto, mav::px4_mode::auto_sub::kLand);
const uint32_t kLoiterMode =
    mav::px4_mode::custom_mode(mav::px4_mode::kAuto, mav::px4_mode::auto_sub::kLoiter);

int64_t period_us(double hz) { return hz > 0 ? static_cast<int64_t>(1e6 / hz) : INT64_MAX; }
}  // namespace

OffboardEndpoint::OffboardEndpoint(const OffboardEndpointParams& params, double hover_thrust_N,
                                   int64_t boot_utime)
    : params_(params),
      hover_thrust_N_(hover_thrust_N),
      boot_utime_(boot_utime),
      sender_(params.sysid, params.compid),
      custom_mode_(kLoiterMode),
      attitude_rate_hz_(params.attitude_rate_hz),
      position_rate_hz_(params.position_rate_hz),
      imu_rate_hz_(params.imu_rate_hz) {}

bool OffboardEndpoint::offboard() const {
  return mav::px4_mode::main_mode(custom_mode_) == mav::px4_mode::kOffboard;
}

uint32_t OffboardEndpoint::boot_ms(int64_t now) const {
  return static_cast<uint32_t>(std::max<int64_t>(now - boot_utime_, 0) / 1000);
}

template <class M>
void OffboardEndpoint::send(const M& m, EndpointOutput& out) {
  const mav::FrameBytes f = sender_.pack(m, 0);
  out.bytes.insert(out.bytes.end(), f.bytes().begin(), f.bytes().end());
}

void OffboardEndpoint::text(uint8_t severity, const std::string& s, EndpointOutput& out) {
  mav::Statustext t;
  t.severity = severity;
  mav::set_statustext(t, s);
  send(t, out);
  out.events.push_back(s);
}

void OffboardEndpoint::set_mode(uint32_t mode, EndpointOutput& out) {
  if (mode == custom_mode_) return;
  custom_mode_ = mode;
  out.events.push_back("mode " + mav::mode_name(mav::Flavour::kPx4, mode));
}

bool OffboardEndpoint::stream_ok(int64_t now) const {
  // PX4 wants the offboard signal before the switch: at least the minimum rate over the last
  // second, and the newest setpoint within one period of that rate.
  const auto need = static_cast<size_t>(std::ceil(params_.offboard_min_rate_hz));
  return setpoint_times_.size() >= need &&
         now - last_setpoint_utime_ <= period_us(params_.offboard_min_rate_hz);
}

void OffboardEndpoint::ack(const mav::CommandLong& c, uint8_t result, uint8_t to_sys,
                           uint8_t to_comp, EndpointOutput& out) {
  mav::CommandAck a;
  a.command = c.command;
  a.result = result;
  a.target_system = to_sys;
  a.target_component = to_comp;
  send(a, out);
  if (result != mav::mav_result::kAccepted) ++stats_.rejected_commands;
}

void OffboardEndpoint::on_command(const mav::CommandLong& c, const EndpointInput& in,
                                  EndpointOutput& out) {
  ++stats_.commands;
  const uint8_t to_sys = peer_sysid_, to_comp = peer_compid_;
  switch (c.command) {
    case mav::mav_cmd::kDoSetMode: {
      const auto main_mode = static_cast<uint8_t>(c.param2), sub = static_cast<uint8_t>(c.param3);
      if (!(static_cast<int>(c.param1) & mav::mav_mode_flag::kCustomModeEnabled) ||
          main_mode < mav::px4_mode::kManual || main_mode > mav::px4_mode::kRattitude) {
        ack(c, mav::mav_result::kDenied, to_sys, to_comp, out);
        return;
      }
      if (main_mode == mav::px4_mode::kOffboard && !stream_ok(in.now_utime)) {
        ack(c, mav::mav_result::kTemporarilyRejected, to_sys, to_comp, out);
        text(mav::mav_severity::kCritical, "Switching to Offboard is currently not available", out);
        return;
      }
      set_mode(mav::px4_mode::custom_mode(main_mode, sub), out);
      ack(c, mav::mav_result::kAccepted, to_sys, to_comp, out);
      return;
    }
    case mav::mav_cmd::kComponentArmDisarm: {
      if (c.param1 == 1.0f) {
        if (!armed_)
          out.events.push_back("armed in " + mav::mode_name(mav::Flavour::kPx4, custom_mode_));
        armed_ = true;
        ack(c, mav::mav_result::kAccepted, to_sys, to_comp, out);
      } else if (c.param1 == 0.0f) {
        const bool forced = c.param2 == mav::kForceDisarmMagic;
        if (!in.on_ground && !forced && armed_) {
          ack(c, mav::mav_result::kDenied, to_sys, to_comp, out);
          text(mav::mav_severity::kCritical, "Disarming denied: not landed", out);
          return;
        }
        if (armed_) {
          out.disarm = true;
          out.events.push_back(forced ? "disarmed (forced)" : "disarmed");
        }
        armed_ = false;
        ack(c, mav::mav_result::kAccepted, to_sys, to_comp, out);
      } else {
        ack(c, mav::mav_result::kDenied, to_sys, to_comp, out);
      }
      return;
    }
    case mav::mav_cmd::kRequestMessage:
    case mav::mav_cmd::kRequestAutopilotCapabilities: {
      const bool version = c.command == mav::mav_cmd::kRequestMessage
                               ? static_cast<uint32_t>(c.param1) == mav::AutopilotVersion::kId
                               : c.param1 == 1.0f;
      if (!version) {
        ack(c, mav::mav_result::kUnsupported, to_sys, to_comp, out);
        return;
      }
      ack(c, mav::mav_result::kAccepted, to_sys, to_comp, out);
      mav::AutopilotVersion v;
      v.flight_sw_version = kFlightSwVersion;
      send(v, out);
      return;
    }
    case mav::mav_cmd::kSetMessageInterval: {
      // param2: interval [us]; 0 the default, -1 off.
      const double rate = c.param2 > 0 ? 1e6 / c.param2 : (c.param2 < 0 ? 0.0 : -1.0);
      double* target = nullptr;
      double fallback = 0;
      const auto id = static_cast<uint32_t>(c.param1);
      if (id == mav::HighresImu::kId) target = &imu_rate_hz_, fallback = params_.imu_rate_hz;
      if (id == mav::AttitudeQuaternion::kId)
        target = &attitude_rate_hz_, fallback = params_.attitude_rate_hz;
      if (id == mav::LocalPositionNed::kId)
        target = &position_rate_hz_, fallback = params_.position_rate_hz;
      if (!target || !std::isfinite(c.param2)) {
        ack(c, mav::mav_result::kUnsupported, to_sys, to_comp, out);
        return;
      }
      *target = rate < 0 ? fallback : rate;
      ack(c, mav::mav_result::kAccepted, to_sys, to_comp, out);
      return;
    }
    default:
      ack(c, mav::mav_result::kUnsupported, to_sys, to_comp, out);
  }
}

void OffboardEndpoint::handle(const mav::Frame& f, const EndpointInput& in, EndpointOutput& out) {
  if (f.sysid == params_.sysid && f.compid == params_.compid) return;  // our own echo
  mav::dispatch(f, [&](const auto& m) {
    using M = std::decay_t<decltype(m)>;
    if constexpr (std::is_same_v<M, mav::CommandLong>) {
      if (m.target_system != params_.sysid ||
          (m.target_component != 0 && m.target_component != params_.compid))
        return;
      peer_sysid_ = f.sysid;
      peer_compid_ = f.compid;
      on_command(m, in, out);
    } else if constexpr (std::is_same_v<M, mav::Timesync>) {
      if (m.tc1 == 0) {
        mav::Timesync r;
        r.tc1 = (in.now_utime - boot_utime_) * 1000;
        r.ts1 = m.ts1;
        r.target_system = f.sysid;
        r.target_component = f.compid;
        send(r, out);
      }
    } else if constexpr (std::is_same_v<M, mav::SetAttitudeTarget>) {
      if (m.target_system != params_.sysid) return;
      const auto q = mav::quat_from_wxyz_float(m.q);
      if (!q || !std::isfinite(m.thrust)) return;  // PX4 drops these too
      ++stats_.setpoints;
      setpoint_times_.push_back(in.now_utime);
      last_setpoint_utime_ = in.now_utime;
      if (!offboard() || !armed_) return;
      const Matrix3d R_WB_sp = mav::q_enu_flu_from_ned_frd(*q).toRotationMatrix();
      const Vector3d rpy = rpy_from_rotation(R_WB_sp);
      const double yaw_now = yaw_of(in.state.q_WB.toRotationMatrix());
      AttitudeCommand cmd;
      cmd.utime = in.now_utime;
      cmd.roll_rad = rpy.x();
      cmd.pitch_rad = rpy.y();
      cmd.yaw_rate_radps = std::clamp(params_.yaw_p_per_s * wrap_angle(rpy.z() - yaw_now),
                                      -params_.max_yaw_rate_radps, params_.max_yaw_rate_radps);
      cmd.thrust_N = std::clamp<double>(m.thrust, 0, 1) / params_.hover_thrust * hover_thrust_N_;
      cmd.armed = true;
      out.command = cmd;
    } else if constexpr (std::is_same_v<M, mav::SetPositionTargetLocalNed>) {
      if (m.target_system != params_.sysid || m.coordinate_frame != mav::mav_frame::kLocalNed)
        return;
      if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.z) ||
          !std::isfinite(m.vx) || !std::isfinite(m.vy) || !std::isfinite(m.vz) ||
          !std::isfinite(m.yaw))
        return;
      ++stats_.setpoints;
      setpoint_times_.push_back(in.now_utime);
      last_setpoint_utime_ = in.now_utime;
      if (!offboard() || !armed_) return;
      EndpointPositionTarget t;
      t.utime = in.now_utime;
      t.p_W = mav::enu_from_ned(Vector3d(m.x, m.y, m.z));
      const bool vel = !(m.type_mask & (mav::position_target_typemask::kVxIgnore |
                                        mav::position_target_typemask::kVyIgnore |
                                        mav::position_target_typemask::kVzIgnore));
      if (vel) t.v_W = mav::enu_from_ned(Vector3d(m.vx, m.vy, m.vz));
      const bool acc = !(m.type_mask & mav::position_target_typemask::kAccelIgnore);
      if (acc && std::isfinite(m.afx) && std::isfinite(m.afy) && std::isfinite(m.afz))
        t.a_W = mav::enu_from_ned(Vector3d(m.afx, m.afy, m.afz));
      t.yaw_rad = (m.type_mask & mav::position_target_typemask::kYawIgnore)
                      ? yaw_of(in.state.q_WB.toRotationMatrix())
                      : mav::yaw_enu_from_ned(m.yaw);
      out.position = t;
    } else if constexpr (std::is_same_v<M, mav::AttPosMocap> || std::is_same_v<M, mav::Odometry>) {
      ++stats_.mocap;
    }
  });
}

EndpointOutput OffboardEndpoint::update(const EndpointInput& in) {
  EndpointOutput out;
  const int64_t now = in.now_utime;
  std::erase_if(setpoint_times_, [&](int64_t t) { return now - t > 1'000'000 || t > now; });
  if (!in.bytes.empty()) {
    parser_.push(in.bytes);
    mav::Frame f;
    while (parser_.next(f)) handle(f, in, out);
  }
  // The dynamics disarmed (the command-loss descent ended on the ground): so does the autopilot.
  if (armed_ && !in.state.armed && in.on_ground && !offboard()) {
    armed_ = false;
    out.events.push_back("disarmed after landing");
  }
  // COM_OF_LOSS_T, then COM_OBL_RC_ACT = Land.
  if (offboard() && armed_ &&
      now - last_setpoint_utime_ > static_cast<int64_t>(params_.offboard_loss_timeout_s * 1e6)) {
    ++stats_.failsafes;
    set_mode(kLandMode, out);
    text(mav::mav_severity::kCritical, "Failsafe: offboard signal lost, landing", out);
  }

  if (now >= next_heartbeat_) {
    mav::Heartbeat hb;
    hb.type = mav::mav_type::kQuadrotor;
    hb.autopilot = mav::mav_autopilot::kPx4;
    hb.base_mode =
        mav::mav_mode_flag::kCustomModeEnabled | (armed_ ? mav::mav_mode_flag::kSafetyArmed : 0);
    hb.custom_mode = custom_mode_;
    hb.system_status = armed_ ? mav::mav_state::kActive : mav::mav_state::kStandby;
    send(hb, out);
    next_heartbeat_ = now + kHeartbeatPeriodUs;
  }
  const VehicleState& s = in.state;
  if (now >= next_attitude_ && attitude_rate_hz_ > 0) {
    mav::AttitudeQuaternion a;
    a.time_boot_ms = boot_ms(now);
    const auto q = mav::wxyz_float(mav::q_ned_frd_from_enu_flu(s.q_WB));
    a.q1 = q[0], a.q2 = q[1], a.q3 = q[2], a.q4 = q[3];
    const Vector3d w = mav::frd_from_flu(s.omega_B);
    a.rollspeed = static_cast<float>(w.x());
    a.pitchspeed = static_cast<float>(w.y());
    a.yawspeed = static_cast<float>(w.z());
    send(a, out);
    next_attitude_ = now + period_us(attitude_rate_hz_);
  }
  if (now >= next_position_ && position_rate_hz_ > 0) {
    mav::LocalPositionNed l;
    l.time_boot_ms = boot_ms(now);
    const Vector3d p = mav::ned_from_enu(s.p_W_B), v = mav::ned_from_enu(s.v_W_B);
    l.x = static_cast<float>(p.x()), l.y = static_cast<float>(p.y()),
    l.z = static_cast<float>(p.z());
    l.vx = static_cast<float>(v.x()), l.vy = static_cast<float>(v.y()),
    l.vz = static_cast<float>(v.z());
    send(l, out);
    next_position_ = now + period_us(position_rate_hz_);
  }
  for (const ImuSample& i : in.imu) {
    if (imu_rate_hz_ <= 0 || i.utime - last_imu_sent_ < period_us(imu_rate_hz_) - 500) continue;
    last_imu_sent_ = i.utime;
    mav::HighresImu h;
    h.time_usec = static_cast<uint64_t>(i.utime);
    const Vector3d a = mav::frd_from_flu(i.accel_B), g = mav::frd_from_flu(i.gyro_B);
    h.xacc = static_cast<float>(a.x()), h.yacc = static_cast<float>(a.y()),
    h.zacc = static_cast<float>(a.z());
    h.xgyro = static_cast<float>(g.x()), h.ygyro = static_cast<float>(g.y()),
    h.zgyro = static_cast<float>(g.z());
    h.fields_updated = 0x3F;  // accelerometer and gyro
    send(h, out);
  }
  return out;
}

}  // namespace alight::sim

#include "sim/autopilot_truth.hpp"

#include <algorithm>
#include <cmath>

#include "mavlink/ned_frd.hpp"

namespace alight::sim {

namespace mav = alight::mavlink;

namespace {
/// ArduPilot's metres per 1e-7 degree (libraries/AP_Common/Location.h, LOCATION_SCALING_FACTOR).
constexpr double kArduPilotMPerE7 = 0.011131884502145034;
/// PX4's earth radius (src/lib/geo/geo.h, CONSTANTS_RADIUS_OF_EARTH) [m].
constexpr double kPx4EarthRadiusM = 6371000.0;
constexpr double kDegE7ToRad = 1e-7 * M_PI / 180.0;
/// HEARTBEAT asked of the autopilot on this link [Hz].
constexpr double kHeartbeatRateHz = 10.0;
/// Samples further apart than this are not integrated between: the position restarts at the
/// measured one [s].
constexpr double kMaxGapS = 0.2;
/// A sample further than this from the anchor is corrupt, not flown [m].
constexpr double kMaxOffsetM = 10000.0;
}  // namespace

Vector2d AutopilotTruth::north_east_m(mav::Flavour flavour, int32_t lat_e7, int32_t lon_e7,
                                      int32_t ref_lat_e7, int32_t ref_lon_e7) {
  const double dlat = static_cast<double>(lat_e7) - ref_lat_e7;
  double dlon = static_cast<double>(lon_e7) - ref_lon_e7;
  if (dlon > 1.8e9) dlon -= 3.6e9;
  if (dlon < -1.8e9) dlon += 3.6e9;
  if (flavour == mav::Flavour::kArdupilot) {
    const double mean_lat = 0.5 * (static_cast<double>(lat_e7) + ref_lat_e7) * kDegE7ToRad;
    const double scale = std::max(0.01, std::cos(mean_lat));
    return Vector2d(dlat * kArduPilotMPerE7, dlon * kArduPilotMPerE7 * scale);
  }
  const double ref_lat = ref_lat_e7 * kDegE7ToRad;
  return Vector2d(dlat * kDegE7ToRad * kPx4EarthRadiusM,
                  dlon * kDegE7ToRad * kPx4EarthRadiusM * std::cos(ref_lat));
}

AutopilotTruth::AutopilotTruth(const AutopilotTruthParams& params)
    : params_(params), sender_(params.own_sysid, params.own_compid) {}

template <class M>
void AutopilotTruth::send(const M& m, int64_t now, Output& out) {
  const auto f = sender_.pack(m, now);
  out.bytes.insert(out.bytes.end(), f.bytes().begin(), f.bytes().end());
}

AutopilotTruth::Output AutopilotTruth::update(std::span<const uint8_t> bytes, int64_t now) {
  Output out;
  if (!bytes.empty()) {
    parser_.push(bytes);
    mav::Frame f;
    while (parser_.next(f)) {
      if (f.compid != mav::mav_component::kAutopilot1) continue;
      if (sysid_ && f.sysid != *sysid_) continue;
      if (f.msgid == mav::Heartbeat::kId) {
        const auto hb = mav::decode<mav::Heartbeat>(f);
        if (!hb || hb->autopilot == mav::mav_autopilot::kInvalid) continue;
        if (!sysid_) {
          sysid_ = f.sysid;
          out.events.push_back("autopilot system " + std::to_string(f.sysid) + " heard");
        }
        const bool armed = hb->base_mode & mav::mav_mode_flag::kSafetyArmed;
        if (!heard_ || armed != armed_ || hb->custom_mode != custom_mode_)
          out.events.push_back("autopilot " + mav::mode_name(params_.flavour, hb->custom_mode) +
                               (armed ? ", armed" : ", disarmed"));
        heard_ = true;
        armed_ = armed;
        custom_mode_ = hb->custom_mode;
      } else if (params_.flavour == mav::Flavour::kArdupilot && f.msgid == mav::SimState::kId) {
        const auto m = mav::decode<mav::SimState>(f);
        const auto q = mav::quat_from_wxyz_float({m->q1, m->q2, m->q3, m->q4});
        if (!q || !std::isfinite(m->alt) || !std::isfinite(m->vn) || !std::isfinite(m->ve) ||
            !std::isfinite(m->vd) || !std::isfinite(m->xgyro) || !std::isfinite(m->ygyro) ||
            !std::isfinite(m->zgyro) || (m->lat_int == 0 && m->lon_int == 0)) {
          ++n_rejected_;
          continue;
        }
        Raw r;
        r.lat_e7 = m->lat_int;
        r.lon_e7 = m->lon_int;
        r.alt_m = m->alt;
        r.v_NED = Vector3d(m->vn, m->ve, m->vd);
        r.q_NED_FRD = *q;
        r.omega_FRD = Vector3d(m->xgyro, m->ygyro, m->zgyro);
        on_sample(r, now, out);
      } else if (params_.flavour == mav::Flavour::kPx4 && f.msgid == mav::HilStateQuaternion::kId) {
        const auto m = mav::decode<mav::HilStateQuaternion>(f);
        const auto q = mav::quat_from_wxyz_float(m->attitude_quaternion);
        if (!q || !std::isfinite(m->rollspeed) || !std::isfinite(m->pitchspeed) ||
            !std::isfinite(m->yawspeed)) {
          ++n_rejected_;
          continue;
        }
        Raw r;
        r.lat_e7 = m->lat;
        r.lon_e7 = m->lon;
        r.alt_m = m->alt * 1e-3;
        r.v_NED = Vector3d(m->vx, m->vy, m->vz) * 0.01;
        r.q_NED_FRD = *q;
        r.omega_FRD = Vector3d(m->rollspeed, m->pitchspeed, m->yawspeed);
        on_sample(r, now, out);
      }
    }
  }
  if (now >= next_heartbeat_) {
    mav::Heartbeat hb;
    hb.type = mav::mav_type::kOnboardController;
    hb.autopilot = mav::mav_autopilot::kInvalid;
    hb.system_status = mav::mav_state::kActive;
    send(hb, now, out);
    next_heartbeat_ = now + 1'000'000;
  }
  // The rate is asked until samples come (SET_MESSAGE_INTERVAL; its answer is not needed), and
  // the heartbeat at 10 Hz: the failsafes' record of modes and arming is as fine as it is.
  const bool flowing = last_ && now - last_->utime < 500'000;
  if (sysid_ && (!flowing || heartbeat_asks_ < 3) && now >= next_request_) {
    const auto ask = [&](uint32_t id, double rate_hz) {
      mav::CommandLong c;
      c.target_system = *sysid_;
      c.target_component = mav::mav_component::kAutopilot1;
      c.command = mav::mav_cmd::kSetMessageInterval;
      c.param1 = static_cast<float>(id);
      c.param2 = static_cast<float>(1e6 / rate_hz);
      send(c, now, out);
    };
    if (!flowing)
      ask(params_.flavour == mav::Flavour::kArdupilot ? mav::SimState::kId
                                                      : mav::HilStateQuaternion::kId,
          params_.rate_hz);
    if (heartbeat_asks_ < 3) {
      ask(mav::Heartbeat::kId, kHeartbeatRateHz);
      ++heartbeat_asks_;
    }
    next_request_ = now + 1'000'000;
  }
  return out;
}

void AutopilotTruth::on_sample(const Raw& r, int64_t now, Output& out) {
  if (!anchor_) {
    anchor_ = r;
    // The heading at the anchor becomes the start yaw: world = Rz(start - heading) * ENU.
    const double heading_enu = yaw_of(mav::q_enu_flu_from_ned_frd(r.q_NED_FRD).toRotationMatrix());
    R_W_ENU_ = Eigen::AngleAxisd(wrap_angle(params_.start_yaw_rad - heading_enu), Vector3d::UnitZ())
                   .toRotationMatrix();
    p_NED_.setZero();
    v_prev_NED_ = r.v_NED;
    out.events.push_back("anchored at " + std::to_string(r.lat_e7 * 1e-7) + ", " +
                         std::to_string(r.lon_e7 * 1e-7) + ", " + std::to_string(r.alt_m) +
                         " m, heading " + std::to_string(heading_enu * 180 / M_PI) +
                         " deg (ENU) -> world start yaw " +
                         std::to_string(params_.start_yaw_rad * 180 / M_PI) + " deg");
  }
  const Vector2d ne =
      north_east_m(params_.flavour, r.lat_e7, r.lon_e7, anchor_->lat_e7, anchor_->lon_e7);
  Vector3d measured(ne.x(), ne.y(), -(r.alt_m - anchor_->alt_m));
  // The ground is where the vehicle stood at the anchor. PX4 SIH's ground holds the vehicle only
  // while the net force points down (src/modules/simulation/simulator_sih/sih.cpp, "fake
  // ground"): one arriving at hover thrust sank 0.16 m through it. Held at the ground here.
  Vector3d v_NED = r.v_NED;
  if (measured.z() > 0) {
    measured.z() = 0;
    v_NED.z() = std::min(v_NED.z(), 0.0);
  }
  if (!measured.allFinite() || measured.norm() > kMaxOffsetM) {
    ++n_rejected_;
    return;
  }
  const double dt = last_ ? (now - last_->utime) * 1e-6 : kMaxGapS + 1;
  if (dt >= 0 && dt <= kMaxGapS) {
    const Vector3d predicted = p_NED_ + 0.5 * (v_prev_NED_ + v_NED) * dt;
    const double a = 1.0 - std::exp(-dt / params_.position_tau_s);
    p_NED_ = predicted + a * (measured - predicted);
  } else {
    p_NED_ = measured;  // the first sample, or after a gap: nothing to integrate over
  }
  p_NED_.z() = std::min(p_NED_.z(), 0.0);
  v_prev_NED_ = v_NED;
  TruthSample s;
  s.utime = now;
  s.state.p_W_B = params_.start_W + R_W_ENU_ * mav::enu_from_ned(p_NED_);
  s.state.v_W_B = R_W_ENU_ * mav::enu_from_ned(v_NED);
  s.state.q_WB = Quaterniond(R_W_ENU_) * mav::q_enu_flu_from_ned_frd(r.q_NED_FRD);
  s.state.q_WB.normalize();
  s.state.omega_B = mav::flu_from_frd(r.omega_FRD);
  s.state.yaw_des_rad = yaw_of(s.state.q_WB.toRotationMatrix());
  s.state.armed = armed_;
  last_ = s;
  ++n_samples_;
  out.samples.push_back(s);
}

VehicleState AutopilotTruth::advance(int64_t t) {
  const VehicleState raw = raw_at(t);
  if (!smooth_ || !last_) {
    smooth_ = raw;
    smooth_utime_ = t;
    return raw;
  }
  const double dt = std::clamp((t - smooth_utime_) * 1e-6, 0.0, 0.05);
  smooth_utime_ = std::max(smooth_utime_, t);
  VehicleState& s = *smooth_;
  const double w = 2 * M_PI * params_.smooth_hz;
  const Vector3d a = w * w * (raw.p_W_B - s.p_W_B) + 2 * w * (raw.v_W_B - s.v_W_B);
  s.v_W_B += a * dt;
  s.p_W_B += s.v_W_B * dt;
  const Eigen::AngleAxisd e(s.q_WB.conjugate() * raw.q_WB);  // body-frame attitude error
  Vector3d e_B = e.angle() * e.axis();
  if (e.angle() > M_PI) e_B = (e.angle() - 2 * M_PI) * e.axis();
  s.omega_B = raw.omega_B + params_.attitude_gain_per_s * e_B;
  const Vector3d dtheta = s.omega_B * dt;
  const double angle = dtheta.norm();
  if (angle > 0)
    s.q_WB = (s.q_WB * Quaterniond(Eigen::AngleAxisd(angle, dtheta / angle))).normalized();
  s.armed = raw.armed;
  s.yaw_des_rad = yaw_of(s.q_WB.toRotationMatrix());
  return s;
}

VehicleState AutopilotTruth::raw_at(int64_t t) const {
  if (!last_) {
    VehicleState s;
    s.p_W_B = params_.start_W;
    s.q_WB = Quaterniond(Eigen::AngleAxisd(params_.start_yaw_rad, Vector3d::UnitZ()));
    s.yaw_des_rad = params_.start_yaw_rad;
    s.armed = armed_;
    return s;
  }
  const double dt = std::clamp((t - last_->utime) * 1e-6, -params_.max_extrapolation_s,
                               params_.max_extrapolation_s);
  VehicleState s = last_->state;
  s.armed = armed_;
  s.p_W_B += s.v_W_B * dt;
  const Vector3d dtheta = s.omega_B * dt;
  const double angle = dtheta.norm();
  if (angle > 0)
    s.q_WB = (s.q_WB * Quaterniond(Eigen::AngleAxisd(angle, dtheta / angle))).normalized();
  return s;
}

}  // namespace alight::sim

#include "mocap/tracker.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdlib>

namespace alight::mocap {

namespace {

int64_t seconds_to_us(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

template <size_t N>
bool all_finite(const std::array<double, N>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

void add(vrpn::DecoderStats& a, const vrpn::DecoderStats& b) {
  a.bytes += b.bytes;
  a.messages += b.messages;
  a.sender_descriptions += b.sender_descriptions;
  a.type_descriptions += b.type_descriptions;
  a.poses += b.poses;
  a.velocities += b.velocities;
  a.accelerations += b.accelerations;
  a.other_messages += b.other_messages;
  a.system_ignored += b.system_ignored;
  a.bad_descriptions += b.bad_descriptions;
  a.undescribed += b.undescribed;
  a.bad_payloads += b.bad_payloads;
  a.bad_stamps += b.bad_stamps;
  a.framing_errors += b.framing_errors;
  a.cookie_errors += b.cookie_errors;
}

}  // namespace

// --- ClockMap -----------------------------------------------------------------------------------

ClockMap::ClockMap(const StampParams& params) : params_(params) {}

void ClockMap::observe(int64_t server_us, int64_t recv_utime) {
  if (params_.source != "mapped") return;
  const int64_t offset = recv_utime - server_us;
  while (!window_.empty() && window_.back().second >= offset) window_.pop_back();
  window_.emplace_back(recv_utime, offset);
  const int64_t oldest = recv_utime - seconds_to_us(params_.offset_window_s);
  while (window_.size() > 1 && window_.front().first < oldest) window_.pop_front();
}

std::optional<int64_t> ClockMap::offset_us() const {
  if (window_.empty()) return std::nullopt;
  return window_.front().second;
}

std::optional<int64_t> ClockMap::to_local(int64_t server_us, int64_t recv_utime,
                                          int64_t read_newest_us, std::string* why) const {
  const int64_t latency = seconds_to_us(params_.latency_s);
  if (params_.source == "receive")
    return recv_utime - std::max<int64_t>(0, read_newest_us - server_us) - latency;
  if (params_.source == "server") {
    const int64_t apart = recv_utime - server_us;
    if (std::llabs(apart) > seconds_to_us(params_.max_clock_offset_s)) {
      if (why)
        *why = "server stamp " + std::to_string(apart * 1e-6) +
               " s from our clock (stamp.max_clock_offset_s; stamp.source mapped takes any "
               "offset)";
      return std::nullopt;
    }
    return server_us - latency;
  }
  assert(params_.source == "mapped");
  const auto offset = offset_us();
  if (!offset) {
    if (why) *why = "no stamp observed yet";
    return std::nullopt;
  }
  return server_us + *offset - latency;
}

// --- TrackerClient
// --------------------------------------------------------------------------------

TrackerClient::TrackerClient(const MocapParams& params)
    : params_(params),
      address_(parse_tracker(params.server.tracker).value_or(TrackerAddress{})),
      frame_(params.room, params.body),
      clock_(params.stamp) {}

std::vector<uint8_t> TrackerClient::greeting(int64_t wall_utime) const {
  const auto cookie = vrpn::make_cookie(0);
  std::vector<uint8_t> out(cookie.begin(), cookie.end());
  const auto sec = static_cast<uint32_t>(wall_utime / 1000000);
  const auto usec = static_cast<uint32_t>(wall_utime % 1000000);
  const auto describe = [&](int32_t kind, int32_t id, const std::string& name) {
    const auto p = vrpn::name_payload(name);
    vrpn::append_message(out, kind, id, sec, usec, p.data(), p.size());
  };
  describe(vrpn::kSenderDescription, 0, address_.object);
  describe(vrpn::kTypeDescription, 0, vrpn::kPosQuatType);
  describe(vrpn::kTypeDescription, 1, vrpn::kVelocityType);
  describe(vrpn::kTypeDescription, 2, vrpn::kAccelerationType);
  return out;
}

void TrackerClient::reset() {
  add(finished_, decoder_.stats());
  decoder_ = vrpn::StreamDecoder();
  clock_.reset();
  history_.clear();
  last_server_us_ = -1;
  waiting_.reset();
  early_velocity_.reset();
}

void TrackerClient::end_of_stream() {
  if (!decoder_.failed() && decoder_.pending_bytes() > 0) ++stats_.truncated;
}

TrackerStats TrackerClient::stats() const {
  TrackerStats s = stats_;
  s.decoder = finished_;
  add(s.decoder, decoder_.stats());
  return s;
}

bool TrackerClient::refuse_value(const std::string& why) {
  ++stats_.rejected_values;
  stats_.last_refusal = why;
  return false;
}

std::vector<TrackerPose> TrackerClient::on_bytes(const uint8_t* data, size_t size,
                                                 int64_t recv_utime) {
  std::vector<vrpn::TrackerReport> reports;
  decoder_.feed(data, size, reports);
  const auto ours = [&](const vrpn::TrackerReport& r) {
    return r.tracker == address_.object && r.sensor == params_.server.sensor;
  };
  // The stamps of everything that arrived together first: poses read in one go then map with
  // one offset and keep their spacing.
  int64_t newest = last_server_us_;
  for (const auto& r : reports) {
    if (r.kind != vrpn::TrackerReport::Kind::kPose || !ours(r) || r.stamp_us <= newest) continue;
    clock_.observe(r.stamp_us, recv_utime);
    newest = r.stamp_us;
  }
  std::vector<TrackerPose> out;
  for (const auto& r : reports) {
    if (!ours(r)) {
      ++stats_.other_objects;
      if (trackers_seen_.size() < 16 && std::find(trackers_seen_.begin(), trackers_seen_.end(),
                                                  r.tracker) == trackers_seen_.end())
        trackers_seen_.push_back(r.tracker);
      continue;
    }
    ++stats_.reports;
    switch (r.kind) {
      case vrpn::TrackerReport::Kind::kPose:
        on_pose(r, recv_utime, newest, out);
        break;
      case vrpn::TrackerReport::Kind::kVelocity:
        on_velocity(r, out);
        break;
      case vrpn::TrackerReport::Kind::kAcceleration:
        break;  // counted by the decoder
    }
  }
  stats_.poses += out.size();
  return out;
}

void TrackerClient::on_pose(const vrpn::TrackerReport& r, int64_t recv_utime,
                            int64_t read_newest_us, std::vector<TrackerPose>& out) {
  if (!all_finite(r.v) || !all_finite(r.q_xyzw)) {
    refuse_value("non-finite position or orientation");
    return;
  }
  const Quaterniond q_RM(r.q_xyzw[3], r.q_xyzw[0], r.q_xyzw[1], r.q_xyzw[2]);
  // Not a rotation: a server's bug or a lost object, never renormalised into one (as
  // pose_from_msg).
  if (!(std::abs(q_RM.norm() - 1.0) <= 0.01)) {
    refuse_value("orientation quaternion norm " + std::to_string(q_RM.norm()) + " is not 1");
    return;
  }
  // Positions beyond a kilometre are no room's.
  if (!(frame_.metres_per_unit() * Vector3d(r.v[0], r.v[1], r.v[2]).norm() < 1000.0)) {
    refuse_value("position farther than 1 km from the room's origin");
    return;
  }
  // Receipt stamps do not need the server's to increase (some servers leave them zero).
  if (params_.stamp.source != "receive" && r.stamp_us <= last_server_us_) {
    ++stats_.rejected_stamps;
    stats_.last_refusal =
        "server stamp not after the previous one (a server whose stamps do not advance needs "
        "stamp.source receive)";
    return;
  }
  std::string why;
  const auto utime = clock_.to_local(r.stamp_us, recv_utime, read_newest_us, &why);
  if (!utime || *utime <= last_utime_) {
    ++stats_.rejected_stamps;
    stats_.last_refusal = utime ? "stamp not after the last pose published" : why;
    return;
  }
  last_server_us_ = r.stamp_us;

  const Isometry3d X_WB = frame_.X_WB(Vector3d(r.v[0], r.v[1], r.v[2]), q_RM);
  TrackerPose tp;
  tp.pose.utime = *utime;
  tp.pose.p_W_B = X_WB.translation();
  tp.pose.q_WB = Quaterniond(X_WB.linear()).normalized();
  tp.server_us = r.stamp_us;
  tp.delay_us = recv_utime - r.stamp_us;
  last_utime_ = *utime;

  const bool server_velocity = params_.velocity.source == "server";
  if (!difference(tp)) {
    ++stats_.held_back;
    if (waiting_) {  // its Velocity is not coming after a gap
      ++stats_.velocity_missing;
      out.push_back(*waiting_);
      waiting_.reset();
    }
    history_.push_back({tp.pose.utime, tp.pose.p_W_B, tp.pose.q_WB});
    return;
  }
  history_.push_back({tp.pose.utime, tp.pose.p_W_B, tp.pose.q_WB});
  const int64_t span_us = seconds_to_us(params_.velocity.span_s);
  while (history_.size() >= 2 && tp.pose.utime - history_[1].utime >= span_us) history_.pop_front();

  if (!server_velocity) {
    out.push_back(tp);
    return;
  }
  if (waiting_) {  // the previous pose's Velocity never came: it goes with its difference
    ++stats_.velocity_missing;
    out.push_back(*waiting_);
    waiting_.reset();
  }
  if (early_velocity_ && early_velocity_->stamp_us == r.stamp_us) {
    apply_server_velocity(tp, *early_velocity_);
    early_velocity_.reset();
    out.push_back(tp);
  } else {
    waiting_ = tp;
  }
}

void TrackerClient::on_velocity(const vrpn::TrackerReport& r, std::vector<TrackerPose>& out) {
  if (params_.velocity.source != "server") return;  // counted by the decoder, not used
  if (!all_finite(r.v)) {
    refuse_value("non-finite velocity");
    return;
  }
  if (waiting_ && waiting_->server_us == r.stamp_us) {
    apply_server_velocity(*waiting_, r);
    out.push_back(*waiting_);
    waiting_.reset();
  } else {
    early_velocity_ = r;
  }
}

void TrackerClient::apply_server_velocity(TrackerPose& tp, const vrpn::TrackerReport& r) const {
  // The server's velocity is the tracked object's origin's; the body origin sits at t_M_B
  // from it and moves with the (differenced) angular rate as well.
  const Matrix3d R_WB = tp.pose.q_WB.toRotationMatrix();
  const Isometry3d& X_MB = frame_.X_MB();
  const Vector3d lever_W = R_WB * X_MB.linear().transpose() * X_MB.translation();
  const Vector3d omega_W = R_WB * tp.pose.omega_B;
  tp.pose.v_W_B = frame_.to_world(Vector3d(r.v[0], r.v[1], r.v[2])) + omega_W.cross(lever_W);
  tp.server_velocity = true;
}

bool TrackerClient::difference(TrackerPose& tp) {
  if (history_.empty()) return false;
  const int64_t span_us = seconds_to_us(params_.velocity.span_s);
  const Sample* base = &history_.front();
  for (auto it = history_.rbegin(); it != history_.rend(); ++it) {
    if (tp.pose.utime - it->utime >= span_us) {
      base = &*it;
      break;
    }
  }
  const int64_t dt_us = tp.pose.utime - base->utime;
  if (dt_us <= 0 || dt_us > seconds_to_us(params_.velocity.max_gap_s)) {
    history_.clear();
    return false;
  }
  const double dt_s = dt_us * 1e-6;
  tp.pose.v_W_B = (tp.pose.p_W_B - base->p_W_B) / dt_s;
  // R_WB(t) = R_WB(t - dt) exp([omega_B] dt): the rate in body axes.
  const Eigen::AngleAxisd step(base->q_WB.conjugate() * tp.pose.q_WB);
  tp.pose.omega_B = step.axis() * (step.angle() / dt_s);
  return true;
}

}  // namespace alight::mocap

#include "ground_station/state.hpp"

#include <cassert>
#include <cmath>
#include <limits>

#include "ground_station/json_writer.hpp"

namespace alight::ground_station {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr size_t kSentCommandsKept = 20;

template <class T>
void push_bounded(std::deque<T>& q, T v, size_t max) {
  q.push_back(std::move(v));
  while (q.size() > max) q.pop_front();
}
}  // namespace

void RateMeter::add(int64_t now_utime) {
  ++count_;
  last_utime_ = now_utime;
  arrivals_.push_back(now_utime);
  while (!arrivals_.empty() && arrivals_.front() < now_utime - window_us_) arrivals_.pop_front();
}

double RateMeter::rate_hz(int64_t now_utime) const {
  while (!arrivals_.empty() && arrivals_.front() < now_utime - window_us_) arrivals_.pop_front();
  if (arrivals_.size() < 2) return 0.0;
  // Intervals within the window over the window, so a channel that stopped decays to 0 instead
  // of showing its last rate forever.
  const double span_s =
      std::max(arrivals_.back() - arrivals_.front(), now_utime - arrivals_.front()) * 1e-6;
  return span_s > 0.0 ? (arrivals_.size() - 1) / span_s : 0.0;
}

std::optional<double> RateMeter::age_s(int64_t now_utime) const {
  if (count_ == 0) return std::nullopt;
  return (now_utime - last_utime_) * 1e-6;
}

const char* phase_name(int8_t phase) {
  switch (phase) {
    case autonomy_status_t::PHASE_IDLE:
      return "IDLE";
    case autonomy_status_t::PHASE_TAKEOFF:
      return "TAKEOFF";
    case autonomy_status_t::PHASE_HOVER:
      return "HOVER";
    case autonomy_status_t::PHASE_DETECTION:
      return "DETECTION";
    case autonomy_status_t::PHASE_REFINEMENT:
      return "REFINEMENT";
    case autonomy_status_t::PHASE_APPROACH:
      return "APPROACH";
    case autonomy_status_t::PHASE_FINAL_DESCENT:
      return "FINAL_DESCENT";
    case autonomy_status_t::PHASE_LANDED:
      return "LANDED";
    case autonomy_status_t::PHASE_DONE:
      return "DONE";
    case autonomy_status_t::PHASE_HOLD:
      return "HOLD";
    case autonomy_status_t::PHASE_FAILSAFE:
      return "FAILSAFE";
    case autonomy_status_t::PHASE_KILLED:
      return "KILLED";
  }
  return "UNKNOWN";
}

const char* process_state_name(int8_t state) {
  switch (state) {
    case process_info_t::STATE_WAITING:
      return "waiting";
    case process_info_t::STATE_RUNNING:
      return "running";
    case process_info_t::STATE_BACKOFF:
      return "backoff";
    case process_info_t::STATE_EXITED:
      return "exited";
    case process_info_t::STATE_STOPPED:
      return "stopped";
    case process_info_t::STATE_FAILED:
      return "failed";
  }
  return "unknown";
}

const char* target_reason_name(int8_t reason) {
  switch (reason) {
    case target_t::REASON_OK:
      return "ok";
    case target_t::REASON_NO_POSE:
      return "no pose";
    case target_t::REASON_NO_REFERENCE:
      return "no reference";
    case target_t::REASON_TOO_FEW_FEATURES:
      return "too few features";
    case target_t::REASON_TOO_FEW_MATCHES:
      return "too few matches";
    case target_t::REASON_SMALL_BASELINE:
      return "small baseline";
    case target_t::REASON_NO_DOMINANT_PLANE:
      return "no dominant plane";
    case target_t::REASON_NO_TARGET_PLANE:
      return "no target plane";
    case target_t::REASON_NO_OPENING:
      return "no opening";
    case target_t::REASON_DECOMPOSITION_FAILED:
      return "decomposition failed";
    case target_t::REASON_BAD_IMAGE:
      return "bad image";
    case target_t::REASON_PARTIAL_VIEW:
      return "target partly out of view";
    case target_t::REASON_LOW_PARALLAX:
      return "too little parallax to measure the opening";
    case target_t::REASON_MOTION_BLUR:
      return "motion blur";
    case target_t::REASON_TOP_NOT_PARALLEL:
      return "top not parallel to the floor";
    case target_t::REASON_NO_FLOOR_AROUND_TOP:
      return "no floor around the top";
    case target_t::REASON_TOP_FITS_FLOOR:
      return "top fits the floor";
    case target_t::REASON_TOP_TILTED:
      return "top tilted";
    case target_t::REASON_HEIGHT_OUT_OF_RANGE:
      return "height out of range";
    case target_t::REASON_TOP_PHOTOMETRY:
      return "photometric check failed on the top";
    case target_t::REASON_FLOOR_PHOTOMETRY:
      return "photometric check failed on the floor";
    case target_t::REASON_TOP_FIT_DIVERGED:
      return "top's fit diverged";
    case target_t::REASON_TOP_ALONE_TOO_FEW:
      return "top alone: too few matches on it";
    case target_t::REASON_TOP_ALONE_FLOOR_SEEN:
      return "top alone: floor in sight";
    case target_t::REASON_TOP_ALONE_LOW_RISE:
      return "top alone: too little above the floor";
    case target_t::REASON_TOP_ALONE_LOW_PARALLAX:
      return "top alone: too little parallax";
    case target_t::REASON_MOTION_DISAGREES:
      return "motion disagrees with motion capture";
    case target_t::REASON_OPENING_TOO_SMALL:
      return "opening too small";
    case target_t::REASON_NOT_BEHIND_WALL:
      return "view not behind the wall";
    case target_t::REASON_PARTIAL_NOT_FRAMED:
      return "partial view without the wall around it";
    case target_t::REASON_PARTIAL_NOT_BEHIND:
      return "partial view not behind the wall";
    case target_t::REASON_EXPOSURE_CHANGE:
      return "exposure change";
    case target_t::REASON_DUPLICATE_FRAME:
      return "duplicated frame";
    case target_t::REASON_FRAME_GAP:
      return "frames missing (gap)";
    case target_t::REASON_TOP_PARALLAX_GAP:
      return "top near the epipole (parallax gap)";
    case target_t::REASON_OUTLINE_ON_FLOOR:
      return "featureless outline on the floor";
    case target_t::REASON_OUTLINE_UNMATCHED:
      return "featureless outline not in the reference";
    case target_t::REASON_OUTLINE_SILENT:
      return "featureless outline too faint to place";
    case target_t::REASON_TOP_RUNS_ON:
      return "top runs on past its features or outline";
    case target_t::REASON_TOP_TOO_SMALL:
      return "featureless outline narrower than the gear";
    case target_t::REASON_DECOMPOSITION_AMBIGUOUS:
      return "decomposition ambiguous (no prior)";
    case target_t::REASON_PLANES_DISAGREE:
      return "the two planes' motions disagree";
    case target_t::REASON_ALIGNED_PLANE_BEHIND:
      return "aligned plane behind a camera";
    case target_t::REASON_AIM_BEHIND_CAMERA:
      return "target's centre not in front of the camera";
    case target_t::REASON_CORNER_OFF_PLANE:
      return "outline corner off its plane";
    case target_t::REASON_TOP_POINTS_FEW:
      return "too few top features on its plane";
    case target_t::REASON_TOP_MATCHES_FEW:
      return "too few matches at the top's height";
    case target_t::REASON_NO_TOP_HEIGHT:
      return "nothing above the known floor";
  }
  return "unknown";
}

StationState::StationState(const GroundStationParams& params)
    : params_(params), commands_(params.ack_timeout_s, kSentCommandsKept) {
  params_.validate();
}

double StationState::t_s(int64_t utime) {
  if (!t0_utime_) t0_utime_ = utime;
  return (utime - *t0_utime_) * 1e-6;
}

void StationState::arrived(const std::string& channel, int64_t now_utime) {
  channels_[channel].add(now_utime);
}

void StationState::on_status(const autonomy_status_t& msg, int64_t now_utime,
                             std::optional<int64_t> wall_utime) {
  arrived(params_.status_channel, now_utime);
  status_ = msg;
  sample_height(msg.utime);
  // The vehicle's wall clock when it published (older autonomy: the status time).
  const int64_t vehicle_utime = msg.wall_utime != 0 ? msg.wall_utime : msg.utime;
  // In double: a hostile stamp must not overflow the subtraction (found by fuzzing).
  clock_offset_s_ =
      (static_cast<double>(wall_utime.value_or(now_utime)) - static_cast<double>(vehicle_utime)) *
      1e-6;
  commands_.on_status(msg, now_utime);
}

void StationState::on_pose(const pose_t& msg, int64_t now_utime) {
  arrived(params_.pose_channel, now_utime);
  pose_ = msg;
  const int64_t period_us = static_cast<int64_t>(params_.track_period_s * 1e6);
  // A time jump backwards (log replayed again, simulator restarted) starts a new track.
  if (last_track_utime_ != INT64_MIN && msg.utime < last_track_utime_) {
    track_.clear();
    heights_.clear();
    measurements_.clear();
    target_reasons_.clear();
    t0_utime_.reset();
    last_height_utime_ = INT64_MIN;
    last_track_utime_ = INT64_MIN;
  }
  if (last_track_utime_ == INT64_MIN || msg.utime - last_track_utime_ >= period_us) {
    last_track_utime_ = msg.utime;
    TrackPoint p{t_s(msg.utime), {msg.pos[0], msg.pos[1], msg.pos[2]}};
    push_bounded(track_, p, params_.track_max_points);
  }
  sample_height(msg.utime);
}

void StationState::sample_height(int64_t utime) {
  const int64_t period_us = static_cast<int64_t>(params_.track_period_s * 1e6);
  if (last_height_utime_ != INT64_MIN && utime - last_height_utime_ < period_us &&
      utime >= last_height_utime_)
    return;
  last_height_utime_ = utime;
  HeightPoint h{t_s(utime), kNaN, kNaN, kNaN};
  if (pose_) h.vehicle_z_m = pose_->pos[2];
  if (status_ && status_->has_estimate) {
    h.estimate_z_m = status_->estimate_W[2];
    h.sigma_z_m = std::sqrt(std::max(0.0, status_->covariance[8]));
  }
  push_bounded(heights_, h, params_.track_max_points);
}

void StationState::on_target(const target_t& msg, int64_t now_utime) {
  arrived(params_.target_channel, now_utime);
  target_ = msg;
  ++target_reasons_[msg.reason];
  if (msg.found) {
    Measurement m{t_s(msg.utime), {msg.p_W_target[0], msg.p_W_target[1], msg.p_W_target[2]}};
    push_bounded(measurements_, m, params_.measurements_max);
  }
}

void StationState::on_autopilot_status(const autopilot_status_t& msg, int64_t now_utime) {
  arrived(params_.autopilot_channel, now_utime);
  autopilot_ = msg;
  autopilot_arrival_utime_ = now_utime;
}

void StationState::on_node_status(const node_status_t& msg, int64_t now_utime) {
  arrived(params_.node_status_channel, now_utime);
  // Bounded: a node per name, and no more names than a launch file has processes (an attacker
  // inventing names must not grow the page).
  constexpr size_t kMaxNodes = 64;
  if (nodes_.size() >= kMaxNodes && !nodes_.count(msg.node)) return;
  nodes_[msg.node] = NodeReport{msg, now_utime};
}

void StationState::on_process_status(const process_status_t& msg, int64_t now_utime,
                                     std::optional<int64_t> wall_utime) {
  arrived(params_.process_channel, now_utime);
  processes_ = msg;
  processes_age_at_arrival_us_ = wall_utime.value_or(now_utime) - msg.utime;
  processes_arrival_utime_ = now_utime;
}

void StationState::on_frame(const std::string& channel, int64_t frame_utime, int64_t now_utime,
                            std::optional<int64_t> wall_utime) {
  arrived(channel, now_utime);
  frames_[channel] = FrameArrival{wall_utime.value_or(now_utime) - frame_utime, now_utime};
}

void StationState::on_command_sent(const std::string& name, int64_t seq, int64_t session,
                                   int64_t now_utime) {
  commands_.sent(name, seq, session, now_utime);
}

int64_t StationState::vehicle_session() const {
  if (!status_ || status_->vehicle_id != params_.vehicle_id) return 0;
  return status_->cmd_session;
}

double StationState::channel_rate_hz(const std::string& channel, int64_t now_utime) const {
  auto it = channels_.find(channel);
  return it == channels_.end() ? 0.0 : it->second.rate_hz(now_utime);
}

std::optional<double> StationState::channel_age_s(const std::string& channel,
                                                  int64_t now_utime) const {
  auto it = channels_.find(channel);
  return it == channels_.end() ? std::nullopt : it->second.age_s(now_utime);
}

std::string StationState::to_json(int64_t now_utime, const std::string& extra) const {
  JsonWriter w;
  w.begin_object();
  w.field("now_utime", now_utime);

  w.key("status");
  if (!status_) {
    w.value(std::string("none"));
  } else {
    const auto& s = *status_;
    w.begin_object();
    w.field("utime", s.utime);
    w.field("phase", static_cast<int>(s.phase));
    w.field("phase_name", s.phase_name.empty() ? std::string(phase_name(s.phase)) : s.phase_name);
    w.field("mission", static_cast<int>(s.mission));
    w.field("reason", s.reason);
    w.field("n_measurements", static_cast<int>(s.n_measurements));
    w.field("n_rejected", static_cast<int>(s.n_rejected));
    w.field("retries", static_cast<int>(s.retries));
    w.field("has_estimate", s.has_estimate != 0);
    w.key("estimate_W").begin_array();
    for (double v : s.estimate_W) w.value(v);
    w.end_array();
    w.key("covariance").begin_array();
    for (double v : s.covariance) w.value(v);
    w.end_array();
    w.key("setpoint_W").begin_array();
    for (double v : s.setpoint_W) w.value(v);
    w.end_array();
    w.field("failsafe", static_cast<int>(s.failsafe));
    w.field("cmds_rejected", static_cast<int>(s.cmds_rejected));
    w.field("last_cmd_seq", s.last_cmd_seq);
    w.field("geofence_clamped", s.geofence_clamped != 0);
    w.field("mission_time_s", s.mission_time_s);
    w.field("vehicle_id", s.vehicle_id);
    w.field("cmd_session", s.cmd_session);
    w.field("last_rejected_seq", s.last_rejected_seq);
    w.key("cmds_rejected_by_reason").begin_object();
    for (int r = 1; r < 8; ++r)
      if (s.cmds_rejected_by_reason[r] > 0)
        w.field(reject_reason_name(static_cast<int8_t>(r)),
                static_cast<int>(s.cmds_rejected_by_reason[r]));
    w.end_object();
    w.field(
        "last_reject_reason",
        std::string(s.last_reject_reason == 0 ? "none" : reject_reason_name(s.last_reject_reason)));
    w.end_object();
  }

  w.key("pose");
  if (!pose_) {
    w.value(std::string("none"));
  } else {
    w.begin_object().key("p_W").begin_array();
    for (double v : pose_->pos) w.value(v);
    w.end_array().key("v_W").begin_array();
    for (double v : pose_->vel) w.value(v);
    w.end_array().end_object();
  }

  w.key("target");
  if (!target_) {
    w.value(std::string("none"));
  } else {
    const auto& t = *target_;
    w.begin_object();
    w.field("utime", t.utime);
    w.field("seq", t.seq);
    w.field("mission", static_cast<int>(t.mission));
    w.field("found", t.found != 0);
    w.field("reason", std::string(target_reason_name(t.reason)));
    w.key("p_W_target").begin_array();
    for (double v : t.p_W_target) w.value(v);
    w.end_array();
    w.field("target_height_m", t.target_height_m);
    w.key("size_m").begin_array().value(t.size_m[0]).value(t.size_m[1]).end_array();
    w.field("baseline_m", t.baseline_m);
    w.field("n_features", static_cast<int>(t.n_features));
    w.field("n_matches", static_cast<int>(t.n_matches));
    w.field("n_inliers_dominant", static_cast<int>(t.n_inliers_dominant));
    w.field("n_inliers_target", static_cast<int>(t.n_inliers_target));
    w.end_object();
  }
  // Every target's reason counted since the start (or the last jump back in time): which gate
  // refuses the frames, as alight-vision-eval prints it for a log.
  w.key("target_reasons").begin_object();
  for (const auto& [reason, n] : target_reasons_) w.field(target_reason_name(reason), n);
  w.end_object();

  w.key("channels").begin_object();
  for (const auto& [name, meter] : channels_) {
    const auto age = meter.age_s(now_utime);
    w.key(name).begin_object();
    w.field("count", static_cast<uint64_t>(meter.count()));
    w.field("rate_hz", meter.rate_hz(now_utime));
    w.field("age_s", age ? *age : kNaN);
    w.field("stale", !age || *age > params_.channel_stale_s);
    auto f = frames_.find(name);
    if (f != frames_.end())
      w.field("frame_latency_s",
              (f->second.latency_us + (now_utime - f->second.arrival_utime)) * 1e-6);
    w.end_object();
  }
  w.end_object();

  w.key("processes");
  if (!processes_) {
    w.value(std::string("none"));
  } else {
    w.begin_object();
    w.field("launch_name", processes_->launch_name);
    w.field("age_s",
            (processes_age_at_arrival_us_ + (now_utime - processes_arrival_utime_)) * 1e-6);
    w.key("list").begin_array();
    for (const auto& p : processes_->processes) {
      w.begin_object();
      w.field("name", p.name);
      w.field("pid", static_cast<int>(p.pid));
      w.field("state", std::string(process_state_name(p.state)));
      w.field("exit_code", static_cast<int>(p.exit_code));
      w.field("signal", static_cast<int>(p.signal));
      w.field("restarts", static_cast<int>(p.restarts));
      w.end_object();
    }
    w.end_array().end_object();
  }

  // The bus: which nodes sign it, and every channel where a node refused messages for their
  // origin. Any such count is an alarm: a misconfigured node, or someone publishing on the bus.
  w.key("bus").begin_object();
  bool alarm = false;
  w.key("nodes").begin_array();
  for (const auto& [name, r] : nodes_) {
    w.begin_object();
    w.field("node", name);
    w.field("signed", static_cast<bool>(r.msg.signed_bus));
    w.field("clock_from_inputs", static_cast<bool>(r.msg.clock_from_inputs));
    w.field("age_s", (now_utime - r.arrival_utime) * 1e-6);
    w.key("refused").begin_array();
    for (const auto& c : r.msg.channels) {
      if (c.rejected_auth == 0 && c.second_publisher == 0) continue;
      alarm = true;
      w.begin_object();
      w.field("channel", c.channel);
      w.field("rejected_auth", static_cast<double>(c.rejected_auth));
      w.field("second_publisher", static_cast<double>(c.second_publisher));
      w.end_object();
    }
    w.end_array();
    w.end_object();
  }
  w.end_array();
  w.field("alarm", alarm);
  w.end_object();

  // The autopilot (alight-mavlink): its heartbeat age grows with the station's clock from the
  // report's arrival, so a bridge that went silent shows an ageing link, not a frozen one.
  w.key("autopilot");
  if (!autopilot_) {
    w.value(std::string("none"));
  } else {
    const autopilot_status_t& a = *autopilot_;
    const double since_s = (now_utime - autopilot_arrival_utime_) * 1e-6;
    w.begin_object();
    w.field("autopilot",
            std::string(a.autopilot == autopilot_status_t::AUTOPILOT_PX4 ? "PX4" : "ArduPilot"));
    w.field("link_up", a.link_up && since_s <= params_.channel_stale_s);
    w.field("heartbeat_age_s", a.heartbeat_age_s < 0 ? -1.0 : a.heartbeat_age_s + since_s);
    w.field("report_age_s", since_s);
    w.field("mode", a.mode);
    w.field("armed", static_cast<bool>(a.armed));
    w.field("offboard", static_cast<bool>(a.offboard));
    w.field("engage", a.engage);
    w.field("streaming", static_cast<bool>(a.streaming));
    w.field("last_command", a.last_command);
    w.field("last_result", static_cast<int>(a.last_result));
    w.field("last_statustext", a.last_statustext);
    w.field("battery_V", a.battery_V);
    w.field("firmware", a.firmware);
    w.field("accel_feedforward", static_cast<bool>(a.accel_feedforward));
    w.field("crc_errors", static_cast<double>(a.crc_errors));
    w.field("link_losses", static_cast<double>(a.link_losses));
    w.end_object();
  }

  // Plot series as flat arrays [t, x, y, z, ...] to keep the document small.
  w.key("track").begin_array();
  for (const auto& p : track_) w.value(p.t_s).value(p.p_W[0]).value(p.p_W[1]).value(p.p_W[2]);
  w.end_array();
  w.key("heights").begin_array();
  for (const auto& h : heights_)
    w.value(h.t_s).value(h.vehicle_z_m).value(h.estimate_z_m).value(h.sigma_z_m);
  w.end_array();
  w.key("measurements").begin_array();
  for (const auto& m : measurements_)
    w.value(m.t_s).value(m.p_W[0]).value(m.p_W[1]).value(m.p_W[2]);
  w.end_array();

  w.key("sent").begin_array();
  for (const auto& c : commands_.commands()) {
    const AckState state = commands_.state_at(c, now_utime);
    w.begin_object()
        .field("name", c.name)
        .field("seq", c.seq)
        .field("age_s", (now_utime - c.sent_utime) * 1e-6)
        .field("state", std::string(ack_state_name(state)));
    if (state == AckState::kAcknowledged || state == AckState::kRejected)
      w.field("answer_s", (c.answered_utime - c.sent_utime) * 1e-6);
    if (state == AckState::kRejected) w.field("reject_reason", c.reject_reason);
    w.end_object();
  }
  w.end_array();

  // The operator link: who is commanded, whether the clocks agree, and the alarm for a command
  // the vehicle did not acknowledge.
  w.key("link").begin_object();
  w.field("vehicle_id", params_.vehicle_id);
  w.field("session_known", vehicle_session() != 0);
  w.field("vehicle_seen", status_.has_value());
  if (status_ && status_->vehicle_id != params_.vehicle_id)
    w.field("other_vehicle_id", status_->vehicle_id);
  w.field("clock_offset_s", clock_offset_s_ ? *clock_offset_s_ : kNaN);
  w.field("clock_offset_warn",
          clock_offset_s_ && std::abs(*clock_offset_s_) > params_.clock_offset_warn_s);
  w.field("ack_timeout_s", params_.ack_timeout_s);
  if (const TrackedCommand* a = commands_.alarm(now_utime)) {
    w.key("alarm").begin_object();
    w.field("name", a->name).field("seq", a->seq);
    w.field("age_s", (now_utime - a->sent_utime) * 1e-6);
    w.end_object();
  } else {
    w.field("alarm", std::string("none"));
  }
  w.end_object();

  std::string out = w.str();
  out += ",\"station\":";
  out += extra;
  out += '}';
  return out;
}

}  // namespace alight::ground_station

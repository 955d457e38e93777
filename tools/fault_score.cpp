#include "tools/fault_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/channels.hpp"

namespace alight::tools {

namespace {

bool airborne_mission_phase(int8_t phase) {
  switch (phase) {
    case autonomy_status_t::PHASE_TAKEOFF:
    case autonomy_status_t::PHASE_DETECTION:
    case autonomy_status_t::PHASE_REFINEMENT:
    case autonomy_status_t::PHASE_APPROACH:
    case autonomy_status_t::PHASE_FINAL_DESCENT:
      return true;
    default:
      return false;
  }
}

bool descent_mode(int8_t mode) {
  return mode == attitude_cmd_t::MODE_FAILSAFE_DESCENT ||
         mode == attitude_cmd_t::MODE_SETPOINT_LOST_DESCENT;
}

// "alight-outer-loop" -> "outer_loop": the launcher's name of the process a node runs in.
std::string process_of_node(const std::string& node) {
  std::string n = node.rfind("alight-", 0) == 0 ? node.substr(7) : node;
  std::replace(n.begin(), n.end(), '-', '_');
  return n;
}

std::string json_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

void FaultScorer::seen(int64_t received_utime) {
  if (!first_received_) first_received_ = received_utime;
  last_received_ = std::max(last_received_.value_or(received_utime), received_utime);
}

bool FaultScorer::fresh(const std::string& channel, int64_t utime, int64_t received_utime) {
  const auto it = last_utime_.find(channel);
  // Not older: several commands may be computed from one pose and share its stamp.
  const bool newer = it == last_utime_.end() || utime >= it->second;
  const bool plausible =
      utime > 0 && utime <= received_utime + static_cast<int64_t>(params_.stamp_ahead_s * 1e6);
  if (!newer || !plausible) {
    ++refused_;
    return false;
  }
  last_utime_[channel] = utime;
  return true;
}

double FaultScorer::height_above_surface(const sim_truth_t& t) const {
  double surface_z = 0.0;
  if (t.has_platform) {
    const double dx = t.pos[0] - t.platform_center_W[0], dy = t.pos[1] - t.platform_center_W[1];
    const double c = std::cos(t.platform_yaw_rad), s = std::sin(t.platform_yaw_rad);
    const double along = c * dx + s * dy, across = -s * dx + c * dy;
    if (std::abs(along) <= 0.5 * t.platform_size_m[0] &&
        std::abs(across) <= 0.5 * t.platform_size_m[1])
      surface_z = t.platform_center_W[2];
  }
  // The body origin of a vehicle at rest on the floor sits this high (landing gear).
  const double rest_z = first_truth_ ? first_truth_->pos[2] : 0.0;
  return t.pos[2] - surface_z - rest_z;
}

void FaultScorer::add(const sim_truth_t& m, int64_t received_utime) {
  seen(received_utime);
  if (!fresh(channels::kSimTruth, m.utime, received_utime)) return;
  if (!first_truth_) first_truth_ = m;
  if (last_truth_ && last_truth_->armed && !m.armed) {
    ++disarms_;
    const double h = height_above_surface(m);
    max_disarm_m_ = std::max(max_disarm_m_.value_or(h), h);
  }
  if (last_truth_ && last_truth_->contact == sim_truth_t::CONTACT_NONE &&
      m.contact != sim_truth_t::CONTACT_NONE)
    touchdown_mps_ = std::max(touchdown_mps_.value_or(0.0), -last_truth_->vel[2]);
  flew_ = flew_ || height_above_surface(m) > params_.airborne_height_m;
  collided_ = collided_ || m.collided;
  tipped_ = tipped_ || m.tipped;
  out_of_area_ = out_of_area_ || m.out_of_area;
  last_truth_ = m;
  mission_.add(m);
}

void FaultScorer::add(const attitude_cmd_t& m, int64_t received_utime) {
  seen(received_utime);
  if (!fresh(channels::kAttitudeCmd, m.utime, received_utime)) return;
  if (descent_mode(m.mode) && m.armed) failsafe_seen_ = true;
  last_cmd_ = m;
  last_cmd_received_ = received_utime;
}

void FaultScorer::add(const autonomy_status_t& m, int64_t received_utime) {
  seen(received_utime);
  if (!fresh(channels::kAutonomyStatus, m.utime, received_utime)) return;
  if (m.phase == autonomy_status_t::PHASE_FAILSAFE) failsafe_seen_ = true;
  last_status_ = m;
  last_status_received_ = received_utime;
  mission_.add(m);
}

void FaultScorer::add(const process_status_t& m, int64_t received_utime) {
  seen(received_utime);
  if (!fresh(channels::kProcessStatus, m.utime, received_utime)) return;
  for (const auto& p : m.processes) {
    if (p.state == process_info_t::STATE_STOPPED && !shutdown_received_)
      shutdown_received_ = received_utime;
    const auto it = procs_.find(p.name);
    if (it != procs_.end()) {
      const process_info_t& before = it->second;
      const bool gone = p.state == process_info_t::STATE_BACKOFF ||
                        p.state == process_info_t::STATE_EXITED ||
                        p.state == process_info_t::STATE_FAILED;
      // An exit: the process left RUNNING, or (statuses lost in between) it restarted.
      const int missed = std::max(0, p.restarts - before.restarts -
                                         (before.state == process_info_t::STATE_BACKOFF ? 1 : 0));
      int n = missed + (gone && before.state == process_info_t::STATE_RUNNING ? 1 : 0);
      for (; n > 0; --n) {
        ProcessExit e;
        e.name = p.name;
        e.exit_code = p.exit_code;
        e.signal = p.signal;
        e.t_s = 1e-6 * static_cast<double>(received_utime - *first_received_);
        exits_.push_back(e);
      }
    }
    procs_[p.name] = p;
  }
}

void FaultScorer::add(const node_status_t& m, int64_t received_utime) {
  seen(received_utime);
  NodeSeen& n = nodes_[m.node];
  // A copy of a status (injected, replayed) repeats its uptime; a restart changes the pid.
  if (n.count > 0 && m.pid == n.pid && !(m.uptime_s > n.uptime_s)) {
    ++refused_;
    return;
  }
  n.pid = m.pid;
  n.uptime_s = m.uptime_s;
  n.last_received = received_utime;
  ++n.count;
}

FaultOutcome FaultScorer::result() const {
  FaultOutcome r;
  r.refused_messages = refused_;
  r.disarms = disarms_;
  r.max_disarm_height_m = max_disarm_m_;
  r.max_touchdown_speed_mps = touchdown_mps_;
  r.collided = collided_;
  r.failsafe_descent_seen = failsafe_seen_;
  if (last_status_) r.final_phase = last_status_->phase_name;
  if (last_cmd_) r.final_attitude_mode = last_cmd_->mode;
  const Score mission = mission_.result();
  r.mission_outcome = mission.outcome;

  // Exits: the first SIGKILL of the process the campaign kills is the fault; the rest are not.
  bool expected_used = false;
  for (ProcessExit e : exits_) {
    if (!expected_used && !params_.expected_exit.empty() && e.name == params_.expected_exit &&
        e.signal == 9) {
      e.expected = true;
      expected_used = true;
    } else {
      ++r.unexpected_exits;
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s exited at %.1f s (exit code %d, signal %d)",
                    e.name.c_str(), e.t_s, e.exit_code, e.signal);
      r.violations.push_back(buf);
    }
    r.exits.push_back(e);
  }
  if (!params_.expected_exit.empty() && !expected_used)
    r.violations.push_back("the fault did not happen: no SIGKILL of " + params_.expected_exit);

  // Hung nodes: running at the end of the run (before the shutdown) but silent on NODE_STATUS.
  const int64_t end_utime = shutdown_received_.value_or(last_received_.value_or(0));
  const auto silent_us = static_cast<int64_t>(params_.node_silent_s * 1e6);
  for (const auto& [node, seen] : nodes_) {
    if (seen.count < 3) continue;  // not a node of this session (an injected made-up status)
    const auto proc = procs_.find(process_of_node(node));
    if (proc == procs_.end() || proc->second.state != process_info_t::STATE_RUNNING) continue;
    if (proc->second.started_utime > end_utime - 2 * silent_us) continue;  // just restarted
    if (seen.last_received < end_utime - silent_us) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s silent for the last %.1f s (no NODE_STATUS)", node.c_str(),
                    1e-6 * static_cast<double>(end_utime - seen.last_received));
      r.silent_nodes.push_back(node);
      r.violations.push_back(buf);
    }
  }

  if (!last_truth_) {
    r.outcome = "no_truth";
    r.violations.push_back("no SIM_TRUTH in the log");
    r.ok = false;
    return r;
  }
  const sim_truth_t& t = *last_truth_;
  r.final_height_m = height_above_surface(t);
  r.final_speed_mps = std::sqrt(t.vel[0] * t.vel[0] + t.vel[1] * t.vel[1] + t.vel[2] * t.vel[2]);
  const bool airborne = r.final_height_m > params_.airborne_height_m;
  const bool cmd_lost =
      !last_cmd_ || *last_received_ - last_cmd_received_ > params_.command_lost_s * 1e6;

  if (max_disarm_m_ && *max_disarm_m_ > params_.disarm_max_height_m) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "disarmed %.2f m above the surface (limit %.2f m)",
                  *max_disarm_m_, params_.disarm_max_height_m);
    r.violations.push_back(buf);
  }
  if (tipped_) r.violations.push_back("the vehicle tipped off an edge");
  if (collided_) r.violations.push_back("contact with the wall or the opening's frame");
  if (out_of_area_) r.violations.push_back("the vehicle left the flying area");

  if (out_of_area_) {
    r.outcome = "left_area";
  } else if (tipped_) {
    r.outcome = "tipped";
  } else if (collided_) {
    r.outcome = "collision";
  } else if (max_disarm_m_ && *max_disarm_m_ > params_.disarm_max_height_m) {
    r.outcome = "disarmed_in_air";
  } else if (mission.success) {
    r.outcome = mission.outcome;  // landed / through
  } else if (airborne && t.armed) {
    const bool descending_failsafe =
        (last_cmd_ && descent_mode(last_cmd_->mode) && !cmd_lost) || (cmd_lost && t.vel[2] < -0.05);
    const bool autonomy_flying = last_status_ && airborne_mission_phase(last_status_->phase) &&
                                 *last_received_ - last_status_received_ < 2000000;
    if (descending_failsafe) {
      r.outcome = "failsafe_descent";
    } else if (autonomy_flying) {
      r.outcome = "in_mission";
      r.violations.push_back("still flying " + last_status_->phase_name +
                             " when the run ended (give it more time)");
    } else if (r.final_speed_mps < params_.hold_speed_mps) {
      r.outcome = "safe_hold";
    } else {
      char buf[96];
      std::snprintf(buf, sizeof buf, "moving at %.2f m/s, %.2f m up, in no hold or descent",
                    r.final_speed_mps, r.final_height_m);
      r.outcome = "uncontrolled";
      r.violations.push_back(buf);
    }
  } else if (airborne) {
    r.outcome = "disarmed_in_air";  // falling at the end of the log: the disarm was just now
    r.violations.push_back("motors off in the air at the end of the run");
  } else {
    if (failsafe_seen_) {
      r.outcome = "failsafe_descent";
    } else if (flew_) {
      r.outcome = "came_down";
      r.violations.push_back(
          "came down to the ground with no landing, failsafe descent or hold commanded");
    } else {
      r.outcome = "grounded";  // never left the ground: nothing was put at risk
    }
  }
  r.ok = r.violations.empty();
  return r;
}

std::string FaultOutcome::to_json() const {
  std::string s = "{";
  auto field = [&](const std::string& k, const std::string& v) {
    if (s.size() > 1) s += ", ";
    s += "\"" + k + "\": " + v;
  };
  auto str = [](const std::string& v) { return "\"" + json_escape(v) + "\""; };
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", v);
    return std::string(buf);
  };
  field("outcome", str(outcome));
  field("ok", ok ? "true" : "false");
  field("max_disarm_height_m", max_disarm_height_m ? num(*max_disarm_height_m) : "null");
  field("disarms", std::to_string(disarms));
  field("max_touchdown_speed_mps",
        max_touchdown_speed_mps ? num(*max_touchdown_speed_mps) : "null");
  field("collided", collided ? "true" : "false");
  field("unexpected_exits", std::to_string(unexpected_exits));
  std::string ex = "[";
  for (const auto& e : exits) {
    if (ex.size() > 1) ex += ", ";
    ex += "{\"name\": " + str(e.name) + ", \"exit_code\": " + std::to_string(e.exit_code) +
          ", \"signal\": " + std::to_string(e.signal) + ", \"t_s\": " + num(e.t_s) +
          ", \"expected\": " + (e.expected ? "true" : "false") + "}";
  }
  field("exits", ex + "]");
  std::string sn = "[";
  for (const auto& n : silent_nodes) sn += (sn.size() > 1 ? ", " : "") + str(n);
  field("silent_nodes", sn + "]");
  field("final_phase", str(final_phase));
  field("final_attitude_mode", std::to_string(final_attitude_mode));
  field("failsafe_descent_seen", failsafe_descent_seen ? "true" : "false");
  field("final_height_m", num(final_height_m));
  field("final_speed_mps", num(final_speed_mps));
  field("mission_outcome", str(mission_outcome));
  field("refused_messages", std::to_string(refused_messages));
  std::string v = "[";
  for (const auto& x : violations) v += (v.size() > 1 ? ", " : "") + str(x);
  field("violations", v + "]");
  return s + "}\n";
}

}  // namespace alight::tools

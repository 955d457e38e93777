#include "tools/monitor.hpp"

#include <cmath>
#include <cstdio>

namespace alight::tools {

std::string MissionMonitor::stamp(int64_t utime) const {
  char buf[32];
  std::snprintf(buf, sizeof buf, "[%7.1f s] ",
                1e-6 * static_cast<double>(utime - t0_.value_or(utime)));
  return buf;
}

std::string MissionMonitor::estimate_text(const autonomy_status_t& s) const {
  if (!s.has_estimate) return "";
  char buf[256];
  std::snprintf(buf, sizeof buf, "estimate (%.3f, %.3f, %.3f) m, spread %.1f cm", s.estimate_W[0],
                s.estimate_W[1], s.estimate_W[2],
                100.0 * std::sqrt(std::max(0.0, s.covariance[0] + s.covariance[4])));
  std::string text = buf;
  if (truth_) {
    const bool landing = s.mission == 1 && truth_->has_platform;
    const double* c = landing ? truth_->platform_center_W : truth_->opening_center_W;
    if (landing || truth_->has_opening) {
      std::snprintf(buf, sizeof buf, "; vs truth: lateral %.1f cm, height %+.1f cm",
                    100.0 * std::hypot(s.estimate_W[0] - c[0], s.estimate_W[1] - c[1]),
                    100.0 * (s.estimate_W[2] - c[2]));
      text += buf;
    }
  }
  return text;
}

void MissionMonitor::finish(End end, const std::string& reason, std::vector<std::string>& out) {
  end_ = end;
  end_reason_ = reason;
  out.push_back(std::string(end == End::kSuccess ? "mission complete: " : "mission failed: ") +
                reason);
}

void MissionMonitor::check_landed(int64_t utime, std::vector<std::string>& out) {
  if (end_ != End::kNone) return;
  if (!truth_) {  // no simulator (a real flight): the autonomy's touch-down detection stands
    finish(End::kSuccess, "landed", out);
  } else if (truth_->tipped) {
    finish(End::kFailure, "landed but tipped off the edge", out);
  } else if (truth_->landed) {
    finish(End::kSuccess, "landed", out);
  } else if (utime - *landed_utime_ > params_.settle_s * 1e6) {
    finish(End::kFailure, "motors off, but not at rest on the platform top", out);
  }
}

std::vector<std::string> MissionMonitor::add(const autonomy_status_t& s) {
  std::vector<std::string> out;
  if (end_ != End::kNone) return out;
  if (!t0_) t0_ = s.utime;
  const bool phase_changed = !last_ || last_->phase != s.phase;
  if (phase_changed) {
    std::string line = stamp(s.utime) + s.phase_name;
    if (!s.reason.empty()) line += " (" + s.reason + ")";
    const std::string est = estimate_text(s);
    if (!est.empty()) line += ": n = " + std::to_string(s.n_measurements) + ", " + est;
    out.push_back(line);
    last_progress_utime_ = s.utime;
  } else if (s.n_measurements != last_count_ &&
             s.utime - last_progress_utime_ >= params_.progress_period_s * 1e6) {
    out.push_back(stamp(s.utime) + "  n = " + std::to_string(s.n_measurements) +
                  (s.n_rejected ? " (" + std::to_string(s.n_rejected) + " rejected)" : "") + ", " +
                  estimate_text(s));
    last_progress_utime_ = s.utime;
  }
  last_count_ = s.n_measurements;
  last_ = s;
  switch (s.phase) {
    case autonomy_status_t::PHASE_LANDED:
      if (!landed_utime_) landed_utime_ = s.utime;
      check_landed(s.utime, out);
      break;
    case autonomy_status_t::PHASE_DONE:
      finish(
          truth_ && truth_->collided ? End::kFailure : End::kSuccess,
          truth_ && truth_->collided ? "through the opening, with contact" : "through the opening",
          out);
      break;
    case autonomy_status_t::PHASE_KILLED:
      finish(End::kFailure, "motors killed", out);
      break;
    case autonomy_status_t::PHASE_HOLD:  // retries exhausted, a refusal or an abort
      finish(End::kFailure, "holding: " + s.reason, out);
      break;
    default:
      break;
  }
  if (end_ == End::kNone && s.utime - *t0_ > params_.timeout_s * 1e6)
    finish(End::kFailure,
           "no result within " + std::to_string(static_cast<int>(params_.timeout_s)) + " s", out);
  return out;
}

std::vector<std::string> MissionMonitor::add(const sim_truth_t& t) {
  std::vector<std::string> out;
  const bool newly_tipped = t.tipped && !(truth_ && truth_->tipped);
  const bool newly_collided = t.collided && !(truth_ && truth_->collided);
  const bool newly_out = t.out_of_area && !(truth_ && truth_->out_of_area);
  truth_ = t;
  if (end_ != End::kNone) return out;
  if (!t0_) t0_ = t.utime;
  if (newly_tipped) finish(End::kFailure, "the vehicle tipped off the platform edge", out);
  if (newly_out && end_ == End::kNone)
    finish(End::kFailure, "the vehicle left the flying area", out);
  if (end_ == End::kNone && landed_utime_) check_landed(t.utime, out);
  if (newly_collided)
    out.push_back(stamp(t.utime) + "contact with the wall or the opening's frame");
  return out;
}

}  // namespace alight::tools

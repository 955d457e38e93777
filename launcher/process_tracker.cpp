#include "launcher/process_tracker.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>

namespace alight::launcher {

const char* to_string(ProcState s) {
  switch (s) {
    case ProcState::kWaiting:
      return "waiting";
    case ProcState::kRunning:
      return "running";
    case ProcState::kBackoff:
      return "backoff";
    case ProcState::kExited:
      return "exited";
    case ProcState::kStopped:
      return "stopped";
    case ProcState::kFailed:
      return "failed";
  }
  return "?";
}

ProcessTracker::ProcessTracker(ProcessSpec spec, BackoffParams backoff)
    : spec_(std::move(spec)), backoff_(backoff) {}

void ProcessTracker::started(int pid, int64_t now) {
  assert(pid > 0);
  if (state_ == ProcState::kBackoff) ++restarts_;
  state_ = ProcState::kRunning;
  pid_ = pid;
  started_utime_ = now;
  reason_.clear();
}

void ProcessTracker::start_failed(const std::string& why, int64_t now) {
  // A failed start is an attempt like any other: it counts against the limit and backs off.
  if (state_ == ProcState::kBackoff) ++restarts_;
  started_utime_ = now;
  ended(127, 0, now, why);
}

void ProcessTracker::exited(int exit_code, int signal, int64_t now) {
  ended(exit_code, signal, now,
        signal ? "killed by signal " + std::to_string(signal)
               : "exited with code " + std::to_string(exit_code));
}

void ProcessTracker::ended(int exit_code, int signal, int64_t now, const std::string& reason) {
  pid_ = 0;
  exit_code_ = exit_code;
  signal_ = signal;
  if (stopping_) {
    state_ = ProcState::kStopped;
    return;
  }
  const bool success = signal == 0 && exit_code == 0;
  reason_ = reason;
  if (spec_.shutdown_on_exit) {
    ended_session_ = true;
    state_ = success ? ProcState::kExited : ProcState::kFailed;
    return;
  }
  // Exit code 2 is alight's configuration error (run_node_main: bad parameter, missing file);
  // a restart reads the same files and fails the same way, hundreds of times a session.
  if (signal == 0 && exit_code == kConfigErrorExitCode) {
    state_ = ProcState::kFailed;
    reason_ += " (configuration error: not restarted)";
    return;
  }
  const bool restart = spec_.restart == RestartPolicy::kAlways ||
                       (spec_.restart == RestartPolicy::kOnFailure && !success);
  if (!restart) {
    state_ = success ? ProcState::kExited : ProcState::kFailed;
    return;
  }
  if (spec_.max_restarts >= 0 && restarts_ >= spec_.max_restarts) {
    state_ = ProcState::kFailed;
    reason_ += ", restart limit " + std::to_string(spec_.max_restarts) + " reached";
    return;
  }
  const double ran_s = 1e-6 * static_cast<double>(now - started_utime_);
  const bool quick = ran_s < backoff_.reset_after_s;
  if (backoff_.start_limit_burst > 0 && quick && !success) {
    const int64_t window_us = static_cast<int64_t>(backoff_.start_limit_interval_s * 1e6);
    quick_failures_utime_.push_back(now);
    while (!quick_failures_utime_.empty() && now - quick_failures_utime_.front() > window_us)
      quick_failures_utime_.pop_front();
    if (static_cast<int>(quick_failures_utime_.size()) >= backoff_.start_limit_burst) {
      state_ = ProcState::kFailed;
      char buf[128];
      std::snprintf(buf, sizeof buf,
                    ", start limit: %d quick failures within %.0f s (not restarted)",
                    backoff_.start_limit_burst, backoff_.start_limit_interval_s);
      reason_ += buf;
      return;
    }
  }
  consecutive_crashes_ = quick ? consecutive_crashes_ + 1 : 0;
  backoff_s_ = std::min(backoff_.max_s,
                        backoff_.initial_s * std::pow(2.0, std::max(0, consecutive_crashes_ - 1)));
  next_start_utime_ = now + static_cast<int64_t>(std::llround(backoff_s_ * 1e6));
  state_ = ProcState::kBackoff;
}

void ProcessTracker::stopping() {
  stopping_ = true;
  if (state_ == ProcState::kBackoff || state_ == ProcState::kWaiting) state_ = ProcState::kStopped;
}

bool ProcessTracker::restart_due(int64_t now) const {
  return state_ == ProcState::kBackoff && !stopping_ && now >= next_start_utime_;
}

process_info_t ProcessTracker::info() const {
  process_info_t i{};
  i.name = spec_.name;
  i.pid = pid_;
  switch (state_) {
    case ProcState::kWaiting:
      i.state = process_info_t::STATE_WAITING;
      break;
    case ProcState::kRunning:
      i.state = process_info_t::STATE_RUNNING;
      break;
    case ProcState::kBackoff:
      i.state = process_info_t::STATE_BACKOFF;
      break;
    case ProcState::kExited:
      i.state = process_info_t::STATE_EXITED;
      break;
    case ProcState::kStopped:
      i.state = process_info_t::STATE_STOPPED;
      break;
    case ProcState::kFailed:
      i.state = process_info_t::STATE_FAILED;
      break;
  }
  i.exit_code = exit_code_;
  i.signal = signal_;
  i.restarts = restarts_;
  i.started_utime = started_utime_;
  i.backoff_s = state_ == ProcState::kBackoff ? backoff_s_ : 0.0;
  return i;
}

}  // namespace alight::launcher

#pragma once
// What the launcher knows and decides about one process: its state, its restarts and when the
// next restart is due (bot-procman's policy: a delay of 10 ms doubling to 1 s per consecutive
// crash, back to 10 ms after a run long enough to count as healthy), and systemd's start limit:
// too many quick failures in a window and the process is FAILED, not restarted forever. Pure:
// the node does the fork / exec / wait / kill and tells the tracker what happened, with the
// time of a steady clock (a wall-clock step must neither freeze nor hurry a restart).

#include <alight/process_info_t.hpp>
#include <cstdint>
#include <deque>
#include <string>

#include "launcher/launch_file.hpp"

namespace alight::launcher {

/// The exit code of an alight node that found its configuration bad (common/node.hpp).
constexpr int kConfigErrorExitCode = 2;

enum class ProcState { kWaiting, kRunning, kBackoff, kExited, kStopped, kFailed };
const char* to_string(ProcState s);

class ProcessTracker {
 public:
  ProcessTracker(ProcessSpec spec, BackoffParams backoff);

  void started(int pid, int64_t now_utime);
  /// The program could not be started (exec failed): counts as a crash.
  void start_failed(const std::string& why, int64_t now_utime);
  /// The process ended: exit code when it exited, or the signal that killed it.
  void exited(int exit_code, int signal, int64_t now_utime);
  /// The launcher is shutting down: no more restarts.
  void stopping();

  /// True while BACKOFF and the delay has passed.
  bool restart_due(int64_t now_utime) const;
  /// True when this process's exit must end the session.
  bool ends_session() const { return ended_session_; }

  ProcState state() const { return state_; }
  int pid() const { return pid_; }
  int restarts() const { return restarts_; }
  double backoff_s() const { return backoff_s_; }
  const ProcessSpec& spec() const { return spec_; }
  const std::string& last_reason() const { return reason_; }
  process_info_t info() const;

 private:
  void ended(int exit_code, int signal, int64_t now_utime, const std::string& reason);

  ProcessSpec spec_;
  BackoffParams backoff_;
  ProcState state_ = ProcState::kWaiting;
  int pid_ = 0;
  int restarts_ = 0;
  int consecutive_crashes_ = 0;
  double backoff_s_ = 0.0;
  int64_t started_utime_ = 0;
  int64_t next_start_utime_ = 0;
  std::deque<int64_t> quick_failures_utime_;  // ends of quick failures within the start limit
  int exit_code_ = 0;
  int signal_ = 0;
  bool stopping_ = false;
  bool ended_session_ = false;
  std::string reason_;
};

}  // namespace alight::launcher

#pragma once
// Launch files for the onboard launcher (scripts/alight-launch), modelled on libbot's
// bot-procman deputy: which processes, in which order, with which restart policy.
//
//   name: sim_landing
//   lcm_url: udpm://239.255.76.67:7667?ttl=0   # every process gets it as LCM_DEFAULT_URL
//   bus_key: auto          # auto | none | a key file (scripts/make-key): every process gets it as
//                          # ALIGHT_BUS_KEY_FILE and signs the bus with it; auto: the file in
//                          # $ALIGHT_BUS_KEY_FILE when set, else a fresh key for this launch
//   record: true                               # lcm-logger into the session folder
//   stop_timeout_s: 3.0                        # SIGINT, then SIGKILL after this long
//   backoff: {initial_s: 0.01, max_s: 1.0, reset_after_s: 10.0,   # optional
//             start_limit_burst: 12, start_limit_interval_s: 30.0}
//   processes:
//     - name: sim
//       command: [alight-sim, --scenario, "${ALIGHT_ROOT}/config/scenarios/landing_a.yaml"]
//       restart: on-failure      # never | on-failure | always
//       max_restarts: -1         # -1: unlimited
//       start_delay_s: 0.0       # wait after the previous process started
//       on_exit: shutdown        # restart (default) | shutdown: its exit ends the session
//       env: {ALIGHT_SEED: "3"}
//
// In command arguments and env values, ${ALIGHT_ROOT} (the source tree), ${SESSION_DIR},
// ${LCM_URL} and ${NAME} for any variable in the launcher's environment are replaced (so a
// script can pick the scenario: ALIGHT_SCENARIO=... scripts/alight-launch FILE). A command without
// a slash is looked up next to alight-launch first (build/bin), then on PATH.

#include <map>
#include <string>
#include <vector>

#include "common/channels.hpp"
#include "common/params.hpp"

namespace alight::launcher {

enum class RestartPolicy { kNever, kOnFailure, kAlways };

struct BackoffParams {
  double initial_s = 0.01;      ///< first restart delay [s] (bot-procman: 10 ms)
  double max_s = 1.0;           ///< the delay doubles up to this [s] (bot-procman: 1 s)
  double reset_after_s = 10.0;  ///< a process that ran this long starts again from initial_s [s]
  /// Start limit (systemd's StartLimitBurst / StartLimitIntervalSec): this many quick failures
  /// (each ran less than reset_after_s) within start_limit_interval_s mark the process FAILED
  /// instead of restarting it forever (e.g. an abort at start). 0 disables the limit.
  int start_limit_burst = 12;
  double start_limit_interval_s = 30.0;  ///< window of the start limit [s]
  void validate() const;
};

struct ProcessSpec {
  std::string name;
  std::vector<std::string> command;  ///< argv; command[0] is the program
  RestartPolicy restart = RestartPolicy::kOnFailure;
  int max_restarts = -1;          ///< restarts allowed before FAILED; -1 = unlimited
  double start_delay_s = 0.0;     ///< delay after the previous process's start [s]
  bool shutdown_on_exit = false;  ///< its exit (any code) stops the whole session
  std::map<std::string, std::string> env;
};

struct LaunchFile {
  std::string name;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string bus_key = "auto";  ///< auto, none, or a key file (${VAR} substituted)
  bool record = true;
  std::string record_channels = ".*";  ///< lcm-logger channel regex
  double stop_timeout_s = 3.0;         ///< grace between SIGINT and SIGKILL [s]
  double status_period_s = 1.0;        ///< PROCESS_STATUS period [s]
  std::string status_channel = channels::kProcessStatus;
  BackoffParams backoff;
  std::vector<ProcessSpec> processes;
  void validate() const;
};

/// Reads and validates a launch file; ParamError names file, key and value.
LaunchFile load_launch_file(const std::string& path);
/// Parses launch-file YAML text (`name` stands in for the file name in errors).
LaunchFile parse_launch_file(const std::string& yaml, const std::string& name);

/// Replaces ${VAR} in `arg` from `vars`; unknown variables are left as they are.
std::string substitute(const std::string& arg, const std::map<std::string, std::string>& vars);

}  // namespace alight::launcher

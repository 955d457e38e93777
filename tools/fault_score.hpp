#pragma once
// Outcome of one fault-campaign run (scripts/faults) from its session log. Pure: fed
// decoded messages in log order with their receipt time (lcm-logger's wall-clock stamp);
// alight-fault-score reads the file.
//
// The goal of the campaign: every run ends landed / through, in a safe hold or in a failsafe
// descent; never a disarm above 0.3 m, never a collision, never a process exit other than the
// one the campaign caused. Outcomes:
//   landed, through   the mission succeeded (tools/score.hpp)
//   safe_hold         armed, airborne, slow (< hold_speed_mps), autonomy holding or gone
//   failsafe_descent  a failsafe descent (outer loop modes FAILSAFE_DESCENT /
//   SETPOINT_LOST_DESCENT,
//                     autonomy FAILSAFE, or no ATTITUDE_CMD while the vehicle sinks: the
//                     autopilot's own command-loss failsafe) in progress or ended on the ground
//   grounded          on the ground with motors off or idle, and never flew (e.g. a kill in
//                     take-off before lift-off: the restarted autonomy waits for the operator)
//   came_down         on the ground after flying, with no landing, failsafe or hold (a failure)
//   in_mission        still flying a mission phase when the log ends (run too short: not a pass)
//   collision, tipped, left_area, disarmed_in_air, no_truth   (failures)
//
// The session log also holds what the campaign injected: hostile copies of live messages and an
// old session replayed. So the referee accepts a message only if it is newer than the last one it
// accepted on its channel and not stamped ahead of its receipt by more than stamp_ahead_s (and
// NODE_STATUS only when the node's uptime grew); SIM_TRUTH is never injected.

#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tools/score.hpp"

namespace alight::tools {

struct FaultScoreParams {
  std::string expected_exit;         ///< launcher process name the campaign kills ("" = none)
  double disarm_max_height_m = 0.3;  ///< a disarm higher above the surface below fails the run
  double hold_speed_mps = 0.5;       ///< slower than this, armed in the air: holding
  double airborne_height_m = 0.15;   ///< above the surface below by more than this: airborne
  double stamp_ahead_s = 5.0;        ///< referee: stamps further ahead of receipt are injected
  double node_silent_s = 3.0;        ///< a running node without NODE_STATUS this long: hung
  double command_lost_s = 1.0;       ///< no ATTITUDE_CMD this long: the autopilot is on its own
};

struct ProcessExit {
  std::string name;
  int32_t exit_code = 0;
  int32_t signal = 0;
  double t_s = 0;  ///< since the first message of the log [s]
  bool expected = false;
};

struct FaultOutcome {
  std::string outcome;                        ///< see the file comment
  bool ok = false;                            ///< the campaign's goal held in this run
  std::vector<std::string> violations;        ///< why not, one line each
  std::optional<double> max_disarm_height_m;  ///< highest disarm above the surface below [m]
  int disarms = 0;
  std::optional<double> max_touchdown_speed_mps;  ///< fastest sink rate on touching a surface
  bool collided = false;
  std::vector<ProcessExit> exits;  ///< every exit the launcher reported (shutdown excluded)
  int unexpected_exits = 0;
  std::vector<std::string> silent_nodes;  ///< running nodes whose NODE_STATUS stopped
  std::string final_phase;                ///< last accepted AUTONOMY_STATUS phase name
  int final_attitude_mode = -1;           ///< last accepted ATTITUDE_CMD mode (-1: none)
  bool failsafe_descent_seen = false;
  double final_height_m = 0;  ///< above the surface below at the end [m]
  double final_speed_mps = 0;
  std::string mission_outcome;  ///< tools::Score::outcome
  int refused_messages = 0;     ///< messages the referee refused (injected or replayed)

  std::string to_json() const;
};

class FaultScorer {
 public:
  explicit FaultScorer(FaultScoreParams params = {}) : params_(std::move(params)) {}

  void add(const sim_truth_t& m, int64_t received_utime);
  void add(const attitude_cmd_t& m, int64_t received_utime);
  void add(const autonomy_status_t& m, int64_t received_utime);
  void add(const process_status_t& m, int64_t received_utime);
  void add(const node_status_t& m, int64_t received_utime);
  FaultOutcome result() const;

  /// Height of the body origin above the surface below it (floor or platform top), corrected
  /// for the height at which the vehicle rests on the floor (its first truth sample) [m].
  double height_above_surface(const sim_truth_t& t) const;

 private:
  bool fresh(const std::string& channel, int64_t utime, int64_t received_utime);
  void seen(int64_t received_utime);

  FaultScoreParams params_;
  Scorer mission_;
  std::map<std::string, int64_t> last_utime_;
  std::optional<sim_truth_t> first_truth_, last_truth_;
  bool collided_ = false, tipped_ = false, out_of_area_ = false, flew_ = false;
  std::optional<double> touchdown_mps_;
  std::optional<double> max_disarm_m_;
  int disarms_ = 0;
  std::optional<attitude_cmd_t> last_cmd_;
  int64_t last_cmd_received_ = 0;
  std::optional<autonomy_status_t> last_status_;
  int64_t last_status_received_ = 0;
  bool failsafe_seen_ = false;
  std::map<std::string, process_info_t> procs_;
  std::vector<ProcessExit> exits_;
  struct NodeSeen {
    int32_t pid = 0;
    double uptime_s = -1;
    int64_t last_received = 0;
    int count = 0;
  };
  std::map<std::string, NodeSeen> nodes_;
  std::optional<int64_t> first_received_, last_received_, shutdown_received_;
  int refused_ = 0;
};

}  // namespace alight::tools

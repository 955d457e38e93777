#pragma once
// What the operator sees, aggregated from the vehicle's channels: the mission state of autonomy
// (phase, measurement count n of eq. 7, the waypoint estimate and its spread, paper 3.4), the
// vehicle track and waypoint measurements for a top-down plot like the paper's Fig. 10, the
// height estimate over time like Fig. 11, the latest VISION_TARGET, the age and rate of every
// channel (link health), and the launcher's process table. Pure: time is passed in.

#include <alight/autonomy_status_t.hpp>
#include <alight/autopilot_status_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/target_t.hpp>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>

#include "ground_station/commands.hpp"
#include "ground_station/params.hpp"

namespace alight::ground_station {

/// Arrival statistics of one channel.
class RateMeter {
 public:
  explicit RateMeter(int64_t window_us = 2'000'000) : window_us_(window_us) {}
  void add(int64_t now_utime);
  /// Messages per second over the last window (0 when fewer than two arrivals in it).
  double rate_hz(int64_t now_utime) const;
  /// Seconds since the last arrival, nullopt when nothing arrived.
  std::optional<double> age_s(int64_t now_utime) const;
  uint64_t count() const { return count_; }

 private:
  int64_t window_us_;
  mutable std::deque<int64_t> arrivals_;
  uint64_t count_ = 0;
  int64_t last_utime_ = 0;
};

/// Names of autonomy's phases (autonomy_status_t.PHASE_*), for messages without phase_name.
const char* phase_name(int8_t phase);
const char* process_state_name(int8_t state);
const char* target_reason_name(int8_t reason);

struct TrackPoint {
  double t_s;     ///< since the first sample [s]
  double p_W[3];  ///< vehicle position [m]
};
struct HeightPoint {
  double t_s;           ///< since the first sample [s]
  double vehicle_z_m;   ///< vehicle height (NaN before a pose)
  double estimate_z_m;  ///< estimate z (NaN without an estimate)
  double sigma_z_m;     ///< sqrt of the estimate's z variance (NaN without an estimate)
};
struct Measurement {
  double t_s;
  double p_W[3];
};

class StationState {
 public:
  explicit StationState(const GroundStationParams& params);

  // `now_utime` is the station's steady clock (arrival ages, rates, command deadlines: a step of
  // the system clock must neither hide a dead link nor delay an alarm). Where a message's stamp
  // is compared with the station's wall clock (clock offset, frame latency, process report age)
  // the node passes `wall_utime` too; without it, now_utime stands for both (tests).
  void on_status(const autonomy_status_t& msg, int64_t now_utime,
                 std::optional<int64_t> wall_utime = std::nullopt);
  void on_target(const target_t& msg, int64_t now_utime);
  void on_process_status(const process_status_t& msg, int64_t now_utime,
                         std::optional<int64_t> wall_utime = std::nullopt);
  void on_pose(const pose_t& msg, int64_t now_utime);
  /// One node's input counters: the page shows which nodes sign the bus and every channel where
  /// messages were refused for their origin (unsigned, forged, replayed, a second publisher).
  void on_node_status(const node_status_t& msg, int64_t now_utime);
  /// The autopilot's mode, arming and link as alight-mavlink sees them (a real vehicle only).
  void on_autopilot_status(const autopilot_status_t& msg, int64_t now_utime);
  /// A frame arrived on a video channel; `frame_utime` is its exposure time.
  void on_frame(const std::string& channel, int64_t frame_utime, int64_t now_utime,
                std::optional<int64_t> wall_utime = std::nullopt);
  /// A command was handed to LCM, signed for `session` (shown in the page's command log until
  /// AUTONOMY_STATUS acknowledges or rejects it, or its deadline passes).
  void on_command_sent(const std::string& name, int64_t seq, int64_t session, int64_t now_utime);

  /// The session nonce announced by the configured vehicle's autonomy (0 before any status, or
  /// when its verifier has no key): commands are signed for it.
  int64_t vehicle_session() const;
  /// Station clock minus the vehicle's wall clock at the newest AUTONOMY_STATUS (includes the
  /// link delay) [s]; nullopt before any status.
  std::optional<double> clock_offset_s() const { return clock_offset_s_; }
  const CommandTracker& commands() const { return commands_; }

  /// The page's state document (JSON). `extra` is spliced in verbatim as `"station": extra`.
  std::string to_json(int64_t now_utime, const std::string& extra = "{}") const;

  const std::optional<autonomy_status_t>& status() const { return status_; }
  const std::deque<TrackPoint>& track() const { return track_; }
  const std::deque<HeightPoint>& heights() const { return heights_; }
  const std::deque<Measurement>& measurements() const { return measurements_; }
  /// VISION_TARGET messages by reason (REASON_*) since the start or the last jump back in time.
  const std::map<int8_t, uint64_t>& target_reasons() const { return target_reasons_; }
  double channel_rate_hz(const std::string& channel, int64_t now_utime) const;
  std::optional<double> channel_age_s(const std::string& channel, int64_t now_utime) const;

 private:
  double t_s(int64_t utime);
  void arrived(const std::string& channel, int64_t now_utime);
  void sample_height(int64_t utime);

  GroundStationParams params_;
  std::optional<int64_t> t0_utime_;
  std::optional<autonomy_status_t> status_;
  std::optional<target_t> target_;
  std::map<int8_t, uint64_t> target_reasons_;  // VISION_TARGET messages by reason
  std::optional<process_status_t> processes_;
  std::optional<autopilot_status_t> autopilot_;
  struct NodeReport {
    node_status_t msg;
    int64_t arrival_utime = 0;
  };
  std::map<std::string, NodeReport> nodes_;  // by node name
  int64_t autopilot_arrival_utime_ = 0;
  std::optional<pose_t> pose_;
  std::map<std::string, RateMeter> channels_;
  // Per channel, the newest frame's latency at arrival (wall clock minus exposure) and its
  // arrival on the steady clock: the latency shown grows with the steady clock from there.
  struct FrameArrival {
    int64_t latency_us;
    int64_t arrival_utime;
  };
  std::map<std::string, FrameArrival> frames_;
  int64_t processes_age_at_arrival_us_ = 0;  // wall clock minus the report's stamp
  int64_t processes_arrival_utime_ = 0;
  std::deque<TrackPoint> track_;
  std::deque<HeightPoint> heights_;
  std::deque<Measurement> measurements_;
  int64_t last_track_utime_ = INT64_MIN;
  int64_t last_height_utime_ = INT64_MIN;
  CommandTracker commands_;
  std::optional<double> clock_offset_s_;
};

}  // namespace alight::ground_station

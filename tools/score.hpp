#pragma once
// Scores a flown mission from its session log: the figures the paper reports (touchdown on the
// platform, Fig. 10; platform height, Fig. 11; opening width, Fig. 12) measured against the
// simulator's ground truth (SIM_TRUTH), which flight code never sees. Pure: fed decoded
// messages in log order; alight-score does the file reading.
//
// Timing (paper 4: waypoints at about 5 fps on STARMAC, 2 fps on the Pelican): given each
// message's receipt time in the log (lcm-logger's wall-clock stamp), the scorer also measures
// the camera -> VISION_TARGET latency and the frame and waypoint rates. All of it is wall-clock
// time, whatever real-time factor the simulator ran at. When the log has VISION_TIMING
// (vision_timing_t), the vision's own account comes apart: processing time
// (Pipeline::process), the wait before it (queue and pose), the end-to-end latency from exposure
// to the logger's receipt of the VISION_TARGET, and the frames it received, dropped and
// processed.
//
// Crash: a touch-down (SIM_TRUTH's contact going from nothing, the wall or the frame to the
// floor or the platform) sinking faster than the vehicle's gear takes, the vehicle file's
// vehicle.gear_max_impact_mps, is a crash whatever the attitude and wherever it happens: the
// mission fails with outcome `crashed`. max_touchdown_speed_mps is the fastest sink rate of any
// touch-down in the log.
//
// A moving platform (the log has SIM_PLATFORM, platform_truth_t, with each SIM_TRUTH):
// a touch-down on it is judged by the sink rate relative to its deck (the deck's velocity at the
// vehicle, along the deck's normal), the lateral error against the platform where it is at that
// sample, and the heading against its long axis. A log without SIM_PLATFORM (a platform standing
// still, or a log from before it) is scored exactly as before.

#include <alight/autonomy_status_t.hpp>
#include <alight/platform_truth_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/target_t.hpp>
#include <alight/vision_timing_t.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace alight::tools {

struct Score {
  std::string scenario;
  int mission = 0;          ///< target_t::MISSION_*
  bool success = false;     ///< landed on the platform / flew through without contact
  std::string outcome;      ///< landed, tipped, not_landed, through, refused (autonomy refused
                            ///< the target: too small), collided, crashed, left_area,
                            ///< incomplete
  std::string final_phase;  ///< last AUTONOMY_STATUS phase name
  std::optional<double> mission_time_s;             ///< GO (detection starts) to LANDED / DONE
  std::optional<double> touchdown_lateral_error_m;  ///< body origin to platform centre, in xy
  std::optional<double> max_touchdown_speed_mps;    ///< fastest sink rate on touching down
  double gear_max_impact_mps = 0;                   ///< a faster touch-down is a crash [m/s]
  std::optional<double> platform_height_error_m;    ///< converged estimate z - true top z
  std::optional<double> vision_height_error_m;      ///< median vision platform height - truth
  std::optional<double> opening_width_error_m;      ///< median vision opening width - truth
  std::optional<double> opening_center_error_m;     ///< converged estimate to true centre [m]
  std::optional<double> crossing_offset_m;          ///< wall-plane offset from centre when crossing
  int n_measurements = 0;                           ///< waypoints in the final estimate
  int vision_frames = 0;                            ///< VISION_TARGET messages
  int vision_found = 0;                             ///< ... with a target
  int camera_frames = 0;                            ///< CAMERA frames in the log

  // Latency: receipt of a VISION_TARGET minus receipt of the CAMERA frame with the same exposure
  // time (target_t::utime = image_t::utime), both as stamped by the logger, so it spans the
  // camera message's transport, the vision's queue (it waits for the pose at exposure time and
  // drops to the newest frame when behind), its processing and the target's transport.
  // Percentiles are nearest-rank over the targets whose frame is in the log and had a pose.
  std::optional<double> vision_latency_p50_ms;  ///< median wall-clock latency [ms]
  std::optional<double> vision_latency_p99_ms;  ///< 99th percentile [ms]
  std::optional<double> vision_latency_max_ms;  ///< largest [ms]
  int vision_latency_unmatched = 0;  ///< timed VISION_TARGETs whose CAMERA frame is not in the log
  /// Timed VISION_TARGETs of frames processed without a pose (REASON_NO_POSE: before the pose
  /// source's first message, or none came in max_pose_wait_s), left out of the percentiles: they
  /// waited that long by design, and at a session's start they were the p99.
  int vision_latency_without_pose = 0;
  // Rates: messages per wall second over the log's span (first to last receipt of a CAMERA or
  // VISION_TARGET message).
  std::optional<double> camera_frames_per_s;     ///< CAMERA frames per wall second
  std::optional<double> vision_frames_per_s;     ///< VISION_TARGETs (processed frames) per second
  std::optional<double> vision_waypoints_per_s;  ///< ... of them with a target found
  std::optional<double> vision_frame_coverage;   ///< camera frames that got a VISION_TARGET [0, 1]
  std::optional<double> real_time_factor;        ///< camera exposure time elapsed per wall second

  // From VISION_TIMING (nearest-rank percentiles over its messages) [ms]: Pipeline::process
  // alone; the wait from the node reading the frame to processing it (its input queue, the
  // frames ahead, the pose); and exposure -> VISION_TARGET received by the logger, reported
  // only when the exposure stamps are on the wall clock (camera driver, alight-sim
  // --start-now): its median within [0, 60] s.
  struct Percentiles {
    double p50 = 0, p90 = 0, p99 = 0, max = 0;
  };
  int timing_frames = 0;  ///< VISION_TIMING messages
  std::optional<Percentiles> vision_process_ms, vision_wait_ms, vision_end_to_end_ms;
  std::optional<Percentiles> vision_process_cpu_ms;  ///< the CPU time of the same
  // The vision's counters in its last VISION_TIMING (vision_timing_t frames_*).
  int64_t vision_frames_received = 0, vision_frames_dropped = 0, vision_frames_refused = 0,
          vision_frames_failed = 0, vision_frames_processed = 0, vision_frames_waiting = 0,
          vision_frames_late = 0;
  bool collided = false;
  int n_collisions = 0;
  bool crashed = false;      ///< touched down faster than gear_max_impact_mps (fails any mission)
  bool out_of_area = false;  ///< the vehicle left the flying area (fails any mission)

  // A moving platform (SIM_PLATFORM in the log); listed only then.
  bool platform_moving = false;
  /// The first touch-down on the platform's top: sink rate relative to the deck [m/s] (the
  /// faster of the samples either side, as max_touchdown_speed_mps).
  std::optional<double> touchdown_relative_sink_mps;
  /// There: the vehicle's heading against the platform's long axis, either way round (a
  /// rectangle looks the same turned half round), |error| in [0, 90] [deg].
  std::optional<double> touchdown_heading_error_deg;
  /// There: the platform's speed (its top centre) [m/s].
  std::optional<double> touchdown_platform_speed_mps;
  int platform_messages_refused = 0;  ///< SIM_PLATFORM of a version newer than this reader's

  /// `key: value` lines (absent figures are left out).
  std::string to_text() const;
  std::string to_json() const;
  std::vector<std::pair<std::string, std::string>> fields() const;
};

class Scorer {
 public:
  /// Judges touch-downs against the default vehicle's gear (sim::VehicleParams), for callers
  /// that do not know which vehicle flew.
  Scorer();
  /// `gear_max_impact_mps`: vehicle.gear_max_impact_mps of the vehicle that flew.
  explicit Scorer(double gear_max_impact_mps);

  void add(const sim_truth_t& truth);
  /// SIM_PLATFORM: the moving platform at the time of the SIM_TRUTH that follows it.
  void add(const platform_truth_t& platform);
  void add(const autonomy_status_t& status);
  void add(const target_t& target);
  /// A VISION_TARGET with its receipt time [us, wall clock, as the logger stamps it].
  void add(const target_t& target, int64_t received_utime);
  /// A VISION_TIMING message (its own fields say when; the receipt is not needed).
  void add(const vision_timing_t& timing);
  /// A CAMERA frame: its exposure time (image_t::utime) and receipt time [us].
  void add_camera_frame(int64_t image_utime, int64_t received_utime);
  Score result() const;

 private:
  double gear_max_impact_mps_;
  std::optional<sim_truth_t> last_truth_, touchdown_truth_;
  // The newest SIM_PLATFORM, and the one that went with last_truth_.
  std::optional<platform_truth_t> platform_, last_truth_platform_;
  std::optional<platform_truth_t> touchdown_platform_;  // with touchdown_truth_
  std::optional<double> relative_sink_mps_, heading_error_deg_, platform_speed_mps_;
  bool platform_touched_ = false;
  int platform_refused_ = 0;
  std::optional<double> max_touchdown_speed_mps_;
  std::optional<sim_truth_t> before_crossing_, after_crossing_;
  std::optional<autonomy_status_t> last_status_, converged_status_;
  std::optional<int64_t> go_utime_, end_utime_;
  std::vector<double> widths_m_, heights_m_;
  int mission_ = 0;
  bool tipped_ = false;  // any sample: the vehicle fell off an edge
  int vision_frames_ = 0, vision_found_ = 0;
  // Timing: receipts of camera frames by exposure time (the first one when a frame repeats),
  // and of targets as (exposure time, receipt).
  std::unordered_map<int64_t, int64_t> camera_received_;
  std::vector<std::pair<int64_t, int64_t>> target_received_;
  std::unordered_set<int64_t> without_pose_;  // exposure times of targets with REASON_NO_POSE
  int camera_frames_ = 0, timed_found_ = 0;
  std::optional<int64_t> first_received_, last_received_;
  std::optional<std::pair<int64_t, int64_t>> first_camera_, last_camera_;  // (exposure, receipt)
  std::vector<double> process_ms_, process_cpu_ms_, wait_ms_;
  std::optional<vision_timing_t> last_timing_;  // the one with the most frames processed
  void extend_span(int64_t received_utime);
};

}  // namespace alight::tools

#pragma once
// Parameters of the operator's ground station (alight-ground-station). Optional file: every
// field has a default, a file given with --config overrides them in its `ground_station:` section.

#include <string>

namespace alight::ground_station {

struct GroundStationParams {
  // Channels (docs/ARCHITECTURE.md "Channels").
  std::string camera_channel = "CAMERA";
  std::string diag_channel = "VISION_DIAG";
  std::string status_channel = "AUTONOMY_STATUS";
  std::string target_channel = "VISION_TARGET";
  std::string process_channel = "PROCESS_STATUS";
  std::string pose_channel = "MOCAP_POSE";
  std::string command_channel = "OPERATOR_CMD";

  int http_port = 8080;             ///< TCP port of the web page (0: any free port)
  int http_threads = 24;            ///< server worker threads (each serves one connection)
  int max_queued_connections = 64;  ///< connections waiting for a worker beyond which new
                                    ///< ones are closed at once (bounds memory under load)
  double client_timeout_s = 2.0;    ///< read / write / keep-alive timeout per connection [s]
  double frame_wait_s = 0.5;        ///< a frame request waits this long for a newer frame [s]
  int jpeg_quality = 75;            ///< JPEG quality of re-encoded CAMERA frames [1, 100]

  double track_period_s = 0.1;   ///< vehicle track / height history sampling [s]
  int track_max_points = 2000;   ///< points kept of the track and the height history
  int measurements_max = 500;    ///< VISION_TARGET waypoints kept for the plot
  double channel_stale_s = 1.0;  ///< a channel older than this is shown as stale [s]
  double nudge_max_m = 1.0;      ///< largest position nudge a request may carry [m]

  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Defaults, overridden by the `ground_station:` section of `path` (when not empty).
GroundStationParams load_params(const std::string& path);

}  // namespace alight::ground_station

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

  std::string vehicle_id = "alight";  ///< commands are signed for it (autonomy.vehicle_id)
  double ack_timeout_s = 1.0;  ///< a command not acknowledged within this is NOT ACKNOWLEDGED [s]
  double clock_offset_warn_s = 0.5;  ///< the page warns when the station's clock is further
                                     ///< than this from the vehicle's [s]

  int http_port = 8080;              ///< TCP port of the web page (0: any free port)
  int http_threads = 32;             ///< server worker threads (each serves one connection)
  int command_threads = 2;           ///< workers kept for POST /api/command only: a request
                                     ///< reaches a worker only once its head (and a command's
                                     ///< body) has arrived, so slow clients hold no worker and
                                     ///< a KILL never waits behind page traffic
  int max_queued_connections = 64;   ///< connections waiting for a worker beyond which new
                                     ///< ones are closed at once (bounds memory under load)
  double client_timeout_s = 2.0;     ///< read / write / keep-alive idle timeout per connection [s]
  double head_deadline_s = 2.0;      ///< request line and headers (for a command also its
                                     ///< body) complete within this of the first byte [s]
  int max_pending_heads = 256;       ///< connections whose head is still arriving; beyond it
                                     ///< the oldest is closed [count]
  double request_deadline_s = 10.0;  ///< whole request, head to last byte of the answer [s]
  int max_header_count = 64;         ///< headers per request
  int max_head_bytes = 16384;        ///< request line plus headers [bytes]
  int max_payload_bytes = 65536;     ///< request body [bytes]
  double frame_wait_s = 0.5;         ///< a frame request waits this long for a newer frame [s]
  int jpeg_quality = 75;             ///< JPEG quality of re-encoded CAMERA frames [1, 100]

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

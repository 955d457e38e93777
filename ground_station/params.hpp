#pragma once
// Parameters of the operator's ground station (alight-ground-station). Optional file: every
// field has a default (the initialisers below), a file given with --config overrides them in its
// `ground_station:` section. `alight-params --defaults station` prints every key with its unit,
// constraint and meaning.

#include <string>

#include "common/channels.hpp"
#include "common/param_schema.hpp"

namespace alight::ground_station {

struct GroundStationParams {
  // Channels (docs/ARCHITECTURE.md "Channels").
  std::string camera_channel = channels::kCamera;
  std::string diag_channel = channels::kVisionDiag;
  std::string status_channel = channels::kAutonomyStatus;
  std::string target_channel = channels::kVisionTarget;
  std::string process_channel = channels::kProcessStatus;
  std::string node_status_channel = channels::kNodeStatus;
  std::string autopilot_channel = channels::kAutopilotStatus;
  std::string pose_channel = channels::kMocapPose;
  std::string command_channel = channels::kOperatorCmd;

  std::string vehicle_id = "alight";
  double ack_timeout_s = 1.0;
  double clock_offset_warn_s = 0.5;

  int http_port = 8080;
  int http_threads = 32;
  int command_threads = 2;
  int max_queued_connections = 64;
  double client_timeout_s = 2.0;
  double head_deadline_s = 2.0;
  int max_pending_heads = 256;
  double request_deadline_s = 10.0;
  int max_header_count = 64;
  int max_head_bytes = 16384;
  int max_payload_bytes = 65536;
  double frame_wait_s = 0.5;
  int jpeg_quality = 75;

  double track_period_s = 0.1;
  int track_max_points = 2000;
  int measurements_max = 500;
  double channel_stale_s = 1.0;
  double nudge_max_m = 1.0;

  static const ParamSchema<GroundStationParams>& schema();
  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Defaults, overridden by the `ground_station:` section of `path` (when not empty).
GroundStationParams load_params(const std::string& path);

}  // namespace alight::ground_station

#include "ground_station/params.hpp"

#include "common/params.hpp"

namespace alight::ground_station {

void GroundStationParams::validate() const {
  for (const auto* c : {&camera_channel, &diag_channel, &status_channel, &target_channel,
                        &process_channel, &pose_channel, &command_channel})
    param_check(!c->empty(), "*_channel", *c, "channel names must not be empty");
  param_check(http_port >= 0 && http_port <= 65535, "http_port", http_port,
              "must be in [0, 65535]");
  param_check(!vehicle_id.empty() && vehicle_id.size() <= 64, "vehicle_id", vehicle_id,
              "must be 1 to 64 characters");
  param_check(ack_timeout_s > 0.0 && ack_timeout_s <= 60.0, "ack_timeout_s", ack_timeout_s,
              "must be in (0, 60] s");
  param_check(clock_offset_warn_s > 0.0 && clock_offset_warn_s <= 3600.0, "clock_offset_warn_s",
              clock_offset_warn_s, "must be in (0, 3600] s");
  param_check(http_threads >= 2 && http_threads <= 256, "http_threads", http_threads,
              "must be in [2, 256]");
  param_check(command_threads >= 1 && command_threads <= 16, "command_threads", command_threads,
              "must be in [1, 16]");
  param_check(max_pending_heads >= 8 && max_pending_heads <= 4096, "max_pending_heads",
              max_pending_heads, "must be in [8, 4096]");
  param_check(head_deadline_s > 0.0 && head_deadline_s <= 60.0, "head_deadline_s", head_deadline_s,
              "must be in (0, 60] s");
  param_check(request_deadline_s >= head_deadline_s && request_deadline_s <= 300.0,
              "request_deadline_s", request_deadline_s, "must be in [head_deadline_s, 300] s");
  param_check(max_header_count >= 8 && max_header_count <= 1000, "max_header_count",
              max_header_count, "must be in [8, 1000]");
  param_check(max_head_bytes >= 1024 && max_head_bytes <= 1 << 20, "max_head_bytes", max_head_bytes,
              "must be in [1024, 1048576]");
  param_check(max_payload_bytes >= 1024 && max_payload_bytes <= 1 << 24, "max_payload_bytes",
              max_payload_bytes, "must be in [1024, 16777216]");
  param_check(max_queued_connections >= 1, "max_queued_connections", max_queued_connections,
              "must be >= 1");
  param_check(client_timeout_s > 0.0 && client_timeout_s <= 60.0, "client_timeout_s",
              client_timeout_s, "must be in (0, 60] s");
  param_check(frame_wait_s >= 0.0 && frame_wait_s < client_timeout_s, "frame_wait_s", frame_wait_s,
              "must be in [0, client_timeout_s)");
  param_check(jpeg_quality >= 1 && jpeg_quality <= 100, "jpeg_quality", jpeg_quality,
              "must be in [1, 100]");
  param_check(track_period_s > 0.0 && track_period_s <= 60.0, "track_period_s", track_period_s,
              "must be in (0, 60] s");
  param_check(track_max_points >= 10, "track_max_points", track_max_points, "must be >= 10");
  param_check(measurements_max >= 1, "measurements_max", measurements_max, "must be >= 1");
  param_check(channel_stale_s > 0.0 && channel_stale_s <= 3600.0, "channel_stale_s",
              channel_stale_s, "must be in (0, 3600] s");
  param_check(nudge_max_m > 0.0 && nudge_max_m <= 5.0, "nudge_max_m", nudge_max_m,
              "must be in (0, 5] m");
}

GroundStationParams load_params(const std::string& path) {
  GroundStationParams p;
  if (path.empty()) {
    p.validate();
    return p;
  }
  const ParamNode root = ParamNode::load_file(path);
  const ParamNode n = root.child("ground_station");
  n.read("camera_channel", p.camera_channel);
  n.read("diag_channel", p.diag_channel);
  n.read("status_channel", p.status_channel);
  n.read("target_channel", p.target_channel);
  n.read("process_channel", p.process_channel);
  n.read("pose_channel", p.pose_channel);
  n.read("command_channel", p.command_channel);
  n.read("http_port", p.http_port);
  n.read("vehicle_id", p.vehicle_id);
  n.read("ack_timeout_s", p.ack_timeout_s);
  n.read("clock_offset_warn_s", p.clock_offset_warn_s);
  n.read("http_threads", p.http_threads);
  n.read("command_threads", p.command_threads);
  n.read("max_pending_heads", p.max_pending_heads);
  n.read("head_deadline_s", p.head_deadline_s);
  n.read("request_deadline_s", p.request_deadline_s);
  n.read("max_header_count", p.max_header_count);
  n.read("max_head_bytes", p.max_head_bytes);
  n.read("max_payload_bytes", p.max_payload_bytes);
  n.read("max_queued_connections", p.max_queued_connections);
  n.read("client_timeout_s", p.client_timeout_s);
  n.read("frame_wait_s", p.frame_wait_s);
  n.read("jpeg_quality", p.jpeg_quality);
  n.read("track_period_s", p.track_period_s);
  n.read("track_max_points", p.track_max_points);
  n.read("measurements_max", p.measurements_max);
  n.read("channel_stale_s", p.channel_stale_s);
  n.read("nudge_max_m", p.nudge_max_m);
  n.validate(p);
  n.finish();
  return p;
}

}  // namespace alight::ground_station

#include "ground_station/params.hpp"

#include "common/params.hpp"

namespace alight::ground_station {

void GroundStationParams::validate() const {
  for (const auto* c : {&camera_channel, &diag_channel, &status_channel, &target_channel,
                        &process_channel, &pose_channel, &command_channel})
    param_check(!c->empty(), "*_channel", *c, "channel names must not be empty");
  param_check(http_port >= 0 && http_port <= 65535, "http_port", http_port,
              "must be in [0, 65535]");
  param_check(http_threads >= 2 && http_threads <= 256, "http_threads", http_threads,
              "must be in [2, 256]");
  param_check(max_queued_connections >= 1, "max_queued_connections", max_queued_connections,
              "must be >= 1");
  param_check(client_timeout_s > 0.0 && client_timeout_s <= 60.0, "client_timeout_s",
              client_timeout_s, "must be in (0, 60] s");
  param_check(frame_wait_s >= 0.0 && frame_wait_s < client_timeout_s, "frame_wait_s", frame_wait_s,
              "must be in [0, client_timeout_s)");
  param_check(jpeg_quality >= 1 && jpeg_quality <= 100, "jpeg_quality", jpeg_quality,
              "must be in [1, 100]");
  param_check(track_period_s > 0.0, "track_period_s", track_period_s, "must be > 0");
  param_check(track_max_points >= 10, "track_max_points", track_max_points, "must be >= 10");
  param_check(measurements_max >= 1, "measurements_max", measurements_max, "must be >= 1");
  param_check(channel_stale_s > 0.0, "channel_stale_s", channel_stale_s, "must be > 0");
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
  n.read("http_threads", p.http_threads);
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

#include "ground_station/params.hpp"

namespace alight::ground_station {

const ParamSchema<GroundStationParams>& GroundStationParams::schema() {
  using P = GroundStationParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    const auto channel = [&s](const char* key, std::string P::*field, const char* doc) {
      s.add(key, field, Range::any(), "", doc)
          .check([field](const P& p) { return !(p.*field).empty(); }, "must not be empty");
    };
    channel("camera_channel", &P::camera_channel, "LCM channel of the live video");
    channel("diag_channel", &P::diag_channel, "of the vision's diagnostic image");
    channel("status_channel", &P::status_channel, "of the autonomy's status");
    channel("target_channel", &P::target_channel, "of the vision's measurements");
    channel("process_channel", &P::process_channel, "of the launcher's process states");
    channel("node_status_channel", &P::node_status_channel,
            "of every node's input counters (refused messages, second publishers)");
    channel("autopilot_channel", &P::autopilot_channel,
            "of the autopilot's state (alight-mavlink: mode, arming, link)");
    channel("pose_channel", &P::pose_channel, "of the motion capture");
    channel("command_channel", &P::command_channel, "where operator commands are sent");
    s.add("vehicle_id", &P::vehicle_id, Range::any(), "",
          "commands are signed for it (autonomy.vehicle_id)")
        .check([](const P& p) { return !p.vehicle_id.empty() && p.vehicle_id.size() <= 64; },
               "must be 1 to 64 characters");
    s.add("ack_timeout_s", &P::ack_timeout_s, Range::open_closed(0, 60), "s",
          "a command not acknowledged within this is NOT ACKNOWLEDGED");
    s.add("clock_offset_warn_s", &P::clock_offset_warn_s, Range::open_closed(0, 3600), "s",
          "the page warns when the station's clock is further than this from the vehicle's");
    s.add("http_port", &P::http_port, Range::closed(0, 65535), "",
          "TCP port of the web page (0: any free port)");
    s.add("http_threads", &P::http_threads, Range::closed(2, 256), "",
          "server worker threads (each serves one connection)");
    s.add("command_threads", &P::command_threads, Range::closed(1, 16), "",
          "workers kept for POST /api/command only: a request reaches a worker only once its head "
          "(and a command's body) has arrived, so slow clients hold no worker and a KILL never "
          "waits behind page traffic");
    // Each waiting connection is an open socket, in each of the two pools: 2 x 256 of them,
    // the default max_pending_heads (256) and the workers stay within the 1024 open files a
    // process gets by default (ulimit -n); past that accept() fails for the page and a KILL
    // alike.
    s.add("max_queued_connections", &P::max_queued_connections, Range::closed(1, 256), "",
          "connections waiting for a worker, per pool, beyond which new ones are closed at once "
          "(bounds memory and open files under load)");
    s.add("client_timeout_s", &P::client_timeout_s, Range::open_closed(0, 60), "s",
          "read / write / keep-alive idle timeout per connection");
    s.add("head_deadline_s", &P::head_deadline_s, Range::open_closed(0, 60), "s",
          "request line and headers (for a command also its body) complete within this of the "
          "first byte");
    s.add("max_pending_heads", &P::max_pending_heads, Range::closed(8, 4096), "",
          "connections whose head is still arriving; beyond it the oldest is closed");
    s.add("request_deadline_s", &P::request_deadline_s, Range::le(300), "s",
          "whole request, head to last byte of the answer")
        .check([](const P& p) { return p.request_deadline_s >= p.head_deadline_s; },
               "must be in [head_deadline_s, 300] s");
    s.add("max_header_count", &P::max_header_count, Range::closed(8, 1000), "",
          "headers per request");
    s.add("max_head_bytes", &P::max_head_bytes, Range::closed(1024, 1 << 20), "bytes",
          "request line plus headers");
    s.add("max_payload_bytes", &P::max_payload_bytes, Range::closed(1024, 1 << 24), "bytes",
          "request body");
    // The wait only has to span one frame interval of the slowest video (the vision's
    // diagnostic image: 2 Hz on the paper's Pelican); a longer one only keeps a worker busy and
    // the page waiting. The answer is written after the wait, within both the connection's I/O
    // timeout and the request's deadline.
    s.add("frame_wait_s", &P::frame_wait_s, Range::closed(0, 2), "s",
          "a frame request waits this long for a newer frame")
        .check(
            [](const P& p) {
              return p.frame_wait_s < p.client_timeout_s && p.frame_wait_s < p.request_deadline_s;
            },
            "must be below client_timeout_s and request_deadline_s");
    s.add("jpeg_quality", &P::jpeg_quality, Range::closed(1, 100), "",
          "JPEG quality of re-encoded CAMERA frames");
    s.add("track_period_s", &P::track_period_s, Range::open_closed(0, 60), "s",
          "vehicle track and height history sampling");
    s.add("track_max_points", &P::track_max_points, Range::ge(10), "",
          "points kept of the track and the height history");
    s.add("measurements_max", &P::measurements_max, Range::ge(1), "",
          "VISION_TARGET waypoints kept for the plot");
    s.add("channel_stale_s", &P::channel_stale_s, Range::open_closed(0, 3600), "s",
          "a channel older than this is shown as stale");
    s.add("nudge_max_m", &P::nudge_max_m, Range::open_closed(0, 5), "m",
          "largest position nudge a request may carry");
    return s;
  }();
  return schema;
}

void GroundStationParams::validate() const { schema().validate(*this); }

GroundStationParams load_params(const std::string& path) {
  GroundStationParams p;
  if (path.empty()) {
    p.validate();
    return p;
  }
  GroundStationParams::schema().read(ParamNode::load_file(path).child("ground_station"), p);
  return p;
}

}  // namespace alight::ground_station

#include "mocap/params.hpp"

#include <cctype>

namespace alight::mocap {

std::optional<TrackerAddress> parse_tracker(const std::string& text) {
  const auto at = text.find('@');
  if (at == std::string::npos || at == 0 || text.find('@', at + 1) != std::string::npos)
    return std::nullopt;
  TrackerAddress a;
  a.object = text.substr(0, at);
  std::string host = text.substr(at + 1);
  const auto colon = host.rfind(':');
  if (colon != std::string::npos) {
    const std::string port = host.substr(colon + 1);
    if (port.empty() || port.size() > 5) return std::nullopt;
    for (char c : port)
      if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
    a.port = std::stoi(port);
    if (a.port < 1 || a.port > 65535) return std::nullopt;
    host.resize(colon);
  }
  // Object names may hold spaces (Motive's default is "Rigid Body 1"); host names may not.
  if (host.empty() || a.object.size() >= 100) return std::nullopt;
  for (char c : a.object)
    if (std::iscntrl(static_cast<unsigned char>(c))) return std::nullopt;
  for (char c : host)
    if (std::isspace(static_cast<unsigned char>(c)) || std::iscntrl(static_cast<unsigned char>(c)))
      return std::nullopt;
  a.host = std::move(host);
  return a;
}

const ParamSchema<ServerParams>& ServerParams::schema() {
  using P = ServerParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("tracker", &P::tracker, Range::any(), "",
          "VRPN device: the object's name as the room software shows it, @ the server's host, "
          "optionally :port (3883 by default)")
        .required()
        .check([](const P& p) { return parse_tracker(p.tracker).has_value(); },
               "must be OBJECT@HOST or OBJECT@HOST:PORT");
    s.add("sensor", &P::sensor, Range::closed(0, 1023), "",
          "sensor of that tracker (0 for a rigid body of VICON Tracker, Motive, QTM)");
    s.add("connect_timeout_s", &P::connect_timeout_s, Range::open_closed(0, 30), "s",
          "one TCP connection attempt");
    s.add("silence_timeout_s", &P::silence_timeout_s, Range::open_closed(0, 60), "s",
          "connected but nothing received for this long: reconnect (a server that hung, a cable "
          "pulled: TCP itself notices only after minutes)");
    s.add("retry_initial_s", &P::retry_initial_s, Range::open_closed(0, 10), "s",
          "first reconnection delay; doubles at each failure");
    s.add("retry_max_s", &P::retry_max_s, Range::open_closed(0, 60), "s",
          "largest reconnection delay")
        .check([](const P& p) { return p.retry_max_s >= p.retry_initial_s; },
               "must be >= retry_initial_s");
    s.add("start_timeout_s", &P::start_timeout_s, Range::closed(0, 3600), "s",
          "never connected this long after start: exit 3 (0: keep retrying)");
    return s;
  }();
  return schema;
}

const ParamSchema<RoomParams>& RoomParams::schema() {
  using P = RoomParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("units", &P::units, Range::any(), "", "unit of the server's positions")
        .one_of({"m", "mm"});
    s.add("up_axis", &P::up_axis, Range::any(), "",
          "the room's vertical axis (VICON and QTM: z; Motive by default: y)")
        .one_of({"z", "y"});
    s.add("yaw_deg", &P::yaw_deg, Range::closed(-360, 360), "deg",
          "world yaw of the levelled room axes: rotation about world z from them to world");
    s.add("p_W_R_m", &P::p_W_R_m, Range::closed(-1000, 1000), "m", "room origin in world");
    return s;
  }();
  return schema;
}

const ParamSchema<BodyParams>& BodyParams::schema() {
  using P = BodyParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("rpy_M_B_deg", &P::rpy_M_B_deg, Range::closed(-360, 360), "deg",
          "vehicle body axes (x forward, y left, z up) in the tracked object's frame M, as roll, "
          "pitch, yaw (Z-Y-X); [-90, 0, 0] for an object defined level in a y-up room");
    s.add("t_M_B_m", &P::t_M_B_m, Range::closed(-10, 10), "m",
          "vehicle body origin in the tracked object's frame M");
    return s;
  }();
  return schema;
}

const ParamSchema<StampParams>& StampParams::schema() {
  using P = StampParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("source", &P::source, Range::any(), "",
          "server: the server's stamps as they are (synchronised clocks); mapped: the server's "
          "stamps moved onto our clock by the smallest delay seen; receive: our receipt time")
        .one_of({"server", "mapped", "receive"});
    s.add("latency_s", &P::latency_s, Range::closed(0, 1), "s",
          "known delay from a sample to what its stamp stands for (the room's processing), "
          "subtracted from every stamp");
    s.add("offset_window_s", &P::offset_window_s, Range::closed(0.1, 600), "s",
          "mapped: the smallest receipt delay is taken over this long (clock drift)");
    s.add("max_clock_offset_s", &P::max_clock_offset_s, Range::open_closed(0, 60), "s",
          "server: a stamp further than this from our clock is refused");
    return s;
  }();
  return schema;
}

const ParamSchema<VelocityParams>& VelocityParams::schema() {
  using P = VelocityParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("source", &P::source, Range::any(), "",
          "finite_difference: from successive poses; server: the server's Velocity messages "
          "(linear part)")
        .one_of({"finite_difference", "server"});
    s.add("span_s", &P::span_s, Range::closed(0, 0.1), "s",
          "difference over at least this much time (less noise at high rates)");
    s.add("max_gap_s", &P::max_gap_s, Range::open_closed(0, 1), "s",
          "no difference across a larger gap: the pose after it is held back")
        .check([](const P& p) { return p.max_gap_s > p.span_s; }, "must exceed span_s");
    return s;
  }();
  return schema;
}

const ParamSchema<MocapParams>& MocapParams::schema() {
  using P = MocapParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.section("server", &P::server, ServerParams::schema(), "the VRPN server and object");
    s.section("room", &P::room, RoomParams::schema(), "the room's frame to world (z up, metres)");
    s.section("body", &P::body, BodyParams::schema(), "the vehicle's body in the tracked object");
    s.section("stamp", &P::stamp, StampParams::schema(), "pose_t.utime from the server's stamps");
    s.section("velocity", &P::velocity, VelocityParams::schema(), "pose_t.vel");
    s.add("channel", &P::channel, Range::any(), "", "pose_t output channel")
        .check([](const P& p) { return !p.channel.empty(); }, "must not be empty");
    return s;
  }();
  return schema;
}

void MocapParams::validate() const { schema().validate(*this); }

MocapParams load_params(const ParamNode& root) {
  MocapParams p;
  MocapParams::schema().read(root.child("mocap"), p);
  root.finish();
  return p;
}

MocapParams load_params(const std::string& file) { return load_params(ParamNode::load_file(file)); }

}  // namespace alight::mocap

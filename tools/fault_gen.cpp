#include "tools/fault_gen.hpp"

#include <algorithm>
#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/target_t.hpp>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include "common/channels.hpp"
#include "common/decode.hpp"

namespace alight::tools::faults {

namespace {

// Visits every double field of a message as (pointer to its first element, element count).
using DoubleVisitor = std::function<void(double*, int)>;

void visit_doubles(pose_t& m, const DoubleVisitor& f) {
  f(m.pos, 3);
  f(m.vel, 3);
  f(m.orientation, 4);
  f(m.angular_velocity_B, 3);
}
void visit_doubles(imu_t& m, const DoubleVisitor& f) {
  f(m.accel_B, 3);
  f(m.gyro_B, 3);
}
void visit_doubles(position_setpoint_t& m, const DoubleVisitor& f) {
  f(m.p_W, 3);
  f(m.v_W, 3);
  f(&m.yaw_rad, 1);
}
void visit_doubles(attitude_cmd_t& m, const DoubleVisitor& f) {
  f(&m.roll_rad, 1);
  f(&m.pitch_rad, 1);
  f(&m.yaw_rate_radps, 1);
  f(&m.thrust_N, 1);
}
void visit_doubles(target_t& m, const DoubleVisitor& f) {
  f(m.p_W_target, 3);
  f(m.n_W, 3);
  f(m.pixel, 2);
  f(&m.target_height_m, 1);
  f(m.size_m, 2);
  f(&m.target_yaw_rad, 1);
  f(&m.baseline_m, 1);
}
void visit_doubles(autonomy_status_t& m, const DoubleVisitor& f) {
  f(m.estimate_W, 3);
  f(m.covariance, 9);
  f(m.setpoint_W, 3);
  f(&m.mission_time_s, 1);
}
void visit_doubles(operator_cmd_t& m, const DoubleVisitor& f) { f(m.nudge_W, 3); }
void visit_doubles(process_status_t& m, const DoubleVisitor& f) {
  for (auto& p : m.processes) f(&p.backoff_s, 1);
}
void visit_doubles(node_status_t& m, const DoubleVisitor& f) { f(&m.uptime_s, 1); }
void visit_doubles(sim_truth_t& m, const DoubleVisitor& f) {
  f(m.pos, 3);
  f(m.vel, 3);
  f(m.orientation, 4);
}
void visit_doubles(image_t&, const DoubleVisitor&) {}

template <class Msg>
Bytes encode(const Msg& m) {
  Bytes out(static_cast<size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

// Plausible messages: what each sender would publish at rest, hovering 1 m above the origin.
template <class Msg>
Msg make_default(int64_t now_utime);

template <>
pose_t make_default<pose_t>(int64_t t) {
  pose_t m{};
  m.utime = t;
  m.pos[2] = 1.0;
  m.orientation[0] = 1.0;
  return m;
}
template <>
imu_t make_default<imu_t>(int64_t t) {
  imu_t m{};
  m.utime = t;
  m.accel_B[2] = 9.81;
  return m;
}
template <>
position_setpoint_t make_default<position_setpoint_t>(int64_t t) {
  position_setpoint_t m{};
  m.utime = t;
  m.p_W[2] = 1.0;
  m.motors = position_setpoint_t::MOTORS_ON;
  return m;
}
template <>
attitude_cmd_t make_default<attitude_cmd_t>(int64_t t) {
  attitude_cmd_t m{};
  m.utime = t;
  m.thrust_N = 10.0;
  m.armed = true;
  return m;
}
template <>
target_t make_default<target_t>(int64_t t) {
  target_t m{};
  m.utime = t;
  m.ref_utime = t - 500000;
  m.mission = target_t::MISSION_LANDING;
  m.found = true;
  m.n_W[2] = 1.0;
  m.size_m[0] = 0.6;
  m.size_m[1] = 0.4;
  m.target_height_m = 0.3;
  m.baseline_m = 0.2;
  return m;
}
template <>
autonomy_status_t make_default<autonomy_status_t>(int64_t t) {
  autonomy_status_t m{};
  m.utime = t;
  m.mission = target_t::MISSION_LANDING;
  m.phase = autonomy_status_t::PHASE_HOVER;
  m.phase_name = "HOVER";
  m.reason = "fault campaign";
  return m;
}
template <>
operator_cmd_t make_default<operator_cmd_t>(int64_t t) {
  operator_cmd_t m{};
  m.utime = t;
  m.seq = 1;
  m.sender = "alight-inject";
  m.command = operator_cmd_t::CMD_NONE;
  return m;
}
template <>
process_status_t make_default<process_status_t>(int64_t t) {
  process_status_t m{};
  m.utime = t;
  m.launch_name = "faults";
  m.session_dir = "/tmp";
  process_info_t p{};
  p.name = "autonomy";
  p.pid = 1;
  p.state = process_info_t::STATE_RUNNING;
  p.started_utime = t;
  m.processes = {p};
  m.n = 1;
  return m;
}
template <>
node_status_t make_default<node_status_t>(int64_t t) {
  node_status_t m{};
  m.utime = t;
  m.node = "alight-inject";
  m.pid = 1;
  channel_stats_t c{};
  c.channel = channels::kMocapPose;
  m.channels = {c};
  m.n = 1;
  return m;
}
template <>
sim_truth_t make_default<sim_truth_t>(int64_t t) {
  sim_truth_t m{};
  m.utime = t;
  m.scenario = "faults";
  m.orientation[0] = 1.0;
  m.wall_normal_W[0] = 1.0;
  return m;
}
template <>
image_t make_default<image_t>(int64_t t) {
  image_t m{};
  m.utime = t;
  m.width = 8;
  m.height = 4;
  m.row_stride = 8;
  m.pixelformat = image_t::PIXEL_FORMAT_GRAY;
  m.data.assign(32, 0);
  m.size = 32;
  image_metadata_t seq{};
  seq.key = "seq";
  seq.value.assign(8, 0);
  seq.n = 8;
  m.metadata = {seq};
  m.nmetadata = 1;
  return m;
}

template <class Msg>
std::optional<Msg> decode_or_default(const Bytes& base, int64_t now_utime) {
  Msg m;
  if (!base.empty() && decode_message(m, base.data(), base.size())) return m;
  if (!base.empty()) return std::nullopt;
  return make_default<Msg>(now_utime);
}

// One message per double field with all its elements set to `value`, then one with every field.
template <class Msg>
std::vector<Bytes> nonfinite(const Msg& base, double value) {
  std::vector<Bytes> out;
  Msg probe = base;
  int fields = 0;
  visit_doubles(probe, [&](double*, int) { ++fields; });
  for (int i = 0; i < fields; ++i) {
    Msg m = base;
    int k = 0;
    visit_doubles(m, [&](double* p, int n) {
      if (k++ == i) std::fill(p, p + n, value);
    });
    out.push_back(encode(m));
  }
  if (fields > 1) {
    Msg m = base;
    visit_doubles(m, [&](double* p, int n) { std::fill(p, p + n, value); });
    out.push_back(encode(m));
  }
  return out;
}

// Offset just past an encoded LCM string whose length field is at `at`.
size_t after_string(const std::string& s, size_t at) { return at + 4 + s.size() + 1; }

std::vector<size_t> lengths(const autonomy_status_t& m) {
  const size_t phase_name = 8 + 8 + 1 + 1;
  return {phase_name, after_string(m.phase_name, phase_name)};
}
std::vector<size_t> lengths(const operator_cmd_t&) { return {8 + 8 + 8}; }
std::vector<size_t> lengths(const sim_truth_t&) { return {8 + 8}; }
std::vector<size_t> lengths(const image_t& m) {
  const size_t size = 8 + 8 + 4 * 4;
  const size_t nmetadata = size + 4 + m.data.size();
  std::vector<size_t> out{size, nmetadata};
  size_t at = nmetadata + 4;
  for (const auto& md : m.metadata) {
    const size_t n = after_string(md.key, at);
    out.push_back(at);
    out.push_back(n);
    at = n + 4 + md.value.size();
  }
  return out;
}
std::vector<size_t> lengths(const process_status_t& m) {
  const size_t launch_name = 8 + 8;
  const size_t session_dir = after_string(m.launch_name, launch_name);
  const size_t n = after_string(m.session_dir, session_dir);
  std::vector<size_t> out{launch_name, session_dir, n};
  size_t at = n + 4;
  for (const auto& p : m.processes) {  // name, then pid .. backoff_s: 4+1+4+4+4+8+8 bytes
    out.push_back(at);
    at = after_string(p.name, at) + 33;
  }
  return out;
}
std::vector<size_t> lengths(const node_status_t& m) {
  const size_t node = 8 + 8;
  // pid, uptime_s, source, signed_bus, clock_from_inputs, wall_clock_steps
  const size_t n = after_string(m.node, node) + 4 + 8 + 8 + 1 + 1 + 4;
  std::vector<size_t> out{node, n};
  size_t at = n + 4;
  for (const auto& c : m.channels) {  // channel, then 9 int64 counters
    out.push_back(at);
    at = after_string(c.channel, at) + 9 * 8;
  }
  return out;
}
template <class Msg>
std::vector<size_t> lengths(const Msg&) {
  return {};
}

void put_int32(Bytes& b, size_t at, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(u >> (24 - 8 * i));
}
void put_int64(Bytes& b, size_t at, int64_t v) {
  const auto u = static_cast<uint64_t>(v);
  for (int i = 0; i < 8; ++i) b[at + i] = static_cast<uint8_t>(u >> (56 - 8 * i));
}

std::vector<Bytes> truncations(const Bytes& good) {
  std::set<size_t> cuts{0, 4, 8, 9, 16, good.size() / 3, good.size() / 2, good.size() - 1};
  std::vector<Bytes> out;
  for (size_t c : cuts)
    if (c < good.size()) out.emplace_back(good.begin(), good.begin() + static_cast<long>(c));
  return out;
}

std::vector<Bytes> bad_lengths(const Bytes& good, const std::vector<size_t>& offsets,
                               std::mt19937_64& rng) {
  std::vector<Bytes> out;
  for (size_t at : offsets) {
    const auto past_end =
        static_cast<int32_t>(std::min<size_t>(good.size() - at - 4 + 1, INT32_MAX));
    for (int32_t v : {0, -1, std::numeric_limits<int32_t>::min(),
                      std::numeric_limits<int32_t>::max(), 0x55555556, past_end}) {
      Bytes b = good;
      put_int32(b, at, v);
      out.push_back(std::move(b));
    }
  }
  if (offsets.empty()) {  // a fixed-size type: well-formed, then bytes that belong to nothing
    for (size_t extra : {1, 8, 100}) {
      Bytes b = good;
      const Bytes tail = garbage(rng, extra);
      b.insert(b.end(), tail.begin(), tail.end());
      out.push_back(std::move(b));
    }
  }
  return out;
}

struct TypeOps {
  std::function<std::optional<Bytes>(const Bytes&, int64_t)> base;  // decoded-or-default, encoded
  std::function<std::vector<Bytes>(const Bytes&, double)> nonfinite;
  std::function<std::vector<size_t>(const Bytes&)> lengths;
};

template <class Msg>
TypeOps ops() {
  TypeOps o;
  o.base = [](const Bytes& base, int64_t now) -> std::optional<Bytes> {
    auto m = decode_or_default<Msg>(base, now);
    if (!m) return std::nullopt;
    return encode(*m);
  };
  o.nonfinite = [](const Bytes& good, double v) {
    Msg m;
    if (!decode_message(m, good.data(), good.size())) return std::vector<Bytes>{};
    return nonfinite(m, v);
  };
  o.lengths = [](const Bytes& good) {
    Msg m;
    if (good.empty() || !decode_message(m, good.data(), good.size())) return std::vector<size_t>{};
    return lengths(m);
  };
  return o;
}

const std::map<std::string, TypeOps>& registry() {
  static const std::map<std::string, TypeOps> r{
      {"pose_t", ops<pose_t>()},
      {"imu_t", ops<imu_t>()},
      {"position_setpoint_t", ops<position_setpoint_t>()},
      {"attitude_cmd_t", ops<attitude_cmd_t>()},
      {"target_t", ops<target_t>()},
      {"autonomy_status_t", ops<autonomy_status_t>()},
      {"operator_cmd_t", ops<operator_cmd_t>()},
      {"process_status_t", ops<process_status_t>()},
      {"node_status_t", ops<node_status_t>()},
      {"sim_truth_t", ops<sim_truth_t>()},
      {"image_t", ops<image_t>()},
  };
  return r;
}

const std::map<std::string, std::string>& channel_types() {
  static const std::map<std::string, std::string> c{
      {channels::kMocapPose, "pose_t"},
      {channels::kImu, "imu_t"},
      {channels::kCamera, "image_t"},
      {channels::kVisionDiag, "image_t"},
      {channels::kVisionTarget, "target_t"},
      {channels::kPositionSetpoint, "position_setpoint_t"},
      {channels::kAttitudeCmd, "attitude_cmd_t"},
      {channels::kAutonomyStatus, "autonomy_status_t"},
      {channels::kOperatorCmd, "operator_cmd_t"},
      {channels::kProcessStatus, "process_status_t"},
      {channels::kNodeStatus, "node_status_t"},
      {channels::kSimTruth, "sim_truth_t"},
  };
  return c;
}

}  // namespace

std::optional<Kind> parse_kind(const std::string& name) {
  for (Kind k : all_kinds())
    if (to_string(k) == name) return k;
  return std::nullopt;
}

std::string to_string(Kind kind) {
  switch (kind) {
    case Kind::kGarbage:
      return "garbage";
    case Kind::kTruncated:
      return "truncated";
    case Kind::kBadLengths:
      return "bad_lengths";
    case Kind::kNaN:
      return "nan";
    case Kind::kInf:
      return "inf";
    case Kind::kFuture:
      return "future";
    case Kind::kZeroStamp:
      return "zero_stamp";
  }
  return "?";
}

std::vector<Kind> all_kinds() {
  return {Kind::kGarbage, Kind::kTruncated, Kind::kBadLengths, Kind::kNaN,
          Kind::kInf,     Kind::kFuture,    Kind::kZeroStamp};
}

std::optional<std::string> type_of_channel(const std::string& channel) {
  const auto it = channel_types().find(channel);
  if (it == channel_types().end()) return std::nullopt;
  return it->second;
}

std::vector<std::string> injectable_channels() {
  std::vector<std::string> out;
  for (const auto& [ch, type] : channel_types())
    if (ch != channels::kSimTruth) out.push_back(ch);
  return out;
}

Bytes garbage(std::mt19937_64& rng, size_t size) {
  Bytes out(size);
  std::uniform_int_distribution<int> byte(0, 255);
  for (auto& b : out) b = static_cast<uint8_t>(byte(rng));
  return out;
}

Bytes default_message(const std::string& type_name, int64_t now_utime) {
  const auto it = registry().find(type_name);
  if (it == registry().end()) return {};
  return it->second.base({}, now_utime).value_or(Bytes{});
}

std::vector<size_t> length_field_offsets(const std::string& type_name, const Bytes& msg) {
  const auto it = registry().find(type_name);
  if (it == registry().end()) return {};
  return it->second.lengths(msg);
}

std::optional<int64_t> utime_of(const Bytes& msg) {
  if (msg.size() < 16) return std::nullopt;
  uint64_t u = 0;
  for (size_t i = 8; i < 16; ++i) u = (u << 8) | msg[i];
  return static_cast<int64_t>(u);
}

std::vector<Bytes> generate(Kind kind, const std::string& type_name, const Bytes& base,
                            int64_t now_utime, std::mt19937_64& rng) {
  const auto it = registry().find(type_name);
  if (it == registry().end()) return {};
  const TypeOps& o = it->second;
  // A base that does not decode (the channel carried something odd) is replaced by a default.
  const Bytes good = o.base(base, now_utime).value_or(o.base({}, now_utime).value_or(Bytes{}));
  std::vector<Bytes> out;
  switch (kind) {
    case Kind::kGarbage: {
      for (size_t n : {1, 7, 8, 28, 64, 1024, 65000}) out.push_back(garbage(rng, n));
      for (size_t n : {size_t{20}, good.size() - 8}) {  // the right fingerprint, then noise
        Bytes b(good.begin(), good.begin() + 8);
        const Bytes tail = garbage(rng, n);
        b.insert(b.end(), tail.begin(), tail.end());
        out.push_back(std::move(b));
      }
      break;
    }
    case Kind::kTruncated:
      out = truncations(good);
      break;
    case Kind::kBadLengths:
      out = bad_lengths(good, o.lengths(good), rng);
      break;
    case Kind::kNaN:
      out = o.nonfinite(good, std::numeric_limits<double>::quiet_NaN());
      break;
    case Kind::kInf: {
      out = o.nonfinite(good, std::numeric_limits<double>::infinity());
      auto neg = o.nonfinite(good, -std::numeric_limits<double>::infinity());
      out.insert(out.end(), neg.begin(), neg.end());
      break;
    }
    case Kind::kFuture: {
      Bytes b = good;
      put_int64(b, 8, utime_of(good).value_or(now_utime) + int64_t{3600} * 1000000);
      out.push_back(std::move(b));
      break;
    }
    case Kind::kZeroStamp: {
      Bytes b = good;
      put_int64(b, 8, 0);
      out.push_back(std::move(b));
      position_setpoint_t sp;  // a stamp-0 motors-off setpoint disarmed in the air
      if (type_name == "position_setpoint_t" && decode_message(sp, good.data(), good.size())) {
        sp.utime = 0;
        sp.motors = position_setpoint_t::MOTORS_OFF;
        out.push_back(encode(sp));
      }
      break;
    }
  }
  return out;
}

}  // namespace alight::tools::faults

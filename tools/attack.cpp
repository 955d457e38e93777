#include "tools/attack.hpp"

#include <algorithm>
#include <cmath>

#include "common/bus_auth.hpp"
#include "common/channels.hpp"

namespace alight::tools::attack {

namespace {

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

pose_t made_up_pose(int64_t now) {
  pose_t p{};
  p.utime = now;
  p.pos[2] = 1.6;
  p.orientation[0] = 1.0;
  return p;
}

pose_t heard_pose(const Overheard& h, int64_t now) { return h.pose ? *h.pose : made_up_pose(now); }

position_setpoint_t heard_setpoint(const Overheard& h, int64_t now) {
  if (h.setpoint) return *h.setpoint;
  position_setpoint_t s{};
  const pose_t p = heard_pose(h, now);
  for (int i = 0; i < 3; ++i) s.p_W[i] = p.pos[i];
  s.motors = position_setpoint_t::MOTORS_ON;
  return s;
}

target_t heard_target(const Overheard& h, int64_t now) {
  if (h.target && h.target->found) return *h.target;
  target_t t{};
  t.utime = now;
  t.mission = target_t::MISSION_LANDING;
  t.found = true;
  t.reason = target_t::REASON_OK;
  t.p_W_target[0] = 0.8;
  t.p_W_target[1] = 0.4;
  t.p_W_target[2] = 0.2;
  t.n_W[2] = 1.0;
  t.target_height_m = 0.2;
  t.size_m[0] = 0.43;
  t.size_m[1] = 0.28;
  t.baseline_m = 0.1;
  t.n_features = t.n_matches = 200;
  t.n_inliers_dominant = t.n_inliers_target = 80;
  return t;
}

std::vector<uint8_t> raw_of(const Overheard& h, const std::string& channel) {
  for (const auto& [c, b] : h.raw)
    if (c == channel) return b;
  return {};
}

Datagram shifted_pose(const Overheard& h, int64_t now, double dx) {
  pose_t p = heard_pose(h, now);
  p.utime = (h.pose ? h.pose->utime : now) + 50'000;
  p.pos[0] += dx;
  return {channels::kMocapPose, encode(p)};
}

}  // namespace

const char* name(Kind k) {
  switch (k) {
    case Kind::kKillSetpoint:
      return "kill_setpoint";
    case Kind::kSetpointStream:
      return "setpoint_stream";
    case Kind::kAttitudeDisarm:
      return "attitude_disarm";
    case Kind::kKillCommand:
      return "kill_command";
    case Kind::kPoseOffset:
      return "pose_offset";
    case Kind::kPoseGrowing:
      return "pose_growing";
    case Kind::kPoseAhead:
      return "pose_ahead";
    case Kind::kPoseSpoofed:
      return "pose_spoofed";
    case Kind::kVisionTarget:
      return "vision_target";
    case Kind::kFlood:
      return "flood";
    case Kind::kSecondPublisher:
      return "second_publisher";
  }
  return "?";
}

std::vector<Kind> all() {
  return {Kind::kKillSetpoint, Kind::kSetpointStream, Kind::kAttitudeDisarm, Kind::kKillCommand,
          Kind::kPoseOffset,   Kind::kPoseGrowing,    Kind::kPoseAhead,      Kind::kPoseSpoofed,
          Kind::kVisionTarget, Kind::kFlood,          Kind::kSecondPublisher};
}

std::optional<Kind> parse(const std::string& n) {
  for (Kind k : all())
    if (n == name(k)) return k;
  return std::nullopt;
}

double period_s(Kind k) {
  switch (k) {
    case Kind::kSetpointStream:
      return 0.02;
    case Kind::kAttitudeDisarm:
      return 0.1;
    case Kind::kPoseOffset:
    case Kind::kPoseGrowing:
    case Kind::kPoseSpoofed:
    case Kind::kSecondPublisher:
      return 0.01;
    case Kind::kVisionTarget:
      return 1.0 / 30.0;
    case Kind::kFlood:
      return 0.0;
    default:
      return 1.0;
  }
}

double duration_s(Kind k) {
  switch (k) {
    case Kind::kKillSetpoint:
    case Kind::kPoseAhead:
    case Kind::kKillCommand:
      return 0.0;  // one round
    case Kind::kSetpointStream:
      return 8.0;
    case Kind::kAttitudeDisarm:
      return 1.0;
    case Kind::kFlood:
      return 5.0;
    case Kind::kSecondPublisher:
      return 10.0;
    default:
      return 15.0;
  }
}

std::vector<Datagram> round(Kind k, double t_s, int64_t now, const Overheard& h,
                            std::mt19937_64& rng) {
  std::vector<Datagram> out;
  switch (k) {
    case Kind::kKillSetpoint: {
      position_setpoint_t s = heard_setpoint(h, now);
      s.utime = now + 450'000;
      s.motors = position_setpoint_t::MOTORS_KILL;
      out.push_back({channels::kPositionSetpoint, encode(s)});
      break;
    }
    case Kind::kSetpointStream: {
      position_setpoint_t s = heard_setpoint(h, now);
      s.utime = now;
      s.p_W[0] += 20.0;
      s.motors = position_setpoint_t::MOTORS_ON;
      out.push_back({channels::kPositionSetpoint, encode(s)});
      break;
    }
    case Kind::kAttitudeDisarm: {
      attitude_cmd_t c = h.attitude.value_or(attitude_cmd_t{});
      c.utime = h.attitude ? h.attitude->utime + 10'000 : now;
      c.armed = false;
      c.thrust_N = 0.0;
      c.mode = attitude_cmd_t::MODE_DISARMED;
      out.push_back({channels::kAttitudeCmd, encode(c)});
      break;
    }
    case Kind::kKillCommand: {
      operator_cmd_t c{};
      c.utime = now;
      c.seq = now;
      c.sender = "intruder";
      c.vehicle_id = "alight";
      c.command = operator_cmd_t::CMD_KILL;
      c.auth = operator_cmd_t::AUTH_NONE;
      out.push_back({channels::kOperatorCmd, encode(c)});
      c.seq += 1;
      c.auth = operator_cmd_t::AUTH_HMAC_SHA256;
      for (auto& b : c.hmac) b = static_cast<uint8_t>(rng());
      out.push_back({channels::kOperatorCmd, encode(c)});
      break;
    }
    case Kind::kPoseOffset:
      out.push_back(shifted_pose(h, now, 0.3));
      break;
    case Kind::kPoseGrowing:
      out.push_back(shifted_pose(h, now, 0.5 * t_s));
      break;
    case Kind::kPoseAhead: {
      pose_t p = heard_pose(h, now);
      p.utime = (h.pose ? h.pose->utime : now) + 450'000;
      out.push_back({channels::kMocapPose, encode(p)});
      break;
    }
    case Kind::kPoseSpoofed: {
      Datagram d = shifted_pose(h, now, 0.3);
      const auto live = raw_of(h, channels::kMocapPose);
      const auto r = bus::split(live.data(), live.size());
      if (r.trailer) {
        // The live publisher's id and a counter just above its last: unsigned (no key).
        bus::Sealer as_owner(r.trailer->source, std::nullopt);
        as_owner.seal(d.payload, d.channel, static_cast<int64_t>(r.trailer->counter) + 1);
      }
      out.push_back(std::move(d));
      break;
    }
    case Kind::kVisionTarget: {
      target_t t = heard_target(h, now);
      t.utime = h.target ? h.target->utime + 1000 : now;
      t.found = true;
      t.reason = target_t::REASON_OK;
      t.p_W_target[0] += 0.25;
      out.push_back({channels::kVisionTarget, encode(t)});
      break;
    }
    case Kind::kFlood: {
      // A burst per round: copies of what was overheard (without its publisher's trailer), and
      // garbage of plausible sizes.
      for (const char* ch : {channels::kMocapPose, channels::kPositionSetpoint,
                             channels::kAttitudeCmd, channels::kImu, channels::kVisionTarget}) {
        const auto raw = raw_of(h, ch);
        const auto r = bus::split(raw.data(), raw.size());
        std::vector<uint8_t> copy(r.payload.begin(), r.payload.end());
        if (copy.empty()) copy.resize(64 + rng() % 256);
        for (size_t i = 8; i < copy.size(); i += 1 + rng() % 16)
          copy[i] = static_cast<uint8_t>(rng());
        out.push_back({ch, copy});
      }
      break;
    }
    case Kind::kSecondPublisher:
      for (const auto& [ch, bytes] : h.raw) {
        // The overheard message without its publisher's trailer: the same content from another
        // publisher.
        const auto r = bus::split(bytes.data(), bytes.size());
        out.push_back({ch, std::vector<uint8_t>(r.payload.begin(), r.payload.end())});
      }
      if (h.raw.empty()) out.push_back({channels::kMocapPose, encode(made_up_pose(now))});
      break;
  }
  return out;
}

std::vector<uint8_t> lcm_datagram(const std::string& channel, const std::vector<uint8_t>& payload,
                                  uint32_t seq) {
  std::vector<uint8_t> d = {0x4c, 0x43, 0x30, 0x32};  // "LC02"
  for (int i = 3; i >= 0; --i) d.push_back(static_cast<uint8_t>(seq >> (8 * i)));
  d.insert(d.end(), channel.begin(), channel.end());
  d.push_back(0);
  d.insert(d.end(), payload.begin(), payload.end());
  return d;
}

}  // namespace alight::tools::attack

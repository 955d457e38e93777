// The autopilot bridge's input side: alight-mavlink's Bridge fed arbitrary bytes from
// "the autopilot" in arbitrary chunks, with the stack's setpoints (armed) and motion capture
// interleaved and the clocks advancing by amounts the input chooses. Input: a flags byte (bit 0:
// ArduPilot, bit 1: position control, bit 2: engage operator, bit 3: ODOMETRY), a chunking seed
// byte, then the byte stream (the mavlink_parser seeds fit). Properties: nothing throws or
// crashes; every byte the bridge writes parses back as whole, correct frames from alight's own
// system and component; setpoints sent are finite, attitude quaternions unit and thrust in
// [0, 1]; IMU samples published are finite and stamped increasingly.
#include <cmath>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_support.hpp"
#include "mavlink/bridge.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  using namespace alight::mavlink;
  if (size < 2) return 0;
  const uint8_t flags = data[0];
  uint32_t state = data[1] * 2654435761u + 1;
  data += 2;
  size -= 2;

  BridgeParams params;
  params.autopilot = (flags & 1) ? "ardupilot" : "px4";
  params.control = (flags & 2) ? "position" : "attitude";
  params.engage = (flags & 4) ? "operator" : "auto";
  params.mocap_message = (flags & 8) ? "odometry" : "att_pos_mocap";
  params.offboard_warmup_s = 0.05;
  Bridge bridge(params, 15.0);
  Parser out_parser;
  BridgeClock clock{1'000'000, 1'767'323'045'000'000};
  int64_t last_imu = 0;

  size_t pos = 0;
  while (pos < size) {
    state = state * 1103515245u + 12345u;
    const size_t n = std::min<size_t>(size - pos, 1 + (state >> 16) % 64);
    BridgeInput in;
    in.link_bytes = std::span<const uint8_t>(data + pos, n);
    pos += n;
    const int64_t dt = static_cast<int64_t>((state >> 8) % 20'000);
    clock.steady_us += dt;
    clock.wall_us += dt;
    if (state & 1) {
      AttitudeTarget a;
      a.utime = clock.wall_us;
      a.thrust_N = 16;
      a.armed = true;
      in.attitude = a;
      PositionTarget p;
      p.utime = clock.wall_us;
      p.p_W = Vector3d(0, 0, 1);
      p.motors = (state & 0x700) == 0x700 ? Motors::kKill : Motors::kOn;
      in.position = p;
    }
    if (state & 2) {
      PoseSample pose;
      pose.utime = clock.wall_us;
      in.mocap = pose;
    }
    const BridgeOutput out = bridge.update(in, clock);

    out_parser.push(out.link_bytes);
    Frame f;
    while (out_parser.next(f)) {
      if (f.sysid != params.own_sysid || f.compid != params.own_compid)
        fuzz::fail("a frame not from alight's own system and component");
      if (auto m = decode<SetAttitudeTarget>(f)) {
        if (!(m->thrust >= 0 && m->thrust <= 1)) fuzz::fail("thrust outside [0, 1]");
        const double norm = std::sqrt(m->q[0] * m->q[0] + m->q[1] * m->q[1] + m->q[2] * m->q[2] +
                                      m->q[3] * m->q[3]);
        if (!(std::abs(norm - 1) < 1e-3)) fuzz::fail("attitude setpoint not a unit quaternion");
      }
      if (auto m = decode<SetPositionTargetLocalNed>(f)) {
        if (!std::isfinite(m->x) || !std::isfinite(m->y) || !std::isfinite(m->z) ||
            !std::isfinite(m->yaw))
          fuzz::fail("position setpoint not finite");
      }
    }
    if (out_parser.buffered() != 0 || out_parser.stats().crc_errors != 0 ||
        out_parser.stats().bytes_dropped != 0)
      fuzz::fail("the bridge wrote bytes that are not whole, correct frames");
    for (const ImuOut& s : out.imu) {
      if (!s.accel_B.allFinite() || !s.gyro_B.allFinite()) fuzz::fail("IMU not finite");
      if (s.utime <= last_imu) fuzz::fail("IMU stamps not increasing");
      last_imu = s.utime;
    }
  }
  return 0;
}

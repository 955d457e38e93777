// alight-mocap's input: the bytes of a VRPN server's TCP stream, through the TrackerClient the
// node runs (decoder, object selection, stamps, room frame, velocities). The first byte picks
// the configuration (stamp source, velocity source, units, up axis), the second seeds the chunk
// sizes the stream is cut into (TCP delivers any split); the rest is the stream.
// Properties: every pose returned is finite with a unit quaternion, stamps strictly increase,
// and the decoder never holds more than one message in waiting.
#include <cmath>

#include "fuzz/fuzz_support.hpp"
#include "mocap/tracker.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  using namespace alight::mocap;
  if (size < 2) return 0;
  const uint8_t config = data[0];
  uint32_t chunk_state = data[1] | 0x100u;
  data += 2;
  size -= 2;

  MocapParams p;
  p.server.tracker = "Pelican@127.0.0.1";
  p.stamp.source = (config & 3) == 0 ? "server" : (config & 3) == 1 ? "mapped" : "receive";
  p.stamp.max_clock_offset_s = 60;
  p.velocity.source = config & 4 ? "server" : "finite_difference";
  p.room.units = config & 8 ? "mm" : "m";
  p.room.up_axis = config & 16 ? "y" : "z";
  p.body.t_M_B_m = Eigen::Vector3d(0.1, -0.05, 0.02);
  p.validate();
  TrackerClient client(p);
  (void)client.greeting(1'700'000'000'000'000);

  // Receipt times near the stamps a fuzzed server might send, advancing 1 ms a read.
  int64_t recv_utime = 1'700'000'000'000'000;
  int64_t last = INT64_MIN;
  size_t at = 0;
  while (at < size) {
    chunk_state = chunk_state * 1103515245u + 12345u;
    const size_t n = std::min(size - at, size_t{1} + (chunk_state >> 16) % 256);
    for (const auto& pose : client.on_bytes(data + at, n, recv_utime)) {
      const auto& s = pose.pose;
      if (!s.p_W_B.allFinite() || !s.v_W_B.allFinite() || !s.omega_B.allFinite() ||
          !s.q_WB.coeffs().allFinite())
        fuzz::fail("a pose with a non-finite field");
      if (std::abs(s.q_WB.norm() - 1.0) > 1e-9) fuzz::fail("a pose whose quaternion is not unit");
      if (s.utime <= last) fuzz::fail("pose stamps not strictly increasing");
      last = s.utime;
    }
    if (client.decoder().pending_bytes() >
        vrpn::kHeaderBytes + vrpn::kMaxPayloadBytes + vrpn::kAlign + 256)
      fuzz::fail("decoder holds more than one message");
    at += n;
    recv_utime += 1000;
    if (client.failed()) {  // as the node: a new connection
      client.end_of_stream();
      client.reset();
    }
  }
  client.end_of_stream();
  (void)client.stats();
  return 0;
}
